// The support polygon and its margins (support_polygon.hpp), compiled once into wlx::numerics.
#include "wlx/support_polygon.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace wlx::support {
namespace {

std::size_t at(int i) { return static_cast<std::size_t>(i); }

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// Signed distance of p to the polygon (counter-clockwise, n vertices): the smallest distance to an
// edge's line, positive on the inner side of all of them. A segment (n = 2) or a point (n = 1)
// encloses nothing: minus the distance to it. No support at all: 0 (polygon_size 0 says so).
double signed_distance(std::span<const Eigen::Vector2d> v, int n, const Eigen::Vector2d& p) {
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

Margins margins(int count, const double* point_data, const double* force_data, const double* moment_data, const double* normal,
                const bool* supports, const Eigen::Vector3d& com, std::span<int> polygon, std::span<int> loaded, std::span<int> hull,
                std::span<Eigen::Vector2d> corners) {
  const Eigen::Map<const Eigen::Matrix3Xd> point(point_data, 3, count), force(force_data, 3, count), moment(moment_data, 3, count);
  Margins out;
  // The supporting contacts in load, then their convex hull (Andrew's monotone chain) seen from above.
  int n = 0;
  for (int c = 0; c < count; ++c)
    if (supports[at(c)] && normal[at(c)] > 0) loaded[at(n++)] = c;
  const auto xy = [&](int c) { return Eigen::Vector2d(point(0, c), point(1, c)); };
  std::sort(loaded.begin(), loaded.begin() + n, [&](int a, int b) {
    return point(0, a) < point(0, b) || (point(0, a) == point(0, b) && point(1, a) < point(1, b));
  });
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
  out.polygon_size = std::min(h, count);
  for (int i = 0; i < out.polygon_size; ++i) {
    polygon[at(i)] = hull[at(i)];
    corners[at(i)] = xy(hull[at(i)]);
  }
  const int m = out.polygon_size;
  out.static_margin = signed_distance(corners, m, com.head<2>());

  // The support's net wrench (about K0's origin), and its zero-moment point on the plane z = h of
  // the loaded contacts' mean height: M - zmp x F has no horizontal part there.
  Eigen::Vector3d F = Eigen::Vector3d::Zero(), M = Eigen::Vector3d::Zero();
  double height = 0;
  for (int c = 0; c < count; ++c) {
    F += force.col(c);
    M += point.col(c).cross(force.col(c)) + moment.col(c);
  }
  for (int i = 0; i < m; ++i) height += point(2, polygon[at(i)]) / m;
  out.zmp = F.z() > 0 ? Eigen::Vector3d((height * F.x() - M.y()) / F.z(), (M.x() + height * F.y()) / F.z(), height)
                      : Eigen::Vector3d(com.x(), com.y(), height);  // nothing carries the machine: no ZMP
  out.zmp_margin = signed_distance(corners, m, out.zmp.head<2>());

  // Force-angle: the net force and moment on the CoM other than the support's, f_r = -F and
  // n_r = -(M - com x F), about each edge a -> b (the next vertex counter-clockwise; a segment's
  // two directions). l: from the CoM to the edge's axis, normal to it; the moment's part along the
  // axis becomes the equivalent couple of forces at distance |l|; theta from f* to l, positive while
  // l lies outward of f* (the machine is held up by that edge's side).
  const Eigen::Vector3d f_r = -F, n_r = -(M - com.cross(F));
  out.tip_angle = std::numeric_limits<double>::infinity();
  const int edges = m >= 3 ? m : (m == 2 ? 2 : 0);
  for (int i = 0; i < edges; ++i) {
    const int ca = polygon[at(i)], cb = polygon[at((i + 1) % m)];
    const Eigen::Vector3d a = point.col(ca), b = point.col(cb);
    const Eigen::Vector3d axis = (b - a).normalized();
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - axis * axis.transpose();
    const Eigen::Vector3d l = across * (b - com);
    const Eigen::Vector3d f_star = across * f_r + l.normalized().cross(axis.dot(n_r) * axis) / l.norm();
    const double theta = std::atan2(-axis.dot(f_star.cross(l)), f_star.dot(l));
    if (theta < out.tip_angle) out.tip_angle = theta, out.tip_edge = {ca, cb};
  }
  if (edges == 0) out.tip_angle = 0;  // one contact in load: no edge to stand on
  return out;
}

}  // namespace wlx::support
