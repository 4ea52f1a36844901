// Integration: no drift, convergence, the thesis' singular crossing, stopping cleanly.
#include "../helpers/units.hpp"

#include <doctest/doctest.h>
#include <wlx/error.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/simulation.hpp>

#include <cmath>
#include <numbers>

using namespace wlx;
namespace c = gen::coord;

namespace {
using test::kDeg;
}

TEST_CASE("simulation: the closure does not drift; sample count includes t = 0") {
  Scenario sc;
  sc.rates(c::roll) = 5 * kDeg;
  sc.duration = 2.0;
  const Trajectory tr = simulate(sc);
  REQUIRE(tr.complete);
  CHECK(tr.samples.size() == 2001);  // the thesis' "2001 integrations" for 2 s
  const Model model;
  Data d;
  double worst = 0;
  for (const auto& smp : tr.samples) {
    closure(model, d, smp.s, false);
    worst = std::max(worst, d.Phi.cwiseAbs().maxCoeff());
  }
  CHECK(worst <= 1e-13);
  CHECK(tr.samples.back().s(c::roll) == doctest::Approx(10 * kDeg).epsilon(1e-12));
}

TEST_CASE("simulation: RK4 at 1 ms is converged; Euler differs by ~4e-5 m in y_C (docs/excavator.md section 5)") {
  Scenario sc;
  sc.rates(c::theta_l5) = 0.5 * kDeg;  // ST-A2+
  sc.duration = 0.451;
  const Trajectory rk4 = simulate(sc);
  sc.dt = 0.0005;
  const Trajectory fine = simulate(sc);
  sc.dt = 0.001;
  sc.integrator = Integrator::euler;
  const Trajectory euler = simulate(sc);
  const double rk4_error = std::abs(rk4.samples.back().s(c::y_C) - fine.samples.back().s(c::y_C));
  double euler_error = 0;
  for (std::size_t k = 0; k < rk4.samples.size(); ++k)
    euler_error = std::max(euler_error, std::abs(euler.samples[k].s(c::y_C) - rk4.samples[k].s(c::y_C)));
  MESSAGE("ST-A2+ y_C: |RK4(1 ms) - RK4(0.5 ms)| = " << rk4_error << " m, max |Euler - RK4| = " << euler_error << " m");
  CHECK(rk4_error <= 1e-12);
  CHECK(euler_error == doctest::Approx(4e-5).epsilon(0.5));
}

TEST_CASE("simulation: ST-A1- passes the singular point at t ~ 0.1910 s smoothly") {
  Scenario sc;
  sc.rates(c::roll) = -5 * kDeg;
  sc.duration = 0.4;
  const Trajectory tr = simulate(sc);
  REQUIRE(tr.complete);
  std::size_t peak = 0;
  for (std::size_t k = 0; k < tr.samples.size(); ++k)
    if (tr.samples[k].cond_J_beta > tr.samples[peak].cond_J_beta) peak = k;
  MESSAGE("largest cond(J_beta) " << tr.samples[peak].cond_J_beta << " at t = " << tr.samples[peak].t << " s");
  CHECK(tr.samples[peak].t == doctest::Approx(0.191).epsilon(0.005));
  CHECK(tr.samples[peak].cond_J_beta == doctest::Approx(2.7e7).epsilon(0.1));
  // roll there is -asin(0.05 / 3): the roll cancels the 5 cm step between the wheels.
  CHECK(tr.samples[peak].s(c::roll) == doctest::Approx(-std::asin(0.05 / 3)).epsilon(0.01));
  // The dependent rates stay smooth: second differences at the crossing are as small as elsewhere.
  const auto second = [&](std::size_t k, int i) {
    return std::abs(tr.samples[k + 1].sdot(i) - 2 * tr.samples[k].sdot(i) + tr.samples[k - 1].sdot(i));
  };
  double typical = 0;
  for (std::size_t k = 10; k < 100; ++k) typical = std::max(typical, second(k, c::yaw));
  CHECK(second(peak, c::yaw) <= 10 * typical + 1e-6);
  CHECK(second(peak, c::y_C) <= 1e-6);
}

TEST_CASE("simulation: a run that becomes unreachable stops, keeps its samples and says when") {
  Scenario sc;
  sc.rates(c::z_C) = 3.0;  // lift the cabin until the legs cannot reach the feet
  sc.duration = 1.0;
  const Trajectory tr = simulate(sc);
  CHECK_FALSE(tr.complete);
  REQUIRE(!tr.samples.empty());
  CHECK(tr.samples.size() < 1001);
  CHECK(tr.error.find("stopped at t = ") == 0);
  CHECK(tr.error.find("leg: F_l out of reach") != std::string::npos);
  for (const auto& smp : tr.samples) CHECK(smp.s.allFinite());
}

TEST_CASE("simulation: scenario validation names the field") {
  Scenario sc;
  sc.duration = 1;
  sc.dt = 0;
  CHECK_THROWS_WITH_AS(sc.validate(), "dt: must be a positive number of seconds, got 0", Error);
  sc.dt = 1e-9;
  sc.duration = 1000;
  CHECK_THROWS_WITH_AS(sc.validate(), "dt: 1e-09 s over 1000 s is 1e+12 steps, more than the limit of 1e8", Error);
  sc = Scenario{};
  sc.duration = -2;
  CHECK_THROWS_WITH_AS(sc.validate(), "duration: must be a positive number of seconds, got -2", Error);
  sc = Scenario{};
  sc.duration = 1;
  sc.rates(c::yaw) = 0.1;
  CHECK_THROWS_WITH_AS(sc.validate(),
                       "rates.yaw: yaw is a dependent rate in this scenario (pair (y_C', yaw')): it is computed, not "
                       "commanded",
                       Error);
}

