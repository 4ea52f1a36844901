// An independent library as a check: Orocos KDL, on the open tree built from the generated tables
// (bench/kdl_peer.hpp), computes the frames, the end frames' and bodies' Jacobians and the
// open-tree inverse dynamics (recursive Newton-Euler) that the generated functions compute
// symbolically, and its FK confirms the closed-form IK's solutions. Compiled once per built-in model.
//
// Tolerance: 1e-12 relative to the largest entry of the compared quantity (positions, a Jacobian,
// a torque vector). Both sides are exact formulas evaluated in double precision over at most a
// few dozen operations per entry, so they differ by rounding: some 1e-15 relative. 1e-12 leaves
// a factor of ~1000 for cancellation at the random poses and catches any wrong offset, axis, order,
// sign, mass or inertia, which show at 1e-3 or more.
#include "../helpers/random.hpp"
#include "kdl_peer.hpp"

#include <doctest/doctest.h>
#include <kdl/jacobian.hpp>
#include <wlx/ik.hpp>
#include <kdl/treefksolverpos_recursive.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>
#include <kdl/treejnttojacsolver.hpp>

#include <algorithm>
#include <cmath>

using namespace wlx;
using namespace wlx::kdl_peer;

namespace {

constexpr int kConfigurations = 1000;
constexpr double kRelativeTolerance = 1e-12;

Eigen::Vector3d to_eigen(const KDL::Vector& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Matrix3d to_eigen(const KDL::Rotation& R) {
  Eigen::Matrix3d M;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) M(i, j) = R(i, j);
  return M;
}

// KDL's Jacobian (6 x joints, rows v then omega) spread onto the coordinates s.
Eigen::Matrix<double, 6, gen::kCoordinateCount> on_coordinates(const PeerTree& peer, const KDL::Jacobian& J) {
  Eigen::Matrix<double, 6, gen::kCoordinateCount> out = Eigen::Matrix<double, 6, gen::kCoordinateCount>::Zero();
  for (std::size_t i = 0; i < peer.coordinate_of_joint.size(); ++i) out.col(peer.coordinate_of_joint[i]) = J.data.col(static_cast<Eigen::Index>(i));
  return out;
}

// |a - b|max / |b|max: the normwise relative difference.
template <typename A, typename B>
double relative(const A& a, const B& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1e-300, b.cwiseAbs().maxCoeff());
}

struct Worst {
  double positions = 0, rotations = 0, body_jacobians = 0, closure_rows = 0, torques = 0;
};

