// Benchmarks (Google Benchmark): generated functions per call, and closed-form vs Newton IK.
// Compare numbers from one run only (ratios): these machines are noisy.
#include "numeric_baseline.hpp"
#include "../tests/helpers/kane_over_bodies.hpp"

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <wlx/ik.hpp>
#include <wlx/dynamics.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>
#include <wlx/simulation.hpp>

#include <algorithm>
#include <deque>
#include <memory>
#include <numbers>
#include <stdexcept>

#ifdef WLX_HAVE_KDL
#include "kdl_peer.hpp"

#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/chainiksolverpos_nr.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>
#include <kdl/jacobian.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>
#include <kdl/treejnttojacsolver.hpp>
#endif

#include <cstring>
#include <map>
#include <random>
#include <string>
#include <initializer_list>
#include <tuple>
#include <vector>

namespace {

using namespace wlx;

Coordinates assembled_nominal(const Model& model) {
  Coordinates s = nominal_inputs();
  solve_ik_closed_form(model, s);
  return s;
}

// A target away from the nominal pose: cabin lowered and tilted, feet and levels moved.
Coordinates moved_target() {
  Coordinates s = nominal_inputs();
  namespace c = gen::coord;
  s(c::z_C) = 1.7;
  s(c::roll) = 0.08;
  s(c::pitch) = -0.05;
  s(c::x_Fl) = 3.2;
  s(c::z_Fr) = 0.3;
  s(c::z_Wl) = 0.2;
  s(c::theta_l5) = 0.3;
  return s;
}

void BM_gen_kinematics_positions(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::kinematics(s, model.params(), {.positions = &d.frame_positions});
    benchmark::DoNotOptimize(d.frame_positions.data());
  }
}
void BM_gen_kinematics_all(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::kinematics(s, model.params(), {.positions = &d.frame_positions, .rotations = &d.frame_rotations});
    benchmark::DoNotOptimize(d.frame_positions.data());
    benchmark::DoNotOptimize(d.frame_rotations.data());
  }
}
void BM_gen_closure(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::closure(s, model.params(), {.Phi = &d.Phi, .dPhi_ds = &d.dPhi_ds}, false);
    benchmark::DoNotOptimize(d.dPhi_ds.data());
  }
}
void BM_gen_nonholonomic(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::nonholonomic(s, model.params(), {.C = &d.C, .spin = &d.spin}, false);
    benchmark::DoNotOptimize(d.C.data());
  }
}
void BM_gen_convective(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  const Coordinates sdot = Coordinates::Constant(0.1);
  for (auto _ : st) {
    gen::convective(s, sdot, model.params(), {.dPhi_ds_dot_sdot = &d.dPhi_ds_dot_sdot, .C_dot_sdot = &d.C_dot_sdot});
    benchmark::DoNotOptimize(d.C_dot_sdot.data());
  }
}
void BM_gen_bodies(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  const Coordinates sdot = Coordinates::Constant(0.1);
  for (auto _ : st) {
    gen::bodies(s, sdot, model.params(),
                {.com = &d.body_com,
                 .rotations = &d.body_rotations,
                 .Jv = &d.body_Jv,
                 .Jw = &d.body_Jw,
                 .Jv_dot_sdot = &d.body_Jv_dot_sdot,
                 .Jw_dot_sdot = &d.body_Jw_dot_sdot},
                false);
    benchmark::DoNotOptimize(d.body_Jv.data());
  }
}

// FK + Phi + dPhi/ds + C(s): the fused generated function, and the three separate ones. The
// workspace keeps its structural zeros (zero_fill = false, as the runtime calls it); the second
// variant rewrites them every call; the third cycles through 64 random poses (angles within
// +-pi), where data-dependent branches of a libm would show.
template <bool zero_fill>
void BM_gen_kinematic_update_fused(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::kinematic_update(s, model.params(),
                          {.positions = &d.frame_positions,
                           .rotations = &d.frame_rotations,
                           .Phi = &d.Phi,
                           .dPhi_ds = &d.dPhi_ds,
                           .C = &d.C},
                          zero_fill);
    benchmark::DoNotOptimize(d.C.data());
  }
}
void BM_gen_kinematic_update_fused_random_poses(benchmark::State& st) {
  const Model model;
  Data d;
  std::array<Coordinates, 64> poses;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-3.14, 3.14);
  for (auto& s : poses) s = Coordinates::NullaryExpr([&] { return angle(rng); });
  std::size_t k = 0;
  for (auto _ : st) {
    gen::kinematic_update(poses[k++ & 63], model.params(),
                          {.positions = &d.frame_positions,
                           .rotations = &d.frame_rotations,
                           .Phi = &d.Phi,
                           .dPhi_ds = &d.dPhi_ds,
                           .C = &d.C},
                          false);
    benchmark::DoNotOptimize(d.C.data());
  }
}
void BM_gen_kinematic_update_separate(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::kinematics(s, model.params(), {.positions = &d.frame_positions, .rotations = &d.frame_rotations});
    gen::closure(s, model.params(), {.Phi = &d.Phi, .dPhi_ds = &d.dPhi_ds}, false);
    gen::nonholonomic(s, model.params(), {.C = &d.C}, false);
    benchmark::DoNotOptimize(d.C.data());
  }
}
// The full kinematic update of a controller step: closed-form IK of the 4 limbs, then the fused pass.
void BM_full_kinematic_update(benchmark::State& st) {
  const Model model;
  Data d;
  Coordinates s = moved_target();
  for (auto _ : st) {
    solve_ik_closed_form(model, s);
    kinematic_update(model, d, s);
    benchmark::DoNotOptimize(d.C.data());
  }
}