TEST_CASE("simulation: cabin clearance of the 3 x 3 x 0.5 m block") {
  const Params p;
  const Model model{p};
  Coordinates s = nominal_inputs();
  CHECK(lowest_clearance(model, s) == doctest::Approx(2.0 - 0.25));
  s(c::roll) = 0.1;
  CHECK(lowest_clearance(model, s) == doctest::Approx(2.0 - (std::sin(0.1) * 1.5 + std::cos(0.1) * 0.25)));
  // The box itself, for drawings (the viewer): the cabin frame and half the model file's sizes.
  CHECK(gen::kClearanceFrame == gen::frame::C);
  Eigen::Vector3d half;
  gen::clearance(s, p, {.half_extents = &half});
  CHECK(half == Eigen::Vector3d(p.cxd / 2, p.cyd / 2, p.cabin_height / 2));
}

TEST_CASE("simulation: a run that meets a singular J_beta midway stops there with the reason") {
  // Lowering the right wheel's ground to the left one's level makes the wheel axes collinear;
  // with a threshold of 1e4 the run stops when cond(J_beta) passes it.
  Scenario sc;
  sc.rates(c::z_Wr) = -0.1;  // z_Wr: 0.05 m -> 0 at t = 0.5 s
  sc.duration = 1.0;
  sc.nonholonomic.max_condition = 1e4;
  const Trajectory tr = simulate(sc);
  CHECK_FALSE(tr.complete);
  REQUIRE(tr.samples.size() > 100);
  CHECK(tr.samples.back().t < 0.5);
  CHECK(tr.samples.back().cond_J_beta <= 1e4);
  CHECK(tr.error.find("J_beta for the dependent pair (y_C', yaw') is singular: condition number") != std::string::npos);
  CHECK(tr.error.find("exceeds the threshold 1e+04") != std::string::npos);
}

namespace {

// NH-4 (roll at 10 deg/s, levers straddling in opposite senses): the least smooth NH run.
Scenario nh4() {
  Scenario sc;
  sc.rates(c::roll) = 10 * kDeg;
  sc.rates(c::theta_l5) = 0.5 * kDeg;
  sc.rates(c::theta_r5) = -0.5 * kDeg;
  sc.duration = 2.0;
  return sc;
}

double max_difference(const Trajectory& a, const Trajectory& b, long stride) {
  double worst = 0;
  for (std::size_t k = 0; k < a.samples.size(); ++k)
    worst = std::max(worst, (a.samples[k].s.head<kInputCount>() - b.samples[k * static_cast<std::size_t>(stride)].s.head<kInputCount>())
                                .cwiseAbs()
                                .maxCoeff());
  return worst;
}

}  // namespace

TEST_CASE("simulation: dopri5 meets its tolerance, in far fewer evaluations than RK4") {
  // Reference: RK4 at 0.1 ms (its error is ~1e-16 here: RK4 at 1 ms is already within 1e-12).
  Scenario ref_sc = nh4();
  ref_sc.dt = 1e-4;
  const Trajectory ref = simulate(ref_sc);
  REQUIRE(ref.complete);
  double previous = 1;
  for (double tolerance : {1e-6, 1e-9, 1e-12}) {
    Scenario sc = nh4();
    sc.integrator = Integrator::dopri5;
    sc.tolerance = tolerance;
    sc.dt = 0.5;  // output interval only: the steps adapt inside it
    const Trajectory tr = simulate(sc);
    REQUIRE(tr.complete);
    REQUIRE(tr.samples.size() == 5);
    const double error = max_difference(tr, ref, 5000);
    CAPTURE(tolerance);
    MESSAGE("NH-4 dopri5 tolerance " << tolerance << ": max error " << error << " rad or m, " << tr.steps << " steps, "
                                     << tr.rejected_steps << " rejected, " << tr.evaluations << " evaluations");
    // Local errors are held below the tolerance; over 2 s their sum stays within 10x of it here.
    CHECK(error <= 10 * tolerance);
    CHECK(error < previous);
    previous = error;
    CHECK(tr.evaluations < 2000);  // RK4 at the thesis' 1 ms step: 8001
  }
}

TEST_CASE("simulation: dopri5 rejects a long step whose stages leave the workspace; a real failure still stops") {
  // One 0.5 s step of NH-4 probes stage poses beyond the legs' reach: rejected, not an error.
  Scenario sc = nh4();
  sc.integrator = Integrator::dopri5;
  sc.dt = 0.5;
  const Trajectory tr = simulate(sc);
  CHECK(tr.complete);
  CHECK(tr.rejected_steps >= 1);
  // Lifting the cabin out of the legs' reach fails at the same sample as with RK4.
  Scenario lift;
  lift.rates(c::z_C) = 3.0;
  lift.duration = 1.0;
  lift.dt = 0.01;
  const Trajectory rk4 = simulate(lift);
  lift.integrator = Integrator::dopri5;
  const Trajectory adaptive = simulate(lift);
  CHECK_FALSE(adaptive.complete);
  CHECK(adaptive.samples.size() == rk4.samples.size());
  // Near the reach the leg straightens: its rates blow up (singular limb block) or the target
  // leaves the reach, whichever the integrator meets first; either names the leg, never NaN.
  CHECK(adaptive.error.find("left leg: ") != std::string::npos);
  CHECK(adaptive.error.find("nan") == std::string::npos);
  Scenario bad = nh4();
  bad.integrator = Integrator::dopri5;
  bad.tolerance = 1e-16;
  CHECK_THROWS_WITH_AS(bad.validate(), "tolerance: must be between 1e-14 (rounding) and 1e-2, got 1e-16", Error);
}
