// The same benchmarks for every model it is compiled for (CMakeLists.txt: once per model in
// WLX_BENCH_MODELS, linked into wlx_bench), registered as <model>/<row>, so that models of other
// sizes are compared side by side in one run: the IK of every limb, the dependent rates, and one
// inverse-dynamics step (IK, rates, the Newton-Euler pass, the torque split; and the same by Kane's
// sums) and one forward-dynamics step, and what the contacts add to an inverse-dynamics step (the
// forces, the margins, the momentum check, weighting 3), from the model's tables alone. With MuJoCo
// (WLX_HAVE_MUJOCO), the same machine exported by `wlx export mjcf` beside them: its kinematics,
// open-tree inverse dynamics, mass matrix and one simulation step (tests/bench/test_mujoco_peer.cpp
// checks that it computes the same values).
#include <benchmark/benchmark.h>
#include <wlx/contacts.hpp>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/forward_dynamics.hpp>
#include <wlx/ik.hpp>
#include <wlx/nonholonomic.hpp>

#include <memory>
#include <random>
#include <string>
#include <vector>

#ifdef WLX_PINOCCHIO_URDF
#include "pinocchio_peer.hpp"
#endif
#ifdef WLX_HAVE_MUJOCO
#include "mjcf_export.hpp"
#include "mujoco_model.hpp"
#include "physics_engine.hpp"
#include "open_tree.hpp"

#include <fstream>
#include <sstream>
#endif

namespace {

using namespace wlx;

// The nominal pose as the model file means it: its limbs solved by Newton's method from the file's
// start values, then each closed-form limb kept on the branch that solution lies on (a closed
// form's branch 0 may be another configuration, a singular one for a wheeled leg). Every commanded
// speed at 0.2 (m/s or rad/s).
struct Pose {
  const Model model;
  Data d;
  DynamicsTerms terms;
  Coordinates s = nominal_inputs();
  CommandVector u = CommandVector::Constant(0.2);
  Branches branches;
  Pose() {
    std::array<bool, kLimbCount> all;
    all.fill(true);
    s = dependent_start(s);
    solve_newton_limbs(model, d, all, s);
    for (Limb limb : kLimbs)
      if (gen::kClosedForm[static_cast<std::size_t>(limb)].solve != nullptr)
        branches.limb[static_cast<std::size_t>(limb)] = classify_branch(model, limb, s);
    solve_ik_closed_form(model, s, branches);
  }
};

void ik(benchmark::State& st) {
  auto x = std::make_unique<Pose>();
  for (auto _ : st) {
    solve_ik_closed_form(x->model, x->s, x->branches);
    benchmark::DoNotOptimize(x->s.data());
  }
}

// FK of all frames over 1000 states near the nominal pose (every coordinate off by 1 mm or 1 mrad
// at random, seeded), each output kept: what one call over an array costs (Python's m.fk(S),
// tools/python_speed.py), where the same state called again flatters the generated trigonometry.
void fk_1000_states(benchmark::State& st) {
  auto x = std::make_unique<Pose>();
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 1e-3);
  std::vector<Coordinates> states(1000, x->s);
  for (auto& s : states)
    for (int k = 0; k < kCoordinateCount; ++k) s(k) += noise(rng);
  std::vector<gen::FramePositions> positions(states.size());
  std::vector<gen::FrameRotations> rotations(states.size());
  for (auto _ : st) {
    for (std::size_t i = 0; i < states.size(); ++i)
      gen::kinematics(states[i], x->model.params(), {.positions = &positions[i], .rotations = &rotations[i]});
    benchmark::DoNotOptimize(positions.data());
    benchmark::ClobberMemory();
  }
}

void dependent_rates(benchmark::State& st) {
  auto x = std::make_unique<Pose>();
  Coordinates sdot = Coordinates::Zero();
  for (int k = 0; k < kCommandedCount; ++k) sdot(kCommandedSpeeds[static_cast<std::size_t>(k)]) = x->u(k);
  for (auto _ : st) {
    solve_dependent_rates(x->model, x->d, x->s, sdot, dynamics_pair());
    benchmark::DoNotOptimize(sdot.data());
  }
}

void inverse_dynamics_step(benchmark::State& st) {
  auto x = std::make_unique<Pose>();
  for (auto _ : st) {
    solve_ik_closed_form(x->model, x->s, x->branches);
    inverse_dynamics(x->model, x->d, x->s, x->u, CommandVector::Zero(), x->terms);
    const TorqueVector tau = distribute_torques(x->terms.J_beta, x->terms.Qstar, Weighting::model_weights());
    benchmark::DoNotOptimize(tau.data());
  }
}