void BM_ik_closed_form_4_limbs(benchmark::State& st) {
  const Model model;
  Coordinates s = moved_target();
  for (auto _ : st) {
    solve_ik_closed_form(model, s);
    benchmark::DoNotOptimize(s.data());
  }
}
void BM_ik_newton_cold_4_limbs(benchmark::State& st) {
  const Model model;
  Data d;
  Coordinates start = assembled_nominal(model);
  const Coordinates target = moved_target();
  start.head(kInputCount) = target.head(kInputCount);
  long iterations = 0;
  for (auto _ : st) {
    Coordinates s = start;
    const NewtonReport r = solve_ik_newton(model, d, s);
    iterations += r.iterations[0] + r.iterations[1] + r.iterations[2] + r.iterations[3];
    benchmark::DoNotOptimize(s.data());
  }
  st.counters["iterations"] = benchmark::Counter(static_cast<double>(iterations), benchmark::Counter::kAvgIterations);
}
void BM_ik_newton_warm_4_limbs(benchmark::State& st) {
  // A continuation step: the previous solution is 1 mm / 1 mrad away.
  const Model model;
  Data d;
  Coordinates before = moved_target();
  before(gen::coord::x_Fl) -= 1e-3;
  before(gen::coord::z_Wl) -= 1e-3;
  before(gen::coord::theta_r5) -= 1e-3;
  solve_ik_closed_form(model, before);
  Coordinates start = before;
  start.head(kInputCount) = moved_target().head(kInputCount);
  long iterations = 0;
  for (auto _ : st) {
    Coordinates s = start;
    const NewtonReport r = solve_ik_newton(model, d, s);
    iterations += r.iterations[0] + r.iterations[1] + r.iterations[2] + r.iterations[3];
    benchmark::DoNotOptimize(s.data());
  }
  st.counters["iterations"] = benchmark::Counter(static_cast<double>(iterations), benchmark::Counter::kAvgIterations);
}

// Velocity level: closure Jacobian + C(s) + block factorizations + J_beta solve.
void BM_dependent_rates(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  Coordinates sdot = Coordinates::Zero();
  sdot(gen::coord::roll) = 0.1;
  for (auto _ : st) {
    solve_dependent_rates(model, d, s, sdot, default_pair());
    benchmark::DoNotOptimize(sdot.data());
  }
}
// Acceleration level, after the velocity level at the same state (it reuses the factorizations).
void BM_dependent_accelerations(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  Coordinates sdot = Coordinates::Zero();
  sdot(gen::coord::roll) = 0.1;
  solve_dependent_rates(model, d, s, sdot, default_pair());
  Coordinates sddot = Coordinates::Zero();
  for (auto _ : st) {
    solve_dependent_accelerations(model, d, s, sdot, sddot, default_pair());
    benchmark::DoNotOptimize(sddot.data());
  }
}
// The whole NH-1 run: 2 s at 1 ms, RK4, closed-form IK at every stage.
void BM_run_NH1(benchmark::State& st) {
  Scenario sc;
  sc.rates(gen::coord::roll) = 5 * std::numbers::pi / 180;
  sc.duration = 2.0;
  for (auto _ : st) {
    const Trajectory tr = simulate(sc);
    benchmark::DoNotOptimize(tr.samples.data());
  }
}

// The inverse-dynamics step's pose (the cabin 0.3 m forward, x_C' = 3 m/s), solved once: where the
// benchmarks of the step and of its parts start from.
struct SolvedStep {
  const Model model;
  Data d;
  DynamicsTerms terms;
  Coordinates s = nominal_inputs();
  const CommandVector u = CommandVector(0, 3, 0, 0);
  SolvedStep() {
    s(gen::coord::x_C) = 0.3;
    solve_ik_closed_form(model, s);
    inverse_dynamics(model, d, s, u, CommandVector::Zero(), terms);
  }
};

// One inverse-dynamics step: closed-form IK, dependent rates and accelerations, the bodies'
// Newton-Euler pass, J_beta, and the weighted torque distribution.
void BM_inverse_dynamics_step(benchmark::State& st) {
  SolvedStep x;
  for (auto _ : st) {
    solve_ik_closed_form(x.model, x.s);
    inverse_dynamics(x.model, x.d, x.s, x.u, CommandVector::Zero(), x.terms);
    const TorqueVector tau = distribute_torques(x.terms.J_beta, x.terms.Qstar, Weighting::model_weights());
    benchmark::DoNotOptimize(tau.data());
  }
}
// The weighted least-norm torque split of that step alone (weighting 1).
void BM_distribute_torques(benchmark::State& st) {
  SolvedStep x;
  for (auto _ : st) {
    const TorqueVector tau = distribute_torques(x.terms.J_beta, x.terms.Qstar, Weighting::model_weights());
    benchmark::DoNotOptimize(tau.data());
  }
}
// The generated passes of one inverse-dynamics step, then the step's generated code alone, IK
// included, run back to back as the step runs it (its floor: the rest of the step is the runtime's
// linear algebra). T is the rate basis at s, computed once; s'' that step's.
void dynamics_passes(SolvedStep& x) {
  gen::dynamics_update(x.s, x.model.params(), {.dPhi_ds = &x.d.dPhi_ds, .C = &x.d.C}, false);
  gen::convective(x.s, x.terms.sdot, x.model.params(), {.dPhi_ds_dot_sdot = &x.d.dPhi_ds_dot_sdot, .C_dot_sdot = &x.d.C_dot_sdot});
  gen::generalized_forces(x.s, x.terms.sdot, x.terms.sddot, x.terms.T, x.model.params(), {.Qstar = &x.terms.Qstar});
}
void BM_gen_dynamics_passes(benchmark::State& st) {
  SolvedStep x;
  for (auto _ : st) {
    dynamics_passes(x);
    benchmark::DoNotOptimize(x.terms.Qstar.data());
  }
}
// The equations of motion alone: reduced_dynamics' (composite rigid bodies in the joints' frames)
// against Kane's sums over bodies()' full Jacobians with dense Eigen products (what a user of the body Jacobians writes;
// the step's before: the runtime summed them over the bodies' columns).
void BM_gen_kane_sums(benchmark::State& st) {
  SolvedStep x;
  CommandVector b_velocity;
  for (auto _ : st) {
    gen::reduced_dynamics(x.s, x.terms.sdot, x.terms.T, x.model.params(),
                          {.M = &x.terms.M, .b_velocity = &b_velocity, .B_bias = &x.terms.B_bias, .Q_gravity = &x.terms.Q_gravity},
                          false);
    benchmark::DoNotOptimize(x.terms.M.data());
  }
}
void BM_kane_sums_over_body_jacobians(benchmark::State& st) {
  SolvedStep x;
  auto sums = std::make_unique<test::KaneSums>();
  for (auto _ : st) {
    test::kane_over_bodies(x.model.params(), x.s, x.terms.sdot, x.terms.T, *sums);
    benchmark::DoNotOptimize(sums->M.data());
  }
}
void BM_inverse_dynamics_generated_only(benchmark::State& st) {
  SolvedStep x;
  for (auto _ : st) {
    solve_ik_closed_form(x.model, x.s);
    dynamics_passes(x);
    benchmark::DoNotOptimize(x.terms.Qstar.data());
  }
}
// The whole ID-1 run (495 samples, RK4) with weighting 1.
void BM_run_ID1(benchmark::State& st) {
  Scenario sc;
  sc.rates(gen::coord::x_C) = 3.0;
  sc.duration = 0.494;
  sc.weighting = Weighting::model_weights();
  for (auto _ : st) {
    const Trajectory tr = simulate(sc);
    benchmark::DoNotOptimize(tr.samples.data());
  }
}

