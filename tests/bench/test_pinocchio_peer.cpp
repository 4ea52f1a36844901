// Pinocchio 3 as an independent check of a URDF model (built with -DWLX_PINOCCHIO_DIR, beside
// wlx_bench's Pinocchio rows, which it vouches for): Pinocchio's own URDF parser and algorithms,
// with the robot's base joined to the world by six joints (x, y, z, then rotations about z, y, x:
// wlx's base coordinates and their rates), compute at random states what wlx computes from its
// generated functions: every URDF link's pose (framesForwardKinematics against gen::kinematics)
// the joints' Jacobians (computeJointJacobians against gen::joint_jacobian) and the open tree's
// inverse dynamics with gravity (rnea against Kane's sums over the bodies' Jacobians,
// bench/open_tree.hpp). The wheels' spins, which wlx's model does not have as
// coordinates, are held at zero angle, rate and acceleration: each wheel is then a rigid part of its
// leg in both.
//
// Tolerance: 1e-12 relative to the largest entry of the compared quantity: both sides are exact
// formulas in double precision (Pinocchio's recursive Newton-Euler pass in local frames, wlx's
// sums in the world frame), and differ by rounding, some 1e-15 relative. A wrong offset, axis, mass
// or inertia shows far above it: the second test makes the heaviest body 1% heavier in wlx's
// parameters and sees it.
#include "../helpers/random.hpp"
#include "open_tree.hpp"
#include "pinocchio_peer.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/all.hpp>
#include <wlx/model.hpp>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

using namespace wlx;

namespace {

constexpr int kStates = 1000;
constexpr double kRelativeTolerance = 1e-12;

// Pinocchio's configuration and velocities for wlx's coordinates: the base's six, then each
// coordinate that is a URDF joint, by name; the other joints (the wheels' spins) at zero.
struct Mapping {
  wlx_peer::PinocchioRobot& robot;
  std::vector<std::pair<int, int>> q_of, v_of;  // (wlx coordinate, Pinocchio index)
  explicit Mapping(wlx_peer::PinocchioRobot& r) : robot(r) {
    for (int k = 0; k < 6; ++k) q_of.emplace_back(k, k), v_of.emplace_back(k, k);
    for (int k = 6; k < gen::kCoordinateCount; ++k) {
      const std::string name(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
      if (robot.q_index(name) < 0) continue;
      REQUIRE_MESSAGE(robot.q_size(name) == 1, name << ": a coordinate on a joint of " << robot.q_size(name) << " configuration entries");
      q_of.emplace_back(k, robot.q_index(name));
      v_of.emplace_back(k, robot.v_index(name));
    }
  }
  Eigen::VectorXd q(const gen::Coordinates& s) const {
    Eigen::VectorXd out = robot.neutral();
    for (const auto& [k, i] : q_of) out(i) = s(k);
    return out;
  }
  Eigen::VectorXd v(const gen::Coordinates& sdot) const {
    Eigen::VectorXd out = Eigen::VectorXd::Zero(robot.nv());
    for (const auto& [k, i] : v_of) out(i) = sdot(k);
    return out;
  }
};

double relative(double difference, double scale) { return difference / std::max(scale, 1e-300); }

struct Worst {
  double poses = 0, jacobians = 0, torques = 0;
};

// The largest relative differences over kStates random states, with wlx's parameters `p`.
Worst compare(const gen::Params& p) {
  wlx_peer::PinocchioRobot robot(WLX_PINOCCHIO_URDF, wlx_peer::Root::euler_zyx);
  const Mapping map(robot);
  // Every joint that moves a body is a wlx coordinate: the base's six and the legs' joints.
  REQUIRE(robot.nv() == static_cast<int>(map.v_of.size()) + gen::kWheelCount);
  // wlx's frames of URDF links: all but the wheels' contact frames.
  std::vector<int> link_frames;
  std::vector<std::string> link_names;
  for (int f = 0; f < gen::kFrameCount; ++f) {
    const std::string name(gen::kFrameNames[static_cast<std::size_t>(f)]);
    if (name.rfind("contact_", 0) == 0) continue;
    link_frames.push_back(f);
    link_names.push_back(name);
  }
  CHECK(link_frames.size() == static_cast<std::size_t>(gen::kFrameCount - gen::kWheelCount));
  std::mt19937_64 rng(20261206);
  open_tree::OpenTreeWorkspace w;
  Worst worst;
  for (int n = 0; n < kStates; ++n) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng), sddot = test::random_rates(rng);
    const Eigen::VectorXd q = map.q(s);
    gen::FramePositions positions;
    gen::FrameRotations rotations;
    gen::kinematics(s, p, {.positions = &positions, .rotations = &rotations});
    double pose_difference = 0, pose_scale = 1;  // rotations' entries are of order 1
    const std::vector<Eigen::Matrix<double, 3, 4>> X = robot.link_placements(q, link_names);
    for (std::size_t k = 0; k < link_frames.size(); ++k) {
      const int f = link_frames[k];
      pose_difference = std::max({pose_difference, (X[k].leftCols<3>() - rotations[static_cast<std::size_t>(f)]).cwiseAbs().maxCoeff(),
                                  (X[k].col(3) - positions.col(f)).cwiseAbs().maxCoeff()});
      pose_scale = std::max(pose_scale, positions.col(f).cwiseAbs().maxCoeff());
    }
    // The joints' twists: wlx's column of each coordinate against Pinocchio's of its joint.
    gen::JointJacobian J;
    gen::joint_jacobian(s, p, {.J = &J});
    const Eigen::MatrixXd Jp = robot.joint_jacobians(q);
    double jacobian_difference = 0, jacobian_scale = 0;
    for (const auto& [k, i] : map.v_of) {
      jacobian_difference = std::max(jacobian_difference, (J.col(k) - Jp.col(i)).cwiseAbs().maxCoeff());
      jacobian_scale = std::max(jacobian_scale, J.col(k).cwiseAbs().maxCoeff());
    }
    worst.jacobians = std::max(worst.jacobians, relative(jacobian_difference, jacobian_scale));
    gen::Coordinates Q;
    open_tree::open_tree_inverse_dynamics(p, s, sdot, sddot, w, Q);
    const Eigen::VectorXd tau = robot.inverse_dynamics(q, map.v(sdot), map.v(sddot));
    double torque_difference = 0, torque_scale = 0;
    for (const auto& [k, i] : map.v_of) {
      torque_difference = std::max(torque_difference, std::abs(tau(i) - Q(k)));
      torque_scale = std::max(torque_scale, std::abs(Q(k)));
    }
    worst.poses = std::max(worst.poses, relative(pose_difference, pose_scale));
    worst.torques = std::max(worst.torques, relative(torque_difference, torque_scale));
  }
  return worst;
}

}  // namespace