// Compares KDL on `peer` with the generated functions at parameters p, over random configurations.
Worst compare(const PeerTree& peer, const gen::Params& p, int configurations) {
  KDL::TreeFkSolverPos_recursive fk(peer.tree);
  KDL::TreeJntToJacSolver jacobian(peer.tree);
  KDL::TreeIdSolver_RNE rne(peer.tree, peer.gravity);
  const unsigned nj = peer.tree.getNrOfJoints();
  KDL::Jacobian J(nj);
  KDL::JntArray tau(nj);
  OpenTreeWorkspace w;
  gen::FramePositions positions;
  gen::FrameRotations rotations;
  gen::ClosureJacobian dPhi_ds;
  gen::Coordinates Q;
  std::mt19937_64 rng(16);
  Worst worst;
  for (int trial = 0; trial < configurations; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng), sddot = test::random_rates(rng);
    const KDL::JntArray q = peer.joints(s), qdot = peer.joints(sdot), qddot = peer.joints(sddot);

    // Frames: every frame of interest.
    gen::kinematics(s, p, {.positions = &positions, .rotations = &rotations});
    gen::FramePositions kdl_positions;
    gen::FrameRotations kdl_rotations;
    for (int f = 0; f < gen::kFrameCount; ++f) {
      KDL::Frame F;
      const int wheel = wheel_of_contact(f);  // a hub's contact frame: from the hub's KDL pose
      REQUIRE(fk.JntToCart(q, F, frame_name(wheel < 0 ? f : gen::kWheels[static_cast<std::size_t>(wheel)].hub_frame)) >= 0);
      kdl_positions.col(f) = to_eigen(F.p);
      kdl_rotations[static_cast<std::size_t>(f)] = to_eigen(F.M);
      if (wheel >= 0) {
        const ContactFromHub c = contact_from_hub(p, wheel, to_eigen(F.p), to_eigen(F.M));
        kdl_positions.col(f) = c.position;
        kdl_rotations[static_cast<std::size_t>(f)] = c.rotation;
      }
      worst.rotations = std::max(worst.rotations, (kdl_rotations[static_cast<std::size_t>(f)] - rotations[static_cast<std::size_t>(f)]).cwiseAbs().maxCoeff());
    }
    worst.positions = std::max(worst.positions, relative(kdl_positions, positions));

    // The bodies' CoM Jacobians.
    gen::bodies(s, sdot, p, {.Jv = &w.Jv, .Jw = &w.Jw});
    for (int b = 0; b < gen::kBodyCount; ++b) {
      REQUIRE(jacobian.JntToJac(q, J, body_com_name(b)) >= 0);
      Eigen::Matrix<double, 6, gen::kCoordinateCount> generated;
      generated << w.Jv[static_cast<std::size_t>(b)], w.Jw[static_cast<std::size_t>(b)];
      worst.body_jacobians = std::max(worst.body_jacobians, relative(on_coordinates(peer, J), generated));
    }

    // The end frames' Jacobians as the closure rows carry them: a point row is a component of
    // the frame's origin velocity minus its target input, a level row the z component of
    // omega x (the frame's axis). (Sum rows involve no kinematics.)
    gen::closure(s, p, {.dPhi_ds = &dPhi_ds});
    for (int r = 0; r < gen::kClosureCount; ++r) {
      const gen::ClosureRowInfo& row = gen::kClosureRows[static_cast<std::size_t>(r)];
      if (row.kind == gen::RowKind::sum) continue;
      const int wheel = wheel_of_contact(row.frame);
      const int hub = wheel < 0 ? row.frame : gen::kWheels[static_cast<std::size_t>(wheel)].hub_frame;
      REQUIRE(jacobian.JntToJac(q, J, frame_name(hub)) >= 0);
      Eigen::Matrix<double, 6, gen::kCoordinateCount> Js = on_coordinates(peer, J);
      if (wheel >= 0) {  // the contact point's columns, from the hub's pose and Jacobian
        const Eigen::Matrix<double, 6, Eigen::Dynamic> hub_jacobian = Js;
        Js.topRows<3>() = contact_from_hub(p, wheel, positions.col(hub), rotations[static_cast<std::size_t>(hub)], &hub_jacobian).jacobian;
      }
      Eigen::Matrix<double, 1, gen::kCoordinateCount> expected;
      if (row.kind == gen::RowKind::point) {
        expected = Js.row(row.axis);
        expected(row.target) -= 1;
      } else {
        const Eigen::Vector3d axis = kdl_rotations[static_cast<std::size_t>(row.frame)].col(row.axis);
        for (int c = 0; c < gen::kCoordinateCount; ++c) expected(c) = Js.col(c).tail<3>().cross(axis).z();
      }
      worst.closure_rows = std::max(worst.closure_rows, relative(expected, dPhi_ds.row(r)));
    }

    // Open-tree inverse dynamics: KDL's recursive Newton-Euler against Kane's sums over the
    // generated body kinematics.
    REQUIRE(rne.CartToJnt(q, qdot, qddot, KDL::WrenchMap(), tau) >= 0);
    open_tree_inverse_dynamics(p, s, sdot, sddot, w, Q);
    Eigen::VectorXd generated(nj);
    for (unsigned i = 0; i < nj; ++i) generated(i) = Q(peer.coordinate_of_joint[i]);
    worst.torques = std::max(worst.torques, relative(tau.data, generated));
  }
  return worst;
}

}  // namespace

TEST_CASE("KDL: the open tree built from the generated tables has every frame, body and moving coordinate") {
  const gen::Params p;
  const PeerTree peer = build_tree(p);
  // Every coordinate that moves a frame is a KDL joint, once; every other one moves nothing.
  std::vector<int> joints = peer.coordinate_of_joint;
  std::sort(joints.begin(), joints.end());
  CHECK(std::adjacent_find(joints.begin(), joints.end()) == joints.end());
  std::vector<bool> is_joint(gen::kCoordinateCount, false);
  for (int c : joints) is_joint[static_cast<std::size_t>(c)] = true;
  for (int c = 0; c < gen::kCoordinateCount; ++c) {
    if (is_joint[static_cast<std::size_t>(c)]) continue;
    gen::Coordinates s = gen::Coordinates::Zero();
    gen::FramePositions at_zero, moved;
    gen::FrameRotations turned_at_zero, turned;
    gen::kinematics(s, p, {.positions = &at_zero, .rotations = &turned_at_zero});
    s(c) = 1;
    gen::kinematics(s, p, {.positions = &moved, .rotations = &turned});
    CHECK_MESSAGE((moved == at_zero && turned == turned_at_zero), gen::kCoordinateNames[static_cast<std::size_t>(c)]);
  }
  for (int f = 0; f < gen::kFrameCount; ++f) CHECK(peer.tree.getSegments().count(frame_name(f)) == (wheel_of_contact(f) < 0 ? 1u : 0u));
  for (int b = 0; b < gen::kBodyCount; ++b) CHECK(peer.tree.getSegments().count(body_com_name(b)) == 1);
  MESSAGE(gen::kModelName << ": " << peer.tree.getNrOfJoints() << " KDL joints, " << peer.tree.getNrOfSegments() << " segments, "
                          << peer.end_frames.size() << " end frames");
}

