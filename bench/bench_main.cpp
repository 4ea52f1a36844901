// Benchmarks (Google Benchmark): generated functions per call, and closed-form vs Newton IK.
// Compare numbers from one run only (ratios): these machines are noisy.
#include <benchmark/benchmark.h>
#include <wlx/ik.hpp>
#include <wlx/dynamics.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>
#include <wlx/simulation.hpp>

#include <numbers>

#include <random>

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
    gen::kinematics(s, model.params(), &d.frame_positions, nullptr);
    benchmark::DoNotOptimize(d.frame_positions.data());
  }
}
void BM_gen_kinematics_all(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::kinematics(s, model.params(), &d.frame_positions, &d.frame_rotations);
    benchmark::DoNotOptimize(d.frame_positions.data());
    benchmark::DoNotOptimize(d.frame_rotations.data());
  }
}
void BM_gen_closure(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::closure(s, model.params(), &d.Phi, &d.dPhi_ds);
    benchmark::DoNotOptimize(d.dPhi_ds.data());
  }
}
void BM_gen_nonholonomic(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::nonholonomic(s, model.params(), &d.C, &d.spin);
    benchmark::DoNotOptimize(d.C.data());
  }
}
void BM_gen_convective(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  const Coordinates sdot = Coordinates::Constant(0.1);
  for (auto _ : st) {
    gen::convective(s, sdot, model.params(), &d.dPhi_ds_dot_sdot, &d.C_dot_sdot);
    benchmark::DoNotOptimize(d.C_dot_sdot.data());
  }
}
void BM_gen_bodies(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  const Coordinates sdot = Coordinates::Constant(0.1);
  for (auto _ : st) {
    gen::bodies(s, sdot, model.params(), &d.body_com, &d.body_rotations, &d.body_Jv, &d.body_Jw, &d.body_Jv_dot_sdot,
                &d.body_Jw_dot_sdot);
    benchmark::DoNotOptimize(d.body_Jv.data());
  }
}

// FK + Phi + dPhi/ds + C(s): the fused generated function, and the three separate ones.
void BM_gen_kinematic_update_fused(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::kinematic_update(s, model.params(), &d.frame_positions, &d.frame_rotations, &d.Phi, &d.dPhi_ds, &d.C);
    benchmark::DoNotOptimize(d.C.data());
  }
}
void BM_gen_kinematic_update_separate(benchmark::State& st) {
  const Model model;
  Data d;
  const Coordinates s = assembled_nominal(model);
  for (auto _ : st) {
    gen::kinematics(s, model.params(), &d.frame_positions, &d.frame_rotations);
    gen::closure(s, model.params(), &d.Phi, &d.dPhi_ds);
    gen::nonholonomic(s, model.params(), &d.C, nullptr);
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
    kinematic_update(model, s, d);
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
    const NewtonReport r = solve_ik_newton(model, s, d);
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
    const NewtonReport r = solve_ik_newton(model, s, d);
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
    solve_dependent_rates(model, s, sdot, kPairA, d);
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
  solve_dependent_rates(model, s, sdot, kPairA, d);
  Coordinates sddot = Coordinates::Zero();
  for (auto _ : st) {
    solve_dependent_accelerations(model, s, sdot, sddot, kPairA, d);
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

// One inverse-dynamics step: closed-form IK, dependent rates and accelerations, body kinematics,
// Kane's sums, J_beta, and the weighted torque distribution.
void BM_inverse_dynamics_step(benchmark::State& st) {
  const Model model;
  Data d;
  DynamicsTerms terms;
  Coordinates s = nominal_inputs();
  s(gen::coord::x_C) = 0.3;
  const Vector4 u(0, 3, 0, 0);
  for (auto _ : st) {
    solve_ik_closed_form(model, s);
    inverse_dynamics(model, s, u, Vector4::Zero(), d, terms);
    const Vector8 tau = distribute_torques(terms.J_beta, terms.Qstar, Weighting::strong_weak());
    benchmark::DoNotOptimize(tau.data());
  }
}
// The whole ID-1 run (495 samples, RK4) with weighting 1.
void BM_run_ID1(benchmark::State& st) {
  Scenario sc;
  sc.rates(gen::coord::x_C) = 3.0;
  sc.duration = 0.494;
  sc.weighting = Weighting::strong_weak();
  for (auto _ : st) {
    const Trajectory tr = simulate(sc);
    benchmark::DoNotOptimize(tr.samples.data());
  }
}

}  // namespace

BENCHMARK(BM_inverse_dynamics_step);
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
BENCHMARK(BM_gen_kinematic_update_fused);
BENCHMARK(BM_gen_kinematic_update_separate);
BENCHMARK(BM_full_kinematic_update);
BENCHMARK(BM_ik_closed_form_4_limbs);
BENCHMARK(BM_ik_newton_cold_4_limbs);
BENCHMARK(BM_ik_newton_warm_4_limbs);
BENCHMARK_MAIN();