TEST_CASE("Pinocchio, from the URDF by its own parser, computes the links' poses, the joints' Jacobians and the open tree's inverse dynamics that wlx computes") {
  const Model model;
  const Worst worst = compare(model.params());
  MESSAGE("over " << kStates << " random states, the largest relative differences: link poses " << worst.poses
                  << ", joint Jacobians " << worst.jacobians << ", torques " << worst.torques);
  CHECK(worst.poses < kRelativeTolerance);
  CHECK(worst.jacobians < kRelativeTolerance);
  CHECK(worst.torques < kRelativeTolerance);
}

TEST_CASE("The Pinocchio check sees the heaviest body 1% heavier in wlx's parameters") {
  const Model model;
  gen::Params p = model.params();
  int heaviest = 0;
  for (int b = 1; b < gen::kBodyCount; ++b)
    if (p.*gen::kBodyMass[static_cast<std::size_t>(b)].mass > p.*gen::kBodyMass[static_cast<std::size_t>(heaviest)].mass) heaviest = b;
  p.*gen::kBodyMass[static_cast<std::size_t>(heaviest)].mass *= 1.01;
  const Worst worst = compare(p);
  MESSAGE("with " << gen::kBodyNames[static_cast<std::size_t>(heaviest)] << " 1% heavier: torques " << worst.torques);
  CHECK(worst.poses < kRelativeTolerance);  // the mass moves no frame
  CHECK(worst.jacobians < kRelativeTolerance);  // nor any joint
  CHECK(worst.torques > 1e3 * kRelativeTolerance);
}
