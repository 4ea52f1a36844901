// Will it tip: the support polygon of the contacts in load, the static, ZMP and force-angle
// margins, from the contacts' points, forces and moments alone. Geometry on a model's contacts,
// whatever their number: compiled once, into the library wlx::numerics (contacts.hpp's stability()
// gives it a model's contact forces and centre of mass). Allocates nothing: the caller lends the
// workspace, sized for its contacts.
#pragma once

#include <Eigen/Core>

#include <array>
#include <span>

namespace wlx::support {

struct Margins {
  int polygon_size = 0;  // vertices written to `polygon`; fewer than 3 on a line or a point
  // The CoM's projection: signed distance to the nearest polygon edge (m, positive inside).
  double static_margin = 0;
  // The zero-moment point of the contact forces on the plane of the loaded contacts' mean height,
  // and its signed distance to the nearest edge (m, positive inside).
  Eigen::Vector3d zmp = Eigen::Vector3d::Zero();
  double zmp_margin = 0;
  // The force-angle stability measure (Papadopoulos and Rey, 1996): for every edge of the polygon
  // the angle between the net force on the CoM (gravity and inertia, with the moment's equivalent
  // couple) and the line from the CoM to the edge; the machine tips about the edge whose angle
  // reaches zero. The smallest angle (rad) and its edge (two contacts).
  double tip_angle = 0;
  std::array<int, 2> tip_edge{-1, -1};
};

// `count` contacts, each a column of point, force and moment (3 x count, column-major, K0) with its
// normal force and whether it supports the machine; com the machine's centre of mass. The support
// polygon (the supporting contacts with a positive normal force, counter-clockwise seen from above;
// fewer than 3 on a line or a point) goes to polygon[0 .. polygon_size); with nothing in load the
// margins and the tip angle are 0 and the ZMP is the CoM's projection. Workspace: `loaded` holds
// count entries, `hull` 2 count + 1, `corners` count (each at least 1).
Margins margins(int count, const double* point, const double* force, const double* moment, const double* normal,
                const bool* supports, const Eigen::Vector3d& com, std::span<int> polygon, std::span<int> loaded,
                std::span<int> hull, std::span<Eigen::Vector2d> corners);

}  // namespace wlx::support