// ---- the numeric baseline: the same quantities without generated code ----
void BM_base_frames(benchmark::State& st) {
  const Model model;
  baseline::Frames w;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    baseline::frames(model.params(), s, w);
    benchmark::DoNotOptimize(w.r.data());
  }
}
void BM_base_closure_jacobian(benchmark::State& st) {
  const Model model;
  baseline::Frames w;
  gen::ClosureJacobian J;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    baseline::closure_jacobian(model.params(), s, J, w);
    benchmark::DoNotOptimize(J.data());
  }
}
void BM_base_nonholonomic(benchmark::State& st) {
  const Model model;
  baseline::Frames w;
  gen::WheelRows C;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    baseline::nonholonomic_rows(model.params(), s, C, w);
    benchmark::DoNotOptimize(C.data());
  }
}
void BM_base_convective(benchmark::State& st) {
  const Model model;
  baseline::Frames w;
  gen::ClosureVector phi;
  gen::WheelVector C;
  const Coordinates s = assembled_nominal(model);
  const Coordinates sdot = Coordinates::Constant(0.1);
  for (auto _ : st) {
    baseline::convective(model.params(), s, sdot, phi, C, w);
    benchmark::DoNotOptimize(C.data());
  }
}
void BM_base_body_jacobians(benchmark::State& st) {
  const Model model;
  baseline::Frames w;
  gen::BodyJacobians Jv, Jw;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    baseline::body_jacobians(model.params(), s, Jv, Jw, w);
    benchmark::DoNotOptimize(Jv.data());
  }
}
void BM_base_newton_cold(benchmark::State& st) {
  const Model model;
  baseline::Frames w;
  Coordinates start = assembled_nominal(model);
  start.head(kInputCount) = moved_target().head(kInputCount);
  for (auto _ : st) {
    Coordinates s = start;
    benchmark::DoNotOptimize(baseline::newton_ik(model.params(), s, w));
  }
}


#ifdef WLX_HAVE_KDL
// ---- Orocos KDL as a peer: the model's open tree built from the generated tables ----
// (bench/kdl_peer.hpp; tests/bench/test_kdl_peer.cpp checks that it computes the same values).
// Both sides get their inputs prepared outside the loop, as a controller holding them would.

