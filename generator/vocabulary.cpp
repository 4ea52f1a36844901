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

Frame Frame::translated(const Vec3& local_offset) const {
  Frame f = *this;
  const Vec3 rho = R * local_offset;
  f.r = r + rho;
  f.v = v + cross(omega, rho);
  f.a_bias = a_bias + cross(alpha_bias, rho) + cross(omega, cross(omega, rho));
  return f;
}

Frame Frame::rotated(Axis axis, const Coordinate& c) const {
  Frame f = *this;
  const Vec3 a = R.col(static_cast<int>(axis));  // the joint axis does not move with its own joint
  f.R = R * rot(axis, c.q);
  f.omega = omega + ex(c.qdot) * a;
  f.alpha_bias = alpha_bias + ex(c.qdot) * cross(omega, a);  // the axis turns with the frame before
  f.joints.push_back({c.index, true, a, r});
  return f;
}

Frame Frame::slid(Axis axis, const Coordinate& c) const {
  Frame f = *this;
  const Vec3 a = R.col(static_cast<int>(axis));
  const Vec3 d = ex(c.q) * a;
  f.r = r + d;
  f.v = v + cross(omega, d) + ex(c.qdot) * a;
  f.a_bias = a_bias + cross(alpha_bias, d) + cross(omega, cross(omega, d)) +
             ex(2 * c.qdot) * cross(omega, a);
  f.joints.push_back({c.index, false, a, r});
  return f;
}

Frame Frame::turned(Axis axis, const ex& angle) const {
  Frame f = *this;
  f.R = R * rot(axis, angle);
  return f;
}

std::vector<Vec3> linear_jacobian(const Frame& f, int n) {
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