// The same step with Q* from the equations of motion (M u' + b - Q_gravity, reduced_dynamics on
// the commanded speeds) instead of the Newton-Euler pass: what the step cost before, and
// what it costs a user who also wants M.
void inverse_dynamics_step_by_kane(benchmark::State& st) {
  auto x = std::make_unique<Pose>();
  const CommandVector u_dot = CommandVector::Zero();
  for (auto _ : st) {
    solve_ik_closed_form(x->model, x->s, x->branches);
    equations_of_motion(x->model, x->d, x->s, x->u, x->terms);
    x->terms.Qstar.noalias() = x->terms.M * u_dot + x->terms.b - x->terms.Q_gravity;
    const TorqueVector tau = distribute_torques(x->terms.J_beta, x->terms.Qstar, Weighting::model_weights());
    benchmark::DoNotOptimize(tau.data());
  }
}

// The converse step, side by side with the one above: IK, then the accelerations under the
// torques that hold the nominal pose (one inverse-dynamics evaluation and a Cholesky of M).
void forward_dynamics_step(benchmark::State& st) {
  auto x = std::make_unique<Pose>();
  inverse_dynamics(x->model, x->d, x->s, x->u, CommandVector::Zero(), x->terms);
  const TorqueVector tau = distribute_torques(x->terms.J_beta, x->terms.Qstar, Weighting::model_weights());
  CommandVector u_dot;
  for (auto _ : st) {
    solve_ik_closed_form(x->model, x->s, x->branches);
    forward_dynamics(x->model, x->d, x->s, x->u, tau, u_dot, x->terms);
    benchmark::DoNotOptimize(u_dot.data());
  }
}

// The contacts of an inverse-dynamics step, each part alone after the step (its factorizations
// current): the forces (multipliers), the support polygon and margins, the momentum check by the
// bodies' accelerations, and weighting 3 (its cutting-plane programmes), against the step itself.
struct ContactStep : Pose {
  TorqueVector tau;
  ContactForces forces;
  Stability stability;
  ContactStep() {
    inverse_dynamics(model, d, s, u, CommandVector::Zero(), terms);
    tau = distribute_torques(terms.J_beta, terms.Qstar, Weighting::model_weights());
    contact_forces(model, d, s, terms, tau, forces);
  }
};
void contact_forces_part(benchmark::State& st) {
  auto x = std::make_unique<ContactStep>();
  for (auto _ : st) {
    contact_forces(x->model, x->d, x->s, x->terms, x->tau, x->forces);
    benchmark::DoNotOptimize(x->forces.normal.data());
  }
}
void contact_margins_part(benchmark::State& st) {
  auto x = std::make_unique<ContactStep>();
  for (auto _ : st) {
    stability(x->model, x->d, x->s, x->forces, x->stability);
    benchmark::DoNotOptimize(&x->stability.tip_angle);
  }
}
void momentum_check_part(benchmark::State& st) {
  auto x = std::make_unique<ContactStep>();
  for (auto _ : st) {
    const MomentumBalance b = momentum_balance(x->model, x->d, x->s, x->terms.sdot, x->terms.sddot, x->forces);
    benchmark::DoNotOptimize(&b);
  }
}
void weighting_3_part(benchmark::State& st) {
  auto x = std::make_unique<ContactStep>();
  for (auto _ : st) {
    const ContactDistribution r = distribute_torques_on_contacts(x->model, x->d, x->s, x->terms);
    benchmark::DoNotOptimize(r.tau.data());
  }
}

#ifdef WLX_PINOCCHIO_URDF
// The generated kernels alone at the nominal pose, its rates s' = T u and s'' = 0.2 on every
// coordinate: the Newton-Euler pass's tau (generalized_forces, the open tree's inverse dynamics
// where every joint that carries a body moves, as on the wheeled quadruped) and M on the
// commanded speeds (reduced_dynamics), beside Pinocchio's rnea and crba.
struct KernelPose : Pose {
  gen::Coordinates sddot = gen::Coordinates::Constant(0.2), tau;
  CommandMatrix M;
  KernelPose() { equations_of_motion(model, d, s, u, terms); }
};
void newton_euler(benchmark::State& st) {
  auto x = std::make_unique<KernelPose>();
  for (auto _ : st) {
    gen::generalized_forces(x->s, x->terms.sdot, x->sddot, x->terms.T, x->model.params(), {.tau = &x->tau});
    benchmark::DoNotOptimize(x->tau.data());
  }
}
void mass_matrix(benchmark::State& st) {
  auto x = std::make_unique<KernelPose>();
  for (auto _ : st) {
    gen::reduced_dynamics(x->s, x->terms.sdot, x->terms.T, x->model.params(), {.M = &x->M}, false);
    benchmark::DoNotOptimize(x->M.data());
  }
}
#endif