// wlx: the bodies' CoM Jacobians Jv, Jw only (what KDL's tree Jacobian solver gives).
void BM_gen_body_jacobians(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model), no_rates = Coordinates::Zero();  // Jv, Jw do not read s'
  for (auto _ : st) {
    gen::bodies(s, no_rates, model.params(), {.Jv = &d.body_Jv, .Jw = &d.body_Jw}, false);
    benchmark::DoNotOptimize(d.body_Jv.data());
    benchmark::DoNotOptimize(d.body_Jw.data());
  }
}
// wlx: the open tree's inverse dynamics, Kane's sums over the generated body kinematics.
void BM_gen_open_tree_inverse_dynamics(benchmark::State& st) {
  const Model model;
  kdl_peer::OpenTreeWorkspace w;
  const Coordinates s = assembled_nominal(model), sdot = Coordinates::Constant(0.1), sddot = Coordinates::Constant(0.2);
  Coordinates Q;
  for (auto _ : st) {
    kdl_peer::open_tree_inverse_dynamics(model.params(), s, sdot, sddot, w, Q);
    benchmark::DoNotOptimize(Q.data());
  }
}
// KDL: every frame, by one recursive FK pass over each chain from K0 to an end frame.
void BM_kdl_fk_chains(benchmark::State& st) {
  const Model model;
  const kdl_peer::PeerTree peer = kdl_peer::build_tree(model.params());
  const Coordinates s = assembled_nominal(model);
  struct Pass {
    KDL::Chain chain;
    KDL::JntArray q;
    std::vector<KDL::Frame> frames;
  };
  std::vector<Pass> passes;
  for (int f : peer.end_frames) {
    Pass pass;
    peer.tree.getChain(kdl_peer::kRootName, kdl_peer::frame_name(f), pass.chain);
    pass.q.resize(pass.chain.getNrOfJoints());
    unsigned i = 0;
    for (const KDL::Segment& seg : pass.chain.segments)
      if (seg.getJoint().getType() != KDL::Joint::Fixed)
        pass.q(i++) = s(static_cast<int>(std::find(gen::kCoordinateNames.begin(), gen::kCoordinateNames.end(), seg.getJoint().getName()) -
                                         gen::kCoordinateNames.begin()));
    pass.frames.resize(pass.chain.getNrOfSegments());
    passes.push_back(std::move(pass));
  }
  std::vector<KDL::ChainFkSolverPos_recursive> solvers;
  for (const Pass& pass : passes) solvers.emplace_back(pass.chain);
  for (auto _ : st)
    for (std::size_t k = 0; k < passes.size(); ++k) {
      solvers[k].JntToCart(passes[k].q, passes[k].frames);
      benchmark::DoNotOptimize(passes[k].frames.data());
    }
}
void BM_kdl_body_jacobians(benchmark::State& st) {
  const Model model;
  const kdl_peer::PeerTree peer = kdl_peer::build_tree(model.params());
  KDL::TreeJntToJacSolver solver(peer.tree);
  const KDL::JntArray q = peer.joints(assembled_nominal(model));
  std::vector<KDL::Jacobian> J(gen::kBodyCount, KDL::Jacobian(peer.tree.getNrOfJoints()));
  std::vector<std::string> names;
  for (int b = 0; b < gen::kBodyCount; ++b) names.push_back(kdl_peer::body_com_name(b));
  for (auto _ : st)
    for (int b = 0; b < gen::kBodyCount; ++b) {
      solver.JntToJac(q, J[static_cast<std::size_t>(b)], names[static_cast<std::size_t>(b)]);
      benchmark::DoNotOptimize(J[static_cast<std::size_t>(b)].data.data());
    }
}
// KDL: the end frames' full Jacobians (6 x joints each), from which the closure's rows of those
// frames are taken; wlx's generated dPhi/ds holds only those rows (BM_gen_closure).
void BM_kdl_end_frame_jacobians(benchmark::State& st) {
  const Model model;
  const kdl_peer::PeerTree peer = kdl_peer::build_tree(model.params());
  KDL::TreeJntToJacSolver solver(peer.tree);
  const KDL::JntArray q = peer.joints(assembled_nominal(model));
  std::vector<KDL::Jacobian> J(peer.end_frames.size(), KDL::Jacobian(peer.tree.getNrOfJoints()));
  std::vector<std::string> names;
  for (int f : peer.end_frames) names.push_back(kdl_peer::frame_name(f));
  for (auto _ : st)
    for (std::size_t k = 0; k < names.size(); ++k) {
      solver.JntToJac(q, J[k], names[k]);
      benchmark::DoNotOptimize(J[k].data.data());
    }
}
void BM_kdl_tree_rne(benchmark::State& st) {
  const Model model;
  const kdl_peer::PeerTree peer = kdl_peer::build_tree(model.params());
  KDL::TreeIdSolver_RNE solver(peer.tree, peer.gravity);
  const KDL::JntArray q = peer.joints(assembled_nominal(model)), qdot = peer.joints(Coordinates::Constant(0.1)),
                      qddot = peer.joints(Coordinates::Constant(0.2));
  KDL::JntArray tau(peer.tree.getNrOfJoints());
  const KDL::WrenchMap no_external_forces;
  for (auto _ : st) {
    solver.CartToJnt(q, qdot, qddot, no_external_forces, tau);
    benchmark::DoNotOptimize(tau.data.data());
  }
}

