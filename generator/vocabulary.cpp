#include "vocabulary.hpp"

namespace wlx::codegen {

Vec3 operator+(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 operator-(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 operator*(const ex& s, const Vec3& a) { return {s * a[0], s * a[1], s * a[2]}; }
ex dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

Mat3 Mat3::identity() {
  Mat3 m;
  m(0, 0) = m(1, 1) = m(2, 2) = 1;
  return m;
}

Mat3 operator*(const Mat3& a, const Mat3& b) {
  Mat3 m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = a(r, 0) * b(0, c) + a(r, 1) * b(1, c) + a(r, 2) * b(2, c);
  return m;
}

Vec3 operator*(const Mat3& a, const Vec3& v) {
  Vec3 out;
  for (int r = 0; r < 3; ++r) out[r] = a(r, 0) * v[0] + a(r, 1) * v[1] + a(r, 2) * v[2];
  return out;
}

Vec3 unit(Axis axis) {
  Vec3 u;
  u[static_cast<int>(axis)] = 1;
  return u;
}

Mat3 rot(Axis axis, const ex& angle) {
  const ex c = GiNaC::cos(angle), s = GiNaC::sin(angle);
  Mat3 m = Mat3::identity();
  switch (axis) {
    case Axis::X: m(1, 1) = c; m(1, 2) = -s; m(2, 1) = s; m(2, 2) = c; break;
    case Axis::Y: m(0, 0) = c; m(0, 2) = s; m(2, 0) = -s; m(2, 2) = c; break;
    case Axis::Z: m(0, 0) = c; m(0, 1) = -s; m(1, 0) = s; m(1, 1) = c; break;
  }
  return m;
}

Mat3 signed_rot(Axis axis, int sign, const ex& q) {
  const ex c = GiNaC::cos(q), sn = sign * GiNaC::sin(q);
  Mat3 r = Mat3::identity();
  const int i = (static_cast<int>(axis) + 1) % 3, j = (static_cast<int>(axis) + 2) % 3;  // R turns i towards j
  r(i, i) = c;
  r(i, j) = -sn;
  r(j, i) = sn;
  r(j, j) = c;
  return r;
}

Frame Frame::translated(const Vec3& local_offset) const {
  Frame f = *this;
  const Vec3 rho = R * local_offset;
  f.r = r + rho;
  f.local_r = local_r + local_R * local_offset;
  f.v = v + cross(omega, rho);
  f.a_bias = a_bias + cross(alpha_bias, rho) + cross(omega, cross(omega, rho));
  return f;
}

Frame Frame::rotated(Axis axis, const Coordinate& c, int sign) const {
  Frame f = *this;
  const Vec3 a = ex(sign) * R.col(static_cast<int>(axis));  // the joint axis does not move with its own joint
  f.R = R * signed_rot(axis, sign, c.q);
  f.omega = omega + ex(c.qdot) * a;
  f.alpha_bias = alpha_bias + ex(c.qdot) * cross(omega, a);  // the axis turns with the frame before
  f.joints.push_back({c.index, true, a, r, local_R * signed_rot(axis, sign, c.q), local_r, axis, sign});
  f.local_R = Mat3::identity();
  f.local_r = Vec3();
  return f;
}

Frame Frame::slid(Axis axis, const Coordinate& c, int sign) const {
  Frame f = *this;
  const Vec3 a = ex(sign) * R.col(static_cast<int>(axis));
  const Vec3 d = ex(c.q) * a;
  f.r = r + d;
  f.v = v + cross(omega, d) + ex(c.qdot) * a;
  f.a_bias = a_bias + cross(alpha_bias, d) + cross(omega, cross(omega, d)) +
             ex(2 * c.qdot) * cross(omega, a);
  f.joints.push_back({c.index, false, a, r, local_R, local_r + local_R * (ex(sign * c.q) * unit(axis)), axis, sign});
  f.local_R = Mat3::identity();
  f.local_r = Vec3();
  return f;
}

Frame Frame::turned(Axis axis, const ex& angle) const {
  Frame f = *this;
  f.R = R * rot(axis, angle);
  f.local_R = local_R * rot(axis, angle);
  return f;
}

namespace {

// A quantity along the motion: its value, its rate (linear in the coordinate rates) with that
// rate's coefficients, one per coordinate (the Jacobian columns), and its second derivative with
// every coordinate acceleration zero (the "bias", quadratic in the rates). Velocities, Jacobians
// and convective terms of a derived point then follow by the chain rule, without differentiating
// any expression.
struct Moving {
  ex value, rate, bias;
  std::vector<ex> columns;  // d(value)/d(coordinate k), so rate = sum_k columns[k] * rate of k
};
std::vector<ex> combine(const std::vector<ex>& a, const ex& fa, const std::vector<ex>& b, const ex& fb) {
  std::vector<ex> out(a.size(), 0);
  for (std::size_t k = 0; k < a.size(); ++k)
    if (!a[k].is_zero() || !b[k].is_zero()) out[k] = a[k] * fa + b[k] * fb;
  return out;
}
Moving operator+(const Moving& a, const Moving& b) {
  return {a.value + b.value, a.rate + b.rate, a.bias + b.bias, combine(a.columns, 1, b.columns, 1)};
}
Moving operator-(const Moving& a) { return {-a.value, -a.rate, -a.bias, combine(a.columns, -1, a.columns, 0)}; }
Moving operator*(const Moving& a, const Moving& b) {
  return {a.value * b.value, a.rate * b.value + a.value * b.rate, a.bias * b.value + 2 * a.rate * b.rate + a.value * b.bias,
          combine(a.columns, b.value, b.columns, a.value)};
}
Moving reciprocal(const Moving& a) {
  const ex inv = 1 / a.value;
  return {inv, -a.rate * inv * inv, (2 * a.rate * a.rate * inv - a.bias) * inv * inv, combine(a.columns, -inv * inv, a.columns, 0)};
}
Moving root(const Moving& a) {
  const ex r = GiNaC::sqrt(a.value);
  return {r, a.rate / (2 * r), a.bias / (2 * r) - a.rate * a.rate / (4 * r * a.value), combine(a.columns, 1 / (2 * r), a.columns, 0)};
}

}  // namespace

Frame wheel_contact_frame(const Frame& hub, Axis axle, const ex& radius, const ex& offset, const std::vector<Coordinate>& coordinates) {
  const std::size_t n = coordinates.size();
  // The axle a is fixed in the hub: a' = omega x a (column k: axis_k x a for a revolute joint k),
  // a''_bias = alpha_bias x a + omega x (omega x a).
  const Vec3 a = hub.R.col(static_cast<int>(axle));
  const Vec3 a_rate = cross(hub.omega, a);
  const Vec3 a_bias = cross(hub.alpha_bias, a) + cross(hub.omega, cross(hub.omega, a));
  const std::vector<Vec3> hub_columns = linear_jacobian(hub, static_cast<int>(n));
  std::array<Moving, 3> A;
  for (int i = 0; i < 3; ++i) {
    Moving& Ai = A[static_cast<std::size_t>(i)];
    Ai = {a[i], a_rate[i], a_bias[i], std::vector<ex>(n, 0)};
    for (const JointRecord& j : hub.joints)
      if (j.revolute) Ai.columns[static_cast<std::size_t>(j.coordinate)] = cross(j.axis, a)[i];
  }
  // sigma = |a x e_z| = sqrt(a_x^2 + a_y^2) (not sqrt(1 - a_z^2), which loses digits near an upright
  // wheel); n = (a_x, a_y, 0) / sigma is the lateral direction, t = (n_y, -n_x, 0) the forward one.
  const Moving sigma = root(A[0] * A[0] + A[1] * A[1]);
  const Moving inv = reciprocal(sigma);
  const Moving nx = A[0] * inv, ny = A[1] * inv;
  // c = h - r u with u = (-a_z n_x, -a_z n_y, sigma).
  const Moving r{radius, 0, 0, std::vector<ex>(n, 0)};
  // c = h + d a - r u: d moves the rolling plane along the axle (its terms vanish for d = 0).
  const Moving d{offset, 0, 0, std::vector<ex>(n, 0)};
  const std::array<Moving, 3> offset_of_contact = {d * A[0] + r * A[2] * nx, d * A[1] + r * A[2] * ny, d * A[2] + -(r * sigma)};
  Frame f;
  f.joints = hub.joints;  // the coordinates that move it
  f.linear_columns.assign(n, Vec3());
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    f.r[i] = hub.r[i] + offset_of_contact[k].value;
    f.v[i] = hub.v[i] + offset_of_contact[k].rate;
    f.a_bias[i] = hub.a_bias[i] + offset_of_contact[k].bias;
    for (std::size_t c = 0; c < n; ++c) f.linear_columns[c][i] = hub_columns[c][i] + offset_of_contact[k].columns[c];
  }
  f.R(0, 0) = ny.value, f.R(1, 0) = -nx.value, f.R(2, 0) = 0;  // forward t
  f.R(0, 1) = nx.value, f.R(1, 1) = ny.value, f.R(2, 1) = 0;   // lateral n
  f.R(0, 2) = 0, f.R(1, 2) = 0, f.R(2, 2) = 1;                  // up
  // The heading psi of t turns about e_z: psi' = t_x t_y' - t_y t_x' = n_x n_y' - n_y n_x', and its
  // bias acceleration n_x n_y'' - n_y n_x'' (the rates' products cancel).
  f.omega = Vec3(0, 0, nx.value * ny.rate - ny.value * nx.rate);
  f.alpha_bias = Vec3(0, 0, nx.value * ny.bias - ny.value * nx.bias);
  return f;
}

std::vector<Vec3> linear_jacobian(const Frame& f, int n) {
  if (!f.linear_columns.empty()) return f.linear_columns;
  std::vector<Vec3> cols(static_cast<std::size_t>(n));
  for (const auto& j : f.joints)
    cols[static_cast<std::size_t>(j.coordinate)] = j.revolute ? cross(j.axis, f.r - j.origin) : j.axis;
  return cols;
}

std::vector<Vec3> angular_jacobian(const Frame& f, int n) {
  std::vector<Vec3> cols(static_cast<std::size_t>(n));
  for (const auto& j : f.joints)
    if (j.revolute) cols[static_cast<std::size_t>(j.coordinate)] = j.axis;
  return cols;
}

std::vector<ex> attached_direction_gradient(const Frame& f, const Vec3& u, const Vec3& e, int n) {
  std::vector<ex> row(static_cast<std::size_t>(n), 0);
  for (const auto& j : f.joints)
    if (j.revolute) row[static_cast<std::size_t>(j.coordinate)] = dot(e, cross(j.axis, u));
  return row;
}

ex attached_direction_convective(const Frame& f, const Vec3& u, const Vec3& e) {
  return dot(e, cross(f.alpha_bias, u) + cross(f.omega, cross(f.omega, u)));
}

}  // namespace wlx::codegen
