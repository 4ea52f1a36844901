// What the derivations' files share: the closure's and the wheels' rows (derivations.cpp), and the
// structure both dynamics passes (reduced_dynamics.cpp, generalized_forces.cpp) are built on, the
// roles of the coordinates in s' = T u and the tree of the bodies' chains (dynamics_tree.cpp).
// Internal to the generator.
#pragma once

#include "derivations.hpp"
#include "lane_code.hpp"

#include <array>
#include <string>
#include <vector>

namespace wlx::codegen::derivation {

inline int coordinate_count(const Model& m) { return static_cast<int>(m.coordinates.size()); }

// An output's prologue that zeroes a matrix before its nonzero elements are written.
inline constexpr const char* kZeroMatrix = "{}->setZero();";

// ---- rows (derivations.cpp) ---------------------------------------------------------------------

struct ClosureRow {
  ex value;
  std::vector<ex> gradient;
  ex convective;  // (d/dt dPhi_i/ds) s'
};
ClosureRow closure_row(const Model& m, const ClosureCondition& c);

struct WheelRow {
  std::vector<ex> C;     // v_W . n_W = C s'
  std::vector<ex> spin;  // spin rate = spin s'
  ex convective;         // (d/dt C) s'
};
WheelRow wheel_row(const Model& m, const NonholonomicWheel& wheel);

// ---- the dynamics' structure (dynamics_tree.cpp) ------------------------------------------------

// The coordinates' roles in s' = T u (model with a dynamics section): each commanded speed's index
// in u (-1 for the others), and whether T's row is dense (the dependent pair and the dependent joints).
struct RateRoles {
  std::vector<int> speed_of;
  std::vector<bool> dense;
  // Coordinate j's joint moves in a step: its rate is a commanded speed or a dense row of T (the
  // other inputs are held, and add nothing to a twist).
  bool moves(int j) const { return dense[static_cast<std::size_t>(j)] || speed_of[static_cast<std::size_t>(j)] >= 0; }
};
RateRoles rate_roles(const Model& m);

// The commanded speeds each coordinate's rate depends on (T's nonzero columns in its row), from the
// structure of the equations that fix the dense rates: the closure rows and the wheels' rolling
// rows, linear in s'. Their unknowns (the dependent pair and the dependent joints) split into
// independent blocks, the connected parts of "row r involves unknown j" (a leg's joints and its
// wheel's rate, say); a block's rates depend on the commanded speeds its rows involve, and on no
// other. A commanded speed's rate is itself; a held input's is zero (no speeds).
std::vector<std::vector<int>> rate_speeds(const Model& m, const RateRoles& roles);

// A joint of the bodies' chains as a node of their common tree (chains that share a prefix share
// its nodes).
struct TwistNode {
  const JointRecord* joint = nullptr;
  int parent = -1;
  std::vector<int> children, bodies;
  // The frame just after this joint in the frame just after the parent node's joint (K0 for a
  // root), through the held joints between them at their coordinates: orientation and origin.
  Mat3 placement_R = Mat3::identity();
  Vec3 placement_r;
};

// The tree of the bodies' chains through the joints that move in a step (RateRoles::moves): chains
// share their common joints; nodes come parents first.
struct TwistTree {
  std::vector<TwistNode> nodes;
  std::vector<int> body_node;  // each body's last node, -1 for a body no such joint moves
  // Each body's CoM frame in the frame just after its last node's joint (K0 for no node).
  std::vector<Mat3> body_R;
  std::vector<Vec3> body_r;
};
TwistTree twist_tree(const Model& m, const RateRoles& roles);

// A joint's twist per unit rate in K0, (omega; velocity of the point at K0's origin): (a; o x a)
// for a revolute joint (axis a through o), (0; a) for a prismatic one.
std::array<ex, 6> spatial_axis(const JointRecord& joint);
// The same joint, recorded by two chains through it: its coordinate, kind, axis and origin alike.
bool same_joint(const JointRecord& a, const JointRecord& b);

// reduced_dynamics' outputs, in the numbering of its code's statements (lane_code::Statement::output).
enum ReducedOutput { kM, kB_velocity, kB_bias, kQ_gravity, kReducedOutputs };

// reduced_dynamics by composite rigid bodies in the joints' own frames (composite_dynamics.cpp):
// scalar code, on rows of lanes for sibling limbs of one shape, that writes M, b_velocity, B_bias
// and Q_gravity from the composite inertias beyond each joint, the Newton-Euler recursion at zero
// u', and T's pattern.
lane_code::LaneProgram composite_rigid_body_program(const Model& m);

}  // namespace wlx::codegen::derivation