// One leg's IK (the model's first limb): from the target inputs of moved_target(), cold (the
// nominal pose's joints) or warm (the solution 1 mm / 1 mrad of inputs away), as in the 4-limb rows.
constexpr Limb kLeg = 0;
Coordinates leg_start(const Model& model, bool warm) {
  Coordinates start;
  if (warm) {
    start = moved_target();
    start(gen::coord::x_Fl) -= 1e-3;
    start(gen::coord::z_Fl) -= 1e-3;
    solve_ik_closed_form(model, start);
  } else {
    start = assembled_nominal(model);
  }
  start.head(kInputCount) = moved_target().head(kInputCount);
  return start;
}
std::vector<int> leg_joints() {
  const LimbBlock block = limb_block(kLeg);
  return {block.joints.begin(), block.joints.begin() + block.size};
}
void BM_ik_closed_form_leg(benchmark::State& st) {
  const Model model;
  Coordinates s = moved_target();
  for (auto _ : st) {
    solve_limb_closed_form(model, kLeg, 0, s);
    benchmark::DoNotOptimize(s.data());
  }
}
template <bool warm>
void BM_ik_newton_leg(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates start = leg_start(model, warm);
  long iterations = 0;
  for (auto _ : st) {
    Coordinates s = start;
    iterations += solve_limb_newton(model, d, kLeg, s).iterations[kLeg];
    benchmark::DoNotOptimize(s.data());
  }
  st.counters["iterations"] = benchmark::Counter(static_cast<double>(iterations), benchmark::Counter::kAvgIterations);
}
// KDL's iterative solvers on the chain K0 -> the leg's end frame with the cabin pose and the leg's
// own inputs frozen (the leg's dependent joints free), aimed at the end frame of wlx's closed-form
// solution: LMA on its position (weights 1, 1, 1, 0, 0, 0), NR on the whole pose (reachable, so
// its least squares meets it). Tolerance 1e-12 instead of KDL's defaults (1e-5, 1e-6, which stop
// 1e-6 m short), near wlx's (closed form: rounding; Newton: 1e-13 on the residual): KDL's
// solutions then agree with the closed form to about 1e-15 (LMA) and 1e-13 (NR).
enum class KdlIk { lma, nr };
template <KdlIk method, bool warm>
void BM_kdl_ik_leg(benchmark::State& st) {
  const Model model;
  const kdl_peer::PeerTree peer = kdl_peer::build_tree(model.params());
  Coordinates solution = moved_target();
  solve_ik_closed_form(model, solution);
  const std::vector<int> joints = leg_joints();
  const int end = gen::kClosureRows[static_cast<std::size_t>(limb_block(kLeg).rows[0])].frame;
  const KDL::Chain chain = kdl_peer::frozen_chain(peer, end, joints, solution);
  KDL::ChainFkSolverPos_recursive fk(chain);
  const auto on_chain = [&](const Coordinates& s) {
    KDL::JntArray q(chain.getNrOfJoints());
    unsigned i = 0;
    for (const KDL::Segment& seg : chain.segments)
      if (seg.getJoint().getType() != KDL::Joint::Fixed)
        q(i++) = s(static_cast<int>(std::find(gen::kCoordinateNames.begin(), gen::kCoordinateNames.end(), seg.getJoint().getName()) -
                                    gen::kCoordinateNames.begin()));
    return q;
  };
  const KDL::JntArray q_solution = on_chain(solution), q_start = on_chain(leg_start(model, warm));
  KDL::Frame goal;
  fk.JntToCart(q_solution, goal);
  constexpr double kTolerance = 1e-12;
  Eigen::Matrix<double, 6, 1> position_only;
  position_only << 1, 1, 1, 0, 0, 0;
  KDL::ChainIkSolverPos_LMA lma(chain, position_only, kTolerance);
  KDL::ChainIkSolverVel_pinv velocity(chain);
  KDL::ChainIkSolverPos_NR nr(chain, fk, velocity, 100, kTolerance);
  KDL::JntArray q(chain.getNrOfJoints());
  const auto solve = [&] { return method == KdlIk::lma ? lma.CartToJnt(q_start, goal, q) : nr.CartToJnt(q_start, goal, q); };
  if (solve() < 0 || (q.data - q_solution.data).cwiseAbs().maxCoeff() > 1e-10) {
    st.SkipWithError("KDL's IK did not reach wlx's closed-form solution");
    return;
  }
  long iterations = 0;
  for (auto _ : st) {
    solve();
    iterations += lma.lastNrOfIter;  // NR does not report its count
    benchmark::DoNotOptimize(q.data.data());
  }
  if (method == KdlIk::lma)
    st.counters["iterations"] = benchmark::Counter(static_cast<double>(iterations), benchmark::Counter::kAvgIterations);
}
#endif
}  // namespace

BENCHMARK(BM_base_frames);
BENCHMARK(BM_base_closure_jacobian);
BENCHMARK(BM_base_nonholonomic);
BENCHMARK(BM_base_convective);
BENCHMARK(BM_base_body_jacobians);
BENCHMARK(BM_base_newton_cold);
BENCHMARK(BM_inverse_dynamics_step);
BENCHMARK(BM_inverse_dynamics_generated_only);
BENCHMARK(BM_distribute_torques);
BENCHMARK(BM_gen_dynamics_passes);
BENCHMARK(BM_gen_kane_sums);
BENCHMARK(BM_kane_sums_over_body_jacobians);
BENCHMARK(BM_run_ID1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_dependent_rates);
BENCHMARK(BM_dependent_accelerations);
BENCHMARK(BM_run_NH1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_gen_kinematics_positions);
BENCHMARK(BM_gen_kinematics_all);
BENCHMARK(BM_gen_closure);
BENCHMARK(BM_gen_nonholonomic);
BENCHMARK(BM_gen_convective);
BENCHMARK(BM_gen_bodies);
BENCHMARK(BM_gen_kinematic_update_fused<false>)->Name("BM_gen_kinematic_update_fused");
BENCHMARK(BM_gen_kinematic_update_fused<true>)->Name("BM_gen_kinematic_update_fused_zero_fill");
BENCHMARK(BM_gen_kinematic_update_fused_random_poses);
BENCHMARK(BM_gen_kinematic_update_separate);
BENCHMARK(BM_full_kinematic_update);
BENCHMARK(BM_ik_closed_form_4_limbs);
BENCHMARK(BM_ik_newton_cold_4_limbs);
BENCHMARK(BM_ik_newton_warm_4_limbs);
#ifdef WLX_HAVE_KDL
BENCHMARK(BM_gen_body_jacobians);
BENCHMARK(BM_gen_open_tree_inverse_dynamics);
BENCHMARK(BM_kdl_fk_chains);
BENCHMARK(BM_kdl_body_jacobians);
BENCHMARK(BM_kdl_end_frame_jacobians);
BENCHMARK(BM_kdl_tree_rne);
BENCHMARK(BM_ik_closed_form_leg);
BENCHMARK(BM_ik_newton_leg<false>)->Name("BM_ik_newton_leg_cold");
BENCHMARK(BM_ik_newton_leg<true>)->Name("BM_ik_newton_leg_warm");
BENCHMARK(BM_kdl_ik_leg<KdlIk::lma, false>)->Name("BM_kdl_ik_lma_cold");
BENCHMARK(BM_kdl_ik_leg<KdlIk::lma, true>)->Name("BM_kdl_ik_lma_warm");
BENCHMARK(BM_kdl_ik_leg<KdlIk::nr, false>)->Name("BM_kdl_ik_nr_cold");
BENCHMARK(BM_kdl_ik_leg<KdlIk::nr, true>)->Name("BM_kdl_ik_nr_warm");
#endif
namespace {

// Collects the median of the repetitions of every benchmark, in nanoseconds.
class MedianCollector : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& r : runs)
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name == "median")
        median_ns[r.run_name.function_name] = r.GetAdjustedRealTime() * to_ns(r.time_unit);
  }
  static double to_ns(benchmark::TimeUnit u) {
    switch (u) {
      case benchmark::kNanosecond: return 1;
      case benchmark::kMicrosecond: return 1e3;
      case benchmark::kMillisecond: return 1e6;
      case benchmark::kSecond: return 1e9;
    }
    return 1;
  }
  std::map<std::string, double> median_ns;
};