TEST_CASE("KDL: frames, Jacobians and open-tree inverse dynamics agree with the generated functions at 1000 random poses") {
  const gen::Params p;
  const PeerTree peer = build_tree(p);
  const Worst worst = compare(peer, p, kConfigurations);
  MESSAGE(gen::kModelName << " vs KDL, worst relative difference over " << kConfigurations << " poses: positions " << worst.positions
                          << ", rotations " << worst.rotations << ", body Jacobians " << worst.body_jacobians << ", closure rows "
                          << worst.closure_rows << ", open-tree torques " << worst.torques);
  CHECK(worst.positions <= kRelativeTolerance);
  CHECK(worst.rotations <= kRelativeTolerance);
  CHECK(worst.body_jacobians <= kRelativeTolerance);
  CHECK(worst.closure_rows <= kRelativeTolerance);
  CHECK(worst.torques <= kRelativeTolerance);
}

TEST_CASE("KDL: the comparison sees a wrong geometry and wrong masses") {
  // The tree built for lengths, offsets (a URDF's origins) and masses 10% larger than the generated functions are evaluated
  // with must disagree far beyond the tolerance: the comparison is not vacuous.
  const gen::Params p;
  gen::Params changed = p;
  for (const gen::ParamInfo& info : gen::kParamInfo)
    if (info.kind == gen::ParamKind::length || info.kind == gen::ParamKind::offset || info.kind == gen::ParamKind::mass)
      changed.*info.member *= 1.1;
  const Worst worst = compare(build_tree(changed), p, 20);
  CHECK(worst.positions > 1e-3);
  CHECK(worst.body_jacobians > 1e-3);
  CHECK(worst.torques > 1e-3);
}

TEST_CASE("KDL: the closed-form IK puts every limb where its closure rows ask, by KDL's forward kinematics") {
  // Along the model's IK sweeps (reachable by design): each solution's end frames, computed by KDL
  // from the solved joints, meet the limb's point and level rows. (Sum rows involve no kinematics.)
  // Tolerance 1e-12 m or rad: the closed form is exact up to rounding, and KDL's FK adds ~1e-15.
  const Model model;
  const PeerTree peer = build_tree(model.params());
  KDL::TreeFkSolverPos_recursive fk(peer.tree);
  double worst = 0;
  int solved = 0;
  for (const gen::SweepInfo& sweep : gen::kIkSweeps) {
    const int steps = static_cast<int>(std::lround(std::abs(sweep.to - sweep.from) / sweep.step));
    const double direction = sweep.to >= sweep.from ? 1.0 : -1.0;
    for (int k = 0; k <= steps; ++k) {
      gen::Coordinates s = gen::Coordinates::Zero();
      for (int i = 0; i < gen::kInputCount; ++i) s(i) = gen::kSweepStart[static_cast<std::size_t>(i)];
      s(sweep.input) = sweep.from + direction * k * sweep.step;
      solve_limb_closed_form(model, sweep.limb, 0, s);  // throws (fails the test) if out of reach
      ++solved;
      const KDL::JntArray q = peer.joints(s);
      const LimbBlock block = limb_block(sweep.limb);
      for (int r = 0; r < block.size; ++r) {
        const gen::ClosureRowInfo& row = gen::kClosureRows[static_cast<std::size_t>(block.rows[static_cast<std::size_t>(r)])];
        if (row.kind == gen::RowKind::sum) continue;
        KDL::Frame F;
        const int wheel = wheel_of_contact(row.frame);
        REQUIRE(fk.JntToCart(q, F, frame_name(wheel < 0 ? row.frame : gen::kWheels[static_cast<std::size_t>(wheel)].hub_frame)) >= 0);
        if (wheel >= 0) {
          const ContactFromHub c = contact_from_hub(model.params(), wheel, to_eigen(F.p), to_eigen(F.M));
          F.p = to_kdl(c.position);
          F.M = to_kdl(c.rotation);
        }
        const double residual = row.kind == gen::RowKind::point ? F.p(row.axis) - s(row.target) : F.M(2, row.axis);
        worst = std::max(worst, std::abs(residual));
      }
    }
  }
  MESSAGE(gen::kModelName << ": " << solved << " closed-form solutions along the IK sweeps, worst closure residual by KDL's FK "
                          << worst);
  int points = 0;  // every point of every sweep solved (a failure throws above)
  for (const gen::SweepInfo& sweep : gen::kIkSweeps) points += 1 + static_cast<int>(std::lround(std::abs(sweep.to - sweep.from) / sweep.step));
  CHECK(solved == points);
  CHECK(solved >= 100);
  CHECK(worst <= 1e-12);
}
