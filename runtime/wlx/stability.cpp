// Will it tip: the support polygon of the loaded contacts, the static, ZMP and force-angle margins,
// and the smallest contact margin (contacts.hpp).
#include "wlx/contacts.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

WLX_MODEL_NAMESPACE_BEGIN

using contacts_detail::at;

namespace {

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// Signed distance of p to the polygon (counter-clockwise, n vertices): the smallest distance to an
// edge's line, positive on the inner side of all of them. A segment (n = 2) or a point (n = 1)
// encloses nothing: minus the distance to it. No support at all: 0 (polygon_size 0 says so).
double signed_distance(const std::array<Eigen::Vector2d, kContactCount>& v, int n, const Eigen::Vector2d& p) {
  if (n == 0) return 0;  // no support: polygon_size 0 says so (a margin of -infinity would not print)
  if (n == 1) return -(p - v[0]).norm();
  if (n == 2) {
    const Eigen::Vector2d e = v[1] - v[0];
    const double t = std::clamp((p - v[0]).dot(e) / e.squaredNorm(), 0.0, 1.0);
    return -(p - (v[0] + t * e)).norm();
  }
  double margin = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d a = v[at(i)], b = v[at((i + 1) % n)];
    margin = std::min(margin, cross2(b - a, p - a) / (b - a).norm());
  }
  return margin;
}

}  // namespace

void stability(const Model& model, Data& d, const Coordinates& s, const ContactForces& forces, Stability& out) {
  const Params& p = model.params();
  gen::bodies(s, Coordinates::Zero(), p, {.com = &d.body_com}, false);
  out.com = centre_of_mass(model, d);

  // The supporting contacts in load, then their convex hull (Andrew's monotone chain) seen from above.
  std::array<int, kContactCount> loaded{};
  int n = 0;
  for (int c = 0; c < kContactCount; ++c)
    if (gen::kContacts[at(c)].supports && forces.normal(c) > 0) loaded[at(n++)] = c;
  const auto xy = [&](int c) { return Eigen::Vector2d(forces.point(0, c), forces.point(1, c)); };
  std::sort(loaded.begin(), loaded.begin() + n, [&](int a, int b) {
    return forces.point(0, a) < forces.point(0, b) || (forces.point(0, a) == forces.point(0, b) && forces.point(1, a) < forces.point(1, b));
  });
  std::array<int, 2 * kContactCount + 1> hull{};
  int h = 0;
  for (int pass = 0; pass < 2 && n > 0; ++pass) {
    const int start = h;
    for (int k = 0; k < n; ++k) {
      const int c = loaded[at(pass == 0 ? k : n - 1 - k)];
      while (h >= start + 2 && cross2(xy(hull[at(h - 1)]) - xy(hull[at(h - 2)]), xy(c) - xy(hull[at(h - 2)])) <= 0) --h;
      hull[at(h++)] = c;
    }
    --h;  // each chain's last point starts the other
  }
  if (n == 1) h = 1;
  out.polygon_size = std::min(h, kContactCount);
  std::array<Eigen::Vector2d, kContactCount> vertices{};
  for (int i = 0; i < out.polygon_size; ++i) {
    out.polygon[at(i)] = hull[at(i)];
    vertices[at(i)] = xy(hull[at(i)]);
  }
  const int m = out.polygon_size;
  out.static_margin = signed_distance(vertices, m, out.com.head<2>());

  // The support's net wrench (about K0's origin), and its zero-moment point on the plane z = h of
  // the loaded contacts' mean height: M - zmp x F has no horizontal part there.
  Eigen::Vector3d F = Eigen::Vector3d::Zero(), M = Eigen::Vector3d::Zero();
  double height = 0;
  for (int c = 0; c < kContactCount; ++c) {
    F += forces.force.col(c);
    M += forces.point.col(c).cross(forces.force.col(c)) + forces.moment.col(c);
  }
  for (int i = 0; i < m; ++i) height += forces.point(2, out.polygon[at(i)]) / m;
  out.zmp = F.z() > 0 ? Eigen::Vector3d((height * F.x() - M.y()) / F.z(), (M.x() + height * F.y()) / F.z(), height)
                      : Eigen::Vector3d(out.com.x(), out.com.y(), height);  // nothing carries the machine: no ZMP
  out.zmp_margin = signed_distance(vertices, m, out.zmp.head<2>());

  // Force-angle: the net force and moment on the CoM other than the support's, f_r = -F and
  // n_r = -(M - com x F), about each edge a -> b (the next vertex counter-clockwise; a segment's
  // two directions). l: from the CoM to the edge's axis, normal to it; the moment's part along the
  // axis becomes the equivalent couple of forces at distance |l|; theta from f* to l, positive while
  // l lies outward of f* (the machine is held up by that edge's side).
  const Eigen::Vector3d f_r = -F, n_r = -(M - out.com.cross(F));
  out.tip_angle = std::numeric_limits<double>::infinity();
  out.tip_edge = {-1, -1};
  const int edges = m >= 3 ? m : (m == 2 ? 2 : 0);
  for (int i = 0; i < edges; ++i) {
    const int ca = out.polygon[at(i)], cb = out.polygon[at((i + 1) % m)];
    const Eigen::Vector3d a = forces.point.col(ca), b = forces.point.col(cb);
    const Eigen::Vector3d axis = (b - a).normalized();
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - axis * axis.transpose();
    const Eigen::Vector3d l = across * (b - out.com);
    const Eigen::Vector3d f_star = across * f_r + l.normalized().cross(axis.dot(n_r) * axis) / l.norm();
    const double theta = std::atan2(-axis.dot(f_star.cross(l)), f_star.dot(l)) ;
    if (theta < out.tip_angle) out.tip_angle = theta, out.tip_edge = {ca, cb};
  }
  if (edges == 0) out.tip_angle = 0;  // one contact in load: no edge to stand on
}

double smallest_contact_margin(const Model& model, const ContactForces& forces) {
  const double weight = model.total_mass() * (gen::kHasDynamics ? model.params().*gen::kGravity : 1.0);
  double margin = std::numeric_limits<double>::infinity();
  for (int c = 0; c < kContactCount; ++c)
    if (gen::kContacts[at(c)].supports) margin = std::min({margin, forces.normal(c), forces.friction_margin(c)});
  return margin / weight;
}

WLX_MODEL_NAMESPACE_END