struct Row {
  const char* what;
  const char* generated;  // benchmark name
  const char* baseline;   // benchmark name, or nullptr
  long ops;               // operations of the generated function, or 0
  const char* peer = nullptr;  // the baseline's library (a peer: "Orocos KDL", "MuJoCo 2.2.2"), not our numeric baseline
  const char* group = nullptr;  // a heading for the rows from here on (JSON "group")
};

}  // namespace

// Runs the suite (5 repetitions each) and prints one table: operation, median ns per call, the
// numeric baseline and the ratio measured in the same run, and the generated op counts.
// --json prints the same as JSON; --rows runs each benchmark twice (the fewest repetitions with a
// median) and briefly, for a check of the table's rows and operation counts (tools/docs_contract.py:
// 0.2 s instead of 38 s). Other arguments go to Google Benchmark (e.g. --benchmark_filter).
int main(int argc, char** argv) {
  bool json = false, rows_only = false;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) json = true;
    else if (std::strcmp(argv[i], "--rows") == 0) rows_only = true;
    else args.push_back(argv[i]);
    if (std::strcmp(argv[i], "--help") == 0)
      fmt::print("wlx_bench [--json] [--rows] [Google Benchmark options]: runs the suite (5 repetitions each) and prints one\n"
                 "table of medians, the numeric baseline and their ratio measured in the same run, and the generated op counts.\n"
                 "  --json  the same table as JSON\n"
                 "  --rows  each benchmark once and briefly: the table's rows and op counts, its times meaningless\n\n"
                 "Google Benchmark's options:\n");
  }
  std::string reps = rows_only ? "--benchmark_repetitions=2" : "--benchmark_repetitions=5";
  std::string min_time = rows_only ? "--benchmark_min_time=0.000001" : "--benchmark_min_time=0.05";
  args.push_back(reps.data());
  args.push_back(min_time.data());
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  MedianCollector collector;
  benchmark::RunSpecifiedBenchmarks(&collector);
  namespace ops = wlx::gen::operations;
  std::vector<Row> rows = {
      // Orocos KDL, the peer (built with KDL only): first, as the README's table shows them.
      {"KDL peer: FK of all frames (KDL: chain FK to each end frame)", "BM_gen_kinematics_all", "BM_kdl_fk_chains", ops::kinematics, "Orocos KDL"},
      {"KDL peer: bodies' CoM Jacobians Jv, Jw (KDL: tree Jacobians)", "BM_gen_body_jacobians", "BM_kdl_body_jacobians", 0, "Orocos KDL"},
      {"KDL peer: end frames' Jacobians (wlx: their dPhi/ds rows)", "BM_gen_closure", "BM_kdl_end_frame_jacobians", ops::closure, "Orocos KDL"},
      {"KDL peer: open-tree inverse dynamics (KDL: tree RNE)", "BM_gen_open_tree_inverse_dynamics", "BM_kdl_tree_rne", 0, "Orocos KDL"},
      {"KDL peer: leg IK closed form vs KDL LMA, cold", "BM_ik_closed_form_leg", "BM_kdl_ik_lma_cold", 0, "Orocos KDL"},
      {"KDL peer: leg IK closed form vs KDL LMA, warm", "BM_ik_closed_form_leg", "BM_kdl_ik_lma_warm", 0, "Orocos KDL"},
      {"KDL peer: leg IK closed form vs KDL NR, cold", "BM_ik_closed_form_leg", "BM_kdl_ik_nr_cold", 0, "Orocos KDL"},
      {"KDL peer: leg IK closed form vs KDL NR, warm", "BM_ik_closed_form_leg", "BM_kdl_ik_nr_warm", 0, "Orocos KDL"},
      {"KDL peer: leg IK Newton vs KDL NR, cold", "BM_ik_newton_leg_cold", "BM_kdl_ik_nr_cold", 0, "Orocos KDL"},
      {"KDL peer: leg IK Newton vs KDL NR, warm", "BM_ik_newton_leg_warm", "BM_kdl_ik_nr_warm", 0, "Orocos KDL"},
      {"FK of 13 frames (positions + rotations)", "BM_gen_kinematics_all", "BM_base_frames", ops::kinematics},
      {"FK positions only", "BM_gen_kinematics_positions", nullptr, 0},
      {"Phi + dPhi/ds (14 x 32)", "BM_gen_closure", "BM_base_closure_jacobian", ops::closure},
      {"non-holonomic rows C(s) + spin rows", "BM_gen_nonholonomic", "BM_base_nonholonomic", ops::nonholonomic},
      {"convective terms (dPhi/ds)' s', C' s'", "BM_gen_convective", "BM_base_convective", ops::convective},
      {"7 bodies: CoM, R, Jv, Jw, convective", "BM_gen_bodies", "BM_base_body_jacobians", ops::bodies},
      {"fused FK + Phi + dPhi/ds + C(s)", "BM_gen_kinematic_update_fused", "BM_gen_kinematic_update_separate", ops::kinematic_update},
      {"  the same, rewriting structural zeros", "BM_gen_kinematic_update_fused_zero_fill", nullptr, ops::kinematic_update},
      {"  the same, 64 random poses in turn", "BM_gen_kinematic_update_fused_random_poses", nullptr, ops::kinematic_update},
      {"full kinematic update (4-limb IK + fused)", "BM_full_kinematic_update", nullptr, 0},
      {"IK closed form, 4 limbs (vs Newton, cold)", "BM_ik_closed_form_4_limbs", "BM_ik_newton_cold_4_limbs", 0},
      {"IK closed form, 4 limbs (vs Newton, warm)", "BM_ik_closed_form_4_limbs", "BM_ik_newton_warm_4_limbs", 0},
      {"IK Newton (generated J), cold start", "BM_ik_newton_cold_4_limbs", "BM_base_newton_cold", 0},
      {"IK Newton (generated J), warm start", "BM_ik_newton_warm_4_limbs", nullptr, 0},
      {"dependent rates (velocity level)", "BM_dependent_rates", nullptr, 0},
      {"dependent accelerations", "BM_dependent_accelerations", nullptr, 0},
      {"inverse-dynamics step", "BM_inverse_dynamics_step", nullptr, 0},
      {"  its torque split alone (weighted least norm, QR)", "BM_distribute_torques", nullptr, 0},
      {"  its generated code alone: 4-limb IK + the three passes", "BM_inverse_dynamics_generated_only", nullptr, 0},
      {"  the three passes: dynamics_update, convective, generalized_forces (Newton-Euler)", "BM_gen_dynamics_passes", nullptr,
       ops::dynamics_update + ops::convective + ops::generalized_forces},
      {"  reduced_dynamics, M b B_bias Q_gravity (vs Kane's sums over bodies()' Jacobians)", "BM_gen_kane_sums",
       "BM_kane_sums_over_body_jacobians", 0},
      {"NH-1 run (2001 samples, RK4)", "BM_run_NH1", nullptr, 0},
      {"ID-1 run (495 samples, RK4, torques)", "BM_run_ID1", nullptr, 0},
  };
  // The rows every model gets (bench/bench_any_model.cpp: <model>/<row>), side by side: each
  // model's against the first model's (the excavator's) in the same run, so that the ratio, not
  // the machine, is what is read.
  std::deque<std::string> texts;  // stable storage for the rows' strings
  {
    std::vector<std::string> models;
    for (const auto& [name, ns] : collector.median_ns) {
      const auto slash = name.find('/');
      if (slash == std::string::npos || name.rfind("BM_", 0) == 0) continue;
      if (std::find(models.begin(), models.end(), name.substr(0, slash)) == models.end()) models.push_back(name.substr(0, slash));
    }
    // The excavator first (the reference), the others in name order.
    std::sort(models.begin(), models.end(), [](const std::string& a, const std::string& b) {
      return (a == "excavator") != (b == "excavator") ? a == "excavator" : a < b;
    });
    bool first = true;
    for (const std::string& suffix : {std::string("ik_all_limbs"), std::string("fk_1000_states"), std::string("dependent_rates"),
                                      std::string("inverse_dynamics_step"), std::string("inverse_dynamics_step_by_kane"),
                                      std::string("forward_dynamics_step")}) {
      if (models.empty()) break;  // (a --benchmark_filter without them)
      const std::string reference = models.front() + "/" + suffix;
      for (const std::string& model : models) {
        const std::string name = model + "/" + suffix;
        if (!collector.median_ns.count(name)) continue;
        const char* what = texts.emplace_back(fmt::format("{}: {}", model, suffix)).c_str();
        const char* generated = texts.emplace_back(name).c_str();
        const char* baseline = model == models.front() ? nullptr : texts.emplace_back(reference).c_str();
        rows.push_back({what, generated, baseline, 0, nullptr,
                        first ? "every model, side by side (speedup: the first model's time over this one's)" : nullptr});
        first = false;
      }
    }
    // The target for forward dynamics: no dearer than an inverse-dynamics step of the
    // same model (speedup >= 1: the forward step is the cheaper).
    bool first_pair = true;
    for (const std::string& model : models) {
      const std::string forward = model + "/forward_dynamics_step", inverse = model + "/inverse_dynamics_step";
      if (!collector.median_ns.count(forward) || !collector.median_ns.count(inverse)) continue;
      rows.push_back({texts.emplace_back(fmt::format("{}: forward_dynamics_step vs its inverse_dynamics_step", model)).c_str(),
                      texts.emplace_back(forward).c_str(), texts.emplace_back(inverse).c_str(), 0, nullptr,
                      first_pair ? "each model's forward-dynamics step against its own inverse-dynamics step (speedup: inverse / forward)"
                                 : nullptr});
      first_pair = false;
    }
    // A body's Jacobian columns from its joints' twists (6 numbers per joint, gen::joint_jacobian)
    // against the bodies' own (3 x n per body and Jacobian, bodies()).
    bool first_jacobian = true;
    for (const std::string& model : models) {
      const std::string joints = model + "/joint_jacobian", bodies = model + "/body_jacobians";
      if (!collector.median_ns.count(joints) || !collector.median_ns.count(bodies)) continue;
      rows.push_back({texts.emplace_back(fmt::format("{}: joint_jacobian vs body_jacobians", model)).c_str(), texts.emplace_back(joints).c_str(),
                      texts.emplace_back(bodies).c_str(), 0, nullptr,
                      first_jacobian ? "the joints' twists in K0 against every body's CoM Jacobians and pose (speedup: bodies / joints)" : nullptr});
      first_jacobian = false;
    }
    // A peer library's rows beside wlx's, per model: (wlx's row, the peer's row, what they compute).
    using PeerRows = std::initializer_list<std::tuple<const char*, const char*, const char*>>;
    const auto peer_rows = [&](const char* peer_name, const char* label, const char* group, PeerRows pairs) {
      bool first_row = true;
      for (const std::string& model : models)
        for (const auto& [ours, theirs, what] : pairs) {
          const std::string mine = model + "/" + ours, peer = model + "/" + theirs;
          if (!collector.median_ns.count(mine) || !collector.median_ns.count(peer)) continue;
          rows.push_back({texts.emplace_back(fmt::format("{}: {}: {}", label, model, what)).c_str(), texts.emplace_back(mine).c_str(),
                          texts.emplace_back(peer).c_str(), 0, peer_name, first_row ? group : nullptr});
          first_row = false;
        }
    };
    // MuJoCo (built with libmujoco-dev), on each model exported by `wlx export mjcf`: the same
    // quantity in both, but for the mass matrix (wlx's on the commanded speeds, MuJoCo's on the
    // open tree) and the step (wlx's constrained forward dynamics; MuJoCo's contacts, solver and
    // integration of 1 ms).
    peer_rows("MuJoCo 2.2.2", "MuJoCo peer", "MuJoCo on the same machine (`wlx export mjcf`; speedup: MuJoCo's time over wlx's)",
              {{"fk_all_frames", "mujoco_kinematics", "FK of all frames (MuJoCo: mj_kinematics)"},
               {"open_tree_inverse_dynamics", "mujoco_rne", "open-tree inverse dynamics (MuJoCo: kinematics, com, velocities, mj_rne)"},
               {"equations_of_motion", "mujoco_crb", "M, b on the commanded speeds (MuJoCo: open-tree M, mj_crb)"},
               {"forward_dynamics_step", "mujoco_step", "forward-dynamics step (MuJoCo: mj_step of 1 ms on the ground)"}});
    // Pinocchio 3 (-DWLX_PINOCCHIO_DIR: bench/pinocchio_peer.cpp), on the model's URDF loaded by its
    // own parser with a free flyer: the same quantity but for the mass matrix (wlx's M on the
    // commanded speeds, alone and with b and the dependent rates; Pinocchio's M of the open tree),
    // the forward step (wlx's constrained one; Pinocchio's aba on the open tree) and the Jacobians
    // (wlx's of every body at its centre of mass; Pinocchio's of every joint).
#ifdef WLX_PINOCCHIO_VERSION
    const char* const pinocchio = "Pinocchio " WLX_PINOCCHIO_VERSION;
#else
    const char* const pinocchio = "Pinocchio";
#endif
    peer_rows(pinocchio, "Pinocchio peer", "Pinocchio on the same machine (the model's URDF; speedup: Pinocchio's time over wlx's)",
              {{"fk_all_frames", "pinocchio_fk", "FK of all frames (Pinocchio: framesForwardKinematics)"},
               {"open_tree_inverse_dynamics", "pinocchio_rnea", "open-tree inverse dynamics by Kane's sums over the bodies' Jacobians (Pinocchio: rnea)"},
               {"newton_euler", "pinocchio_rnea", "open-tree inverse dynamics by the generated Newton-Euler pass (Pinocchio: rnea)"},
               {"mass_matrix", "pinocchio_crba", "M on the commanded speeds, reduced_dynamics alone (Pinocchio: the open tree's M, crba)"},
               {"equations_of_motion", "pinocchio_crba", "M, b on the commanded speeds, with the dependent rates (Pinocchio: the open tree's M, crba)"},
               {"forward_dynamics_step", "pinocchio_aba", "constrained forward-dynamics step (Pinocchio: the open tree's aba)"},
               {"joint_jacobian", "pinocchio_jacobians", "joint Jacobians, a twist per joint in K0 (Pinocchio: computeJointJacobians)"},
               {"body_jacobians", "pinocchio_jacobians", "bodies' CoM Jacobians, 3 x n per body (Pinocchio: computeJointJacobians)"}});
  }
  const auto get = [&](const char* name) {
    const auto it = collector.median_ns.find(name);
    return it == collector.median_ns.end() ? -1.0 : it->second;
  };
  if (json) {
    std::string out = "[\n";
    bool first = true;
    const char* group = nullptr;
    for (const Row& r : rows) {
      const double g = get(r.generated), b = r.baseline ? get(r.baseline) : -1;
      if (g < 0 || (r.peer && b < 0)) continue;
      out += fmt::format("{}  {{\"operation\": \"{}\", \"ns\": {:.1f}", first ? "" : ",\n", r.what, g);
      if (r.group != nullptr) group = r.group;
      if (group != nullptr) out += fmt::format(", \"group\": \"{}\"", group);
      if (b > 0) out += fmt::format(", \"baseline\": \"{}\", \"baseline_ns\": {:.1f}, \"speedup\": {:.2f}", r.baseline, b, b / g);
      if (r.peer) out += fmt::format(", \"peer\": \"{}\"", r.peer);
      if (r.ops > 0) out += fmt::format(", \"ops\": {}, \"ns_per_op\": {:.3f}", r.ops, g / static_cast<double>(r.ops));
      out += "}";
      first = false;
    }
    fmt::print("{}\n]\n", out);
    return 0;
  }
  fmt::print("\n{:<62} {:>11} {:>34} {:>9} {:>7} {:>7}\n", "operation", "ns/call", "baseline (ns/call)", "speedup", "ops",
             "ns/op");
  for (const Row& r : rows) {
    const double g = get(r.generated);
    const double b = r.baseline ? get(r.baseline) : -1;
    if (g < 0 || (r.peer && b < 0)) continue;
    if (r.group != nullptr) fmt::print("{}\n", r.group);
    std::string baseline_name = r.baseline ? r.baseline : "";
    if (baseline_name.rfind("BM_", 0) == 0) baseline_name.erase(0, 3);
    const std::string base = b > 0 ? fmt::format("{} {:.0f}", baseline_name, b) : "";
    fmt::print("{:<62} {:>11.1f} {:>34} {:>9} {:>7} {:>7}\n", r.what, g, base, b > 0 ? fmt::format("{:.1f}x", b / g) : "",
               r.ops > 0 ? std::to_string(r.ops) : "", r.ops > 0 ? fmt::format("{:.3f}", g / static_cast<double>(r.ops)) : "");
  }
  fmt::print("\nmedians of 5 repetitions, one run; speedup = baseline (Orocos KDL in the \"KDL peer\" rows, MuJoCo in the\n"
             "\"MuJoCo peer\" rows, else the numeric baseline) / wlx, measured side by side\n");
  return 0;
}