// Every body's Jacobians (linear at its centre of mass, angular), with its pose, at the nominal
// pose: what Pinocchio's computeJointJacobians gives per joint (with the joints' placements).
void body_jacobians(benchmark::State& st) {
  auto x = std::make_unique<Pose>();
  const Coordinates sdot = Coordinates::Zero();  // (read only for the convective terms, not asked for)
  gen::BodyVectors com;
  gen::BodyRotations rotations;
  gen::BodyJacobians Jv, Jw;
  for (auto& J : Jv) J.setZero();
  for (auto& J : Jw) J.setZero();
  for (auto _ : st) {
    gen::bodies(x->s, sdot, x->model.params(), {.com = &com, .rotations = &rotations, .Jv = &Jv, .Jw = &Jw}, false);
    benchmark::DoNotOptimize(Jv.data());
  }
}
// Every coordinate's joint as a twist in K0 (gen::joint_jacobian), at the same pose:
// what Pinocchio's computeJointJacobians returns (6 numbers per joint), from which any body's
// Jacobian column is v + omega x c.
void joint_jacobian(benchmark::State& st) {
  auto x = std::make_unique<Pose>();
  gen::JointJacobian J = gen::JointJacobian::Zero();
  for (auto _ : st) {
    gen::joint_jacobian(x->s, x->model.params(), {.J = &J}, false);
    benchmark::DoNotOptimize(J.data());
  }
}

#ifdef WLX_HAVE_MUJOCO
// The nominal pose in MuJoCo too: the exported model at the same coordinates, rates 0.1 and
// accelerations 0.2 (per coordinate; what MuJoCo's free joint and wheel spins make of them).
struct MujocoPose : Pose {
  cli::MjModelPtr m;
  cli::MjDataPtr md;
  Coordinates sdot = Coordinates::Constant(0.1), sddot = Coordinates::Constant(0.2);
  std::vector<double> qpos, qvel;
  MujocoPose() {
    // The model's branches, within the joints' ranges (MuJoCo's joint limits would act otherwise).
    solve_ik_closed_form(model, s);
    std::ifstream in(WLX_DESCRIPTION_FILE);
    std::stringstream text;
    text << in.rdbuf();
    m = cli::load_mjcf(cli::mjcf_of_description(text.str()).xml);
    md.reset(mj_makeData(m.get()));
    const cli::PhysicsEngine engine(text.str(), std::vector<std::string>(gen::kCoordinateNames.begin(), gen::kCoordinateNames.end()));
    const cli::EngineMapping map = engine.mapping(s, sdot);
    const Eigen::VectorXd v = map.G * sdot, a = map.G * sddot + map.Gdot_sdot;
    for (int i = 0; i < m->nq; ++i) md->qpos[i] = map.qpos(i);
    for (int i = 0; i < m->nv; ++i) md->qvel[i] = v(i), md->qacc[i] = a(i);
    qpos.assign(md->qpos, md->qpos + m->nq);
    qvel.assign(md->qvel, md->qvel + m->nv);
  }
};

void fk_all_frames(benchmark::State& st) {
  auto x = std::make_unique<MujocoPose>();
  gen::FramePositions positions;
  gen::FrameRotations rotations;
  for (auto _ : st) {
    gen::kinematics(x->s, x->model.params(), {.positions = &positions, .rotations = &rotations});
    benchmark::DoNotOptimize(positions.data());
  }
}
void mujoco_kinematics(benchmark::State& st) {
  auto x = std::make_unique<MujocoPose>();
  for (auto _ : st) {
    mj_kinematics(x->m.get(), x->md.get());
    benchmark::DoNotOptimize(x->md->xpos);
  }
}
void open_tree_inverse_dynamics(benchmark::State& st) {
  auto x = std::make_unique<MujocoPose>();
  open_tree::OpenTreeWorkspace w;
  Coordinates Q;
  for (auto _ : st) {
    open_tree::open_tree_inverse_dynamics(x->model.params(), x->s, x->sdot, x->sddot, w, Q);
    benchmark::DoNotOptimize(Q.data());
  }
}
// What MuJoCo needs for the same torques from the state: positions, the bodies' inertias in the
// CoM frames, velocities, then the recursive Newton-Euler pass.
void mujoco_rne(benchmark::State& st) {
  auto x = std::make_unique<MujocoPose>();
  std::vector<mjtNum> tau(static_cast<std::size_t>(x->m->nv));
  for (auto _ : st) {
    mj_kinematics(x->m.get(), x->md.get());
    mj_comPos(x->m.get(), x->md.get());
    mj_comVel(x->m.get(), x->md.get());
    mj_rne(x->m.get(), x->md.get(), 1, tau.data());
    benchmark::DoNotOptimize(tau.data());
  }
}
// wlx's M and b on the commanded speeds (the constrained machine) against MuJoCo's composite
// rigid-body pass for the open tree's M.
void equations_of_motion_step(benchmark::State& st) {
  auto x = std::make_unique<MujocoPose>();
  for (auto _ : st) {
    equations_of_motion(x->model, x->d, x->s, x->u, x->terms);
    benchmark::DoNotOptimize(x->terms.M.data());
  }
}
void mujoco_crb(benchmark::State& st) {
  auto x = std::make_unique<MujocoPose>();
  for (auto _ : st) {
    mj_kinematics(x->m.get(), x->md.get());
    mj_comPos(x->m.get(), x->md.get());
    mj_crb(x->m.get(), x->md.get());
    benchmark::DoNotOptimize(x->md->qM);
  }
}
// One MuJoCo step of 1 ms from the nominal pose on the ground (contacts, the constraint solver,
// the integrator), beside wlx's forward-dynamics step (exact rolling and contacts, no integration).
void mujoco_step(benchmark::State& st) {
  auto x = std::make_unique<MujocoPose>();
  for (auto _ : st) {
    std::copy(x->qpos.begin(), x->qpos.end(), x->md->qpos);
    std::copy(x->qvel.begin(), x->qvel.end(), x->md->qvel);
    mj_step(x->m.get(), x->md.get());
    benchmark::DoNotOptimize(x->md->qacc);
  }
}
#endif

const bool registered = [] {
  const std::string model(gen::kModelName);
  benchmark::RegisterBenchmark((model + "/ik_all_limbs").c_str(), ik);
  benchmark::RegisterBenchmark((model + "/fk_1000_states").c_str(), fk_1000_states);
  benchmark::RegisterBenchmark((model + "/body_jacobians").c_str(), body_jacobians);
  benchmark::RegisterBenchmark((model + "/joint_jacobian").c_str(), joint_jacobian);
  if (gen::kHasDynamics) {
    benchmark::RegisterBenchmark((model + "/dependent_rates").c_str(), dependent_rates);
    benchmark::RegisterBenchmark((model + "/inverse_dynamics_step").c_str(), inverse_dynamics_step);
    benchmark::RegisterBenchmark((model + "/inverse_dynamics_step_by_kane").c_str(), inverse_dynamics_step_by_kane);
    benchmark::RegisterBenchmark((model + "/forward_dynamics_step").c_str(), forward_dynamics_step);
    if (kContactCount > 0) {
      benchmark::RegisterBenchmark((model + "/contact_forces").c_str(), contact_forces_part);
      benchmark::RegisterBenchmark((model + "/contact_margins").c_str(), contact_margins_part);
      benchmark::RegisterBenchmark((model + "/momentum_check").c_str(), momentum_check_part);
      benchmark::RegisterBenchmark((model + "/weighting_3").c_str(), weighting_3_part);
    }
  }
#ifdef WLX_PINOCCHIO_URDF
  // Pinocchio on this model's URDF (bench/pinocchio_peer.cpp).
  wlx_peer::register_pinocchio_benchmarks(model, WLX_PINOCCHIO_URDF);
  if (gen::kHasDynamics) {
    benchmark::RegisterBenchmark((model + "/newton_euler").c_str(), newton_euler);
    benchmark::RegisterBenchmark((model + "/mass_matrix").c_str(), mass_matrix);
  }
#endif
#ifdef WLX_HAVE_MUJOCO
  benchmark::RegisterBenchmark((model + "/fk_all_frames").c_str(), fk_all_frames);
  benchmark::RegisterBenchmark((model + "/mujoco_kinematics").c_str(), mujoco_kinematics);
  if (gen::kHasDynamics) {
    benchmark::RegisterBenchmark((model + "/open_tree_inverse_dynamics").c_str(), open_tree_inverse_dynamics);
    benchmark::RegisterBenchmark((model + "/mujoco_rne").c_str(), mujoco_rne);
    benchmark::RegisterBenchmark((model + "/equations_of_motion").c_str(), equations_of_motion_step);
    benchmark::RegisterBenchmark((model + "/mujoco_crb").c_str(), mujoco_crb);
    benchmark::RegisterBenchmark((model + "/mujoco_step").c_str(), mujoco_step);
  }
#endif
  return true;
}();

}  // namespace
