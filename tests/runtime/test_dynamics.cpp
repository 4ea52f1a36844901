// Inverse dynamics: checks independent of the Kane formula under test (energy, power, statics).
#include "../helpers/units.hpp"
#include "../helpers/random.hpp"

#include <doctest/doctest.h>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/forward_dynamics.hpp>
#include <wlx/ik.hpp>
#include <wlx/simulation.hpp>

#include <Eigen/QR>

#include <array>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

using namespace wlx;
namespace c = gen::coord;

namespace {

using test::kDeg;

// A random admissible state near the thesis' workspace: cabin moved and tilted, feet and
// levers moved, dependents by the closed form; pair A regular.
Coordinates random_state(std::mt19937_64& rng, const Model& model) {
  std::uniform_real_distribution<double> small(-1, 1);
  for (;;) {
    Coordinates s = nominal_inputs();
    s(c::x_C) = small(rng);
    s(c::y_C) = small(rng);
    s(c::z_C) = 1.7 + 0.3 * small(rng);
    s(c::yaw) = small(rng);
    s(c::pitch) = 0.1 * small(rng);
    s(c::roll) = 0.1 * small(rng);
    // Feet ahead of the hips, turned with the cabin's yaw.
    const double cy = std::cos(s(c::yaw)), sy = std::sin(s(c::yaw));
    for (double side : {1.0, -1.0}) {
      const double ahead = 3.3 + 0.3 * small(rng), across = side * (1.5 + 0.3 * small(rng));
      s(side > 0 ? c::x_Fl : c::x_Fr) = s(c::x_C) + cy * ahead - sy * across;
      s(side > 0 ? c::y_Fl : c::y_Fr) = s(c::y_C) + sy * ahead + cy * across;
    }
    s(c::z_Wl) = 0.1 * small(rng);
    s(c::z_Wr) = 0.1 + 0.1 * small(rng);
    s(c::theta_l5) = 0.2 * small(rng);
    s(c::theta_r5) = 0.2 * small(rng);
    try {
      solve_ik_closed_form(model, s);
      return s;
    } catch (const Error&) {
    }
  }
}

CommandVector random4(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> d(-scale, scale);
  return CommandVector(d(rng), d(rng), d(rng), d(rng));
}

}  // namespace

TEST_CASE("dynamics: J_beta^T tau = Q* and the power balance tau . beta' = Q* . u, every weighting") {
  std::mt19937_64 rng(60);
  const Model model;
  Data d;
  DynamicsTerms t;
  Eigen::Matrix<double, 8, 8> G = Eigen::Matrix<double, 8, 8>::Random();
  const Weighting weightings[] = {Weighting::model_weights(), Weighting::contribution(),
                                  Weighting::diagonal_of((TorqueVector() << 1, 2, 3, 4, 5, 6, 7, 8).finished()),
                                  Weighting::matrix_of(G * G.transpose() + Eigen::Matrix<double, 8, 8>::Identity())};
  double worst_force = 0, worst_power = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Coordinates s = random_state(rng, model);
    const CommandVector u = random4(rng, 1.0), u_dot = random4(rng, 2.0);
    inverse_dynamics(model, d, s, u, u_dot, t);
    const TorqueVector beta_dot = t.J_beta * u;
    // beta' really is the actuated joints' rate of the solved motion.
    for (int r = 0; r < 8; ++r) CHECK(beta_dot(r) == doctest::Approx(t.sdot(kActuatedJoints[r])).epsilon(1e-12).scale(1));
    // And that motion satisfies the model: the closure and the wheels' sideways constraints hold
    // (dPhi/ds s' = 0, C s' = 0), and it carries the commanded speeds.
    gen::ClosureJacobian J;
    gen::WheelRows C;
    gen::kinematic_update(s, model.params(), {.dPhi_ds = &J, .C = &C});
    CHECK((J * t.sdot).cwiseAbs().maxCoeff() <= 1e-12 * t.sdot.norm());
    CHECK((C * t.sdot).cwiseAbs().maxCoeff() <= 1e-12 * t.sdot.norm());
    for (int k = 0; k < kCommandedCount; ++k) CHECK(t.sdot(kCommandedSpeeds[static_cast<std::size_t>(k)]) == u(k));
    for (const Weighting& w : weightings) {
      const TorqueVector tau = distribute_torques(t.J_beta, t.Qstar, w);
      const double scale = t.Qstar.cwiseAbs().maxCoeff();
      worst_force = std::max(worst_force, (t.J_beta.transpose() * tau - t.Qstar).cwiseAbs().maxCoeff() / scale);
      worst_power = std::max(worst_power, std::abs(tau.dot(beta_dot) - t.Qstar.dot(u)) / (scale * u.norm()));
    }
  }
  MESSAGE("relative errors: J_beta^T tau - Q* " << worst_force << ", power " << worst_power);
  CHECK(worst_force <= 1e-12);
  CHECK(worst_power <= 1e-12);
}

TEST_CASE("dynamics: the torques are the weighted least-norm solution to rounding, up to a condition of 1e11") {
  // J_beta = U diag(sigma) V^T with sigma from 1 down to 10^-k: the fast unpivoted path serves up
  // to a condition of 1e12, the pivoted QR beyond. The reference is the same solution in long
  // double (complete orthogonal decomposition, 11 more bits): the double result must be within
  // its backward-stability bound, cond * eps * a small factor (here 64).
  using LongJacobian = Eigen::Matrix<long double, 8, 4>;
  std::mt19937_64 rng(63);
  for (int k = 0; k <= 11; ++k) {
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::Matrix<double, 8, 8> U = Eigen::Matrix<double, 8, 8>::Random().householderQr().householderQ();
      const Eigen::Matrix4d V = Eigen::Matrix4d::Random().householderQr().householderQ();
      Eigen::Vector4d sigma(1, std::pow(10.0, -k / 3.0), std::pow(10.0, -2 * k / 3.0), std::pow(10.0, -k));
      ActuatorJacobian J = U.leftCols<4>() * sigma.asDiagonal() * V.transpose();
      const CommandVector Qstar = random4(rng, 1.0);
      for (const Weighting& w : {Weighting::model_weights(), Weighting::contribution()}) {
        const TorqueVector tau = distribute_torques(J, Qstar, w);
        // S S^T = W^-1 as distribute_torques defines it for these two diagonal weightings.
        TorqueVector S = w.kind == Weighting::Kind::model_weights ? model_weight_diagonal().cwiseInverse().cwiseSqrt().eval()
                                                                : J.rowwise().norm().cwiseSqrt().eval();
        const LongJacobian A = (S.asDiagonal() * J).cast<long double>();
        // tau = S x, x the minimum-norm solution of A^T x = Q*.
        const Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<long double, 4, 8>> cod(A.transpose());
        const Eigen::Matrix<long double, 8, 1> x = cod.solve(Qstar.cast<long double>());
        const TorqueVector reference = (S.cast<long double>().asDiagonal() * x).cast<double>();
        const double condition = std::pow(10.0, k) * S.maxCoeff() / S.minCoeff();
        CHECK((tau - reference).norm() <= 64 * condition * 2.2e-16 * reference.norm());
      }
    }
  }
}

TEST_CASE("dynamics: the weighted least norm is the optimum (no other solution has a smaller tau^T W tau)") {
  std::mt19937_64 rng(61);
  const Model model;
  Data d;
  DynamicsTerms t;
  const Coordinates s = random_state(rng, model);
  inverse_dynamics(model, d, s, CommandVector(0.1, 0.5, 0.05, 0.0), CommandVector::Zero(), t);
  const TorqueVector tau = distribute_torques(t.J_beta, t.Qstar, Weighting::model_weights());
  const auto cost = [](const TorqueVector& x) { return x.dot(model_weight_diagonal().asDiagonal() * x); };
  // Add null-space directions of J_beta^T: the constraint still holds, the cost only grows.
  const Eigen::FullPivLU<Eigen::Matrix<double, 4, 8>> lu(t.J_beta.transpose());
  const Eigen::MatrixXd null = lu.kernel();
  REQUIRE(null.cols() == 4);
  for (int k = 0; k < 4; ++k)
    for (double step : {-1e3, -1.0, 1.0, 1e3}) CHECK(cost(tau + step * null.col(k)) > cost(tau));
}

TEST_CASE("dynamics: M is the Hessian of the kinetic energy: T = u^T M u / 2") {
  std::mt19937_64 rng(62);
  const Model model;
  Data d;
  DynamicsTerms t;
  double worst = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Coordinates s = random_state(rng, model);
    const CommandVector u = random4(rng, 1.0);
    equations_of_motion(model, d, s, u, t);
    const double T = kinetic_energy(model, d, s, t.sdot);
    worst = std::max(worst, std::abs(T - 0.5 * u.dot(t.M * u)) / T);
    CHECK((t.M - t.M.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * t.M.cwiseAbs().maxCoeff());
  }
  CHECK(worst <= 1e-12);
}

TEST_CASE("dynamics: statics: at rest Q* . u is the rate of change of V along the admissible motion u") {
  // Integrate a short constrained motion with rates +u and -u (RK4, h = 1e-4 s in 10 steps);
  // (V(h) - V(-h)) / 2h matches dV/dt to O(h^2). Q* . u is a sum of terms of size |Q*||u| that
  // largely cancel, so the error is measured against that scale.
  std::mt19937_64 rng(63);
  const Model model;
  Data d;
  DynamicsTerms t;
  for (int trial = 0; trial < 20; ++trial) {
    const Coordinates s = random_state(rng, model);
    const CommandVector u = random4(rng, 0.5);
    inverse_dynamics(model, d, s, CommandVector::Zero(), CommandVector::Zero(), t);
    const double predicted = t.Qstar.dot(u);
    // Near a singular J_beta the dependent rates are large: shorten h so that the motion's third
    // derivative (~|s'|^3) does not dominate the difference quotient.
    const double fastest = std::max(1.0, (t.T * u).cwiseAbs().maxCoeff());
    Scenario sc;
    sc.initial = s;
    sc.duration = 1e-4 / fastest;
    sc.dt = sc.duration / 10;
    double V[2];
    for (int sign : {0, 1}) {
      for (int k = 0; k < 4; ++k) sc.rates(kCommandedSpeeds[k]) = (sign ? -1 : 1) * u(k);
      const Trajectory tr = simulate(sc);
      REQUIRE(tr.complete);
      V[sign] = potential_energy(model, d, tr.samples.back().s);
    }
    const double measured = (V[0] - V[1]) / (2 * sc.duration);
    CAPTURE(d.cond_J_beta);
    CAPTURE(predicted);
    CHECK(std::abs(predicted - measured) <= 1e-7 * t.Qstar.norm() * u.norm());
  }
}

TEST_CASE("dynamics: energy: Q* . u = d(T + V)/dt along integrated motions with constant u") {
  std::mt19937_64 rng(64);
  const Model model;
  Data d;
  DynamicsTerms t;
  double worst = 0;
  for (int trial = 0; trial < 10; ++trial) {
    Scenario sc;
    sc.initial = random_state(rng, model);
    CommandVector u = random4(rng, 0.5);
    // Scale u so the fastest coordinate moves at 1 unit/s: the central differences below then
    // have truncation errors ~dt^2 = 1e-8 whatever the conditioning of J_beta.
    inverse_dynamics(model, d, sc.initial, u, CommandVector::Zero(), t);
    u /= t.sdot.cwiseAbs().maxCoeff();
    for (int k = 0; k < 4; ++k) sc.rates(kCommandedSpeeds[k]) = u(k);
    sc.duration = 0.002;
    sc.dt = 1e-5;
    const Trajectory tr = simulate(sc);
    REQUIRE(tr.complete);
    const auto energy = [&](std::size_t k) {
      const Sample& smp = tr.samples[k];
      return kinetic_energy(model, d, smp.s, smp.sdot) + potential_energy(model, d, smp.s);
    };
    for (std::size_t k = 2; k + 2 < tr.samples.size(); k += 20) {
      // Five-point stencil: truncation ~dt^4 |E^(5)| / 30, rounding ~1e-16 |E| / dt.
      const double dEdt = (energy(k - 2) - 8 * energy(k - 1) + 8 * energy(k + 1) - energy(k + 2)) / (12 * sc.dt);
      inverse_dynamics(model, d, tr.samples[k].s, u, CommandVector::Zero(), t);
      const double power = t.Qstar.dot(u);
      worst = std::max(worst, std::abs(power - dEdt) / std::max(1.0, std::abs(power)));
    }
  }
  MESSAGE("max relative |Q* . u - d(T + V)/dt| = " << worst);
  CHECK(worst <= 1e-6);
}

TEST_CASE("dynamics: the thesis' magnitudes: static torques ~2.8e4 N m (2D estimate 4.53e4), ID-1 torques ~1e4") {
  const Model model;
  Data d;
  DynamicsTerms t;
  Coordinates s = nominal_inputs();
  solve_ik_closed_form(model, s);
  inverse_dynamics(model, d, s, CommandVector::Zero(), CommandVector::Zero(), t);
  const TorqueVector tau = distribute_torques(t.J_beta, t.Qstar, Weighting::model_weights());
  const double estimate = model.params().cxd / 2 * model.total_mass() * model.params().g / 2;  // thesis eq. 6.34
  CHECK(estimate == doctest::Approx(4.53e4).epsilon(1e-3));
  for (int k : {0, 3, 6, 7}) {  // psi_l2, psi_r2, theta_l6, theta_r6
    CAPTURE(k);
    CHECK(std::abs(tau(k)) == doctest::Approx(2.8e4).epsilon(0.05));
    CHECK(std::abs(tau(k)) / estimate > 0.3);  // same order as the 2D estimate
  }
  // Weighting 1 loads the strong joints (weight 0.01) and spares the weak hip yaw (weight 100).
  for (int k : {1, 4}) CHECK(std::abs(tau(k)) < 1e-3 * std::abs(tau(0)));
  const TorqueVector tau2 = distribute_torques(t.J_beta, t.Qstar, Weighting::contribution());
  CHECK(std::abs(tau2(1)) > 100 * std::abs(tau(1)));
}

TEST_CASE("dynamics: ID-1..3 reach the thesis' end states with torques of order 1e4 N m") {
  struct Run { int coordinate; double rate, duration, end; };
  for (const Run& r : {Run{c::x_C, 3.0, 0.494, 1.482}, Run{c::roll, -10 * kDeg, 0.541, -5.41 * kDeg},
                       Run{c::z_C, -3.0, 0.581, 0.257}}) {
    for (const Weighting& w : {Weighting::model_weights(), Weighting::contribution()}) {
      Scenario sc;
      sc.rates(r.coordinate) = r.rate;
      sc.duration = r.duration;
      sc.weighting = w;
      // The thesis' contacts are bilateral: with its weightings ID-2 pulls on the ground (the test
      // of weighting 3 below says how much); its reproduction goes on, as the thesis did.
      sc.stop_on_contact_loss = false;
      const Trajectory tr = simulate(sc);
      REQUIRE(tr.complete);
      CHECK(tr.samples.back().s(r.coordinate) == doctest::Approx(r.end).epsilon(1e-9));
      double peak = 0;
      for (const auto& smp : tr.samples) peak = std::max(peak, smp.tau.cwiseAbs().maxCoeff());
      CHECK(peak > 1e4);
      CHECK(peak < 1e5);
      CHECK(tr.samples.back().clearance > 0);
    }
  }
}

TEST_CASE("forward dynamics: the torques of ID-1..3, fed back, reproduce their trajectories (round trip)") {
  // The inverse-dynamics runs hold u constant. Their torques, as a table, drive simulate_torques
  // (RK4) from the same start and speeds, which must retrace the kinematic run. With the table's
  // rows at every time the forward run's RK4 stages ask for (the inverse run at half its step),
  // nothing is interpolated and the two runs differ only by their integrators' truncation. With
  // rows only at its steps the midpoints are interpolated, off by tau'' dt^2 / 8 (reported).
  //
  // ID-2 (roll', which steers the dependent pair y_C, yaw) passes through a singular J_beta: at
  // t = 0.0955 s its condition number peaks (2.7e7 at the forward run's nearest sample at 0.1 ms,
  // unbounded at the crossing itself, where the pair's rates are the limit of 0 / 0). There the
  // rounding of that solve, so amplified, moves u by 7.6e-10 in one step; before it u holds to 3e-13.
  // From then on the forward run replays the inverse run's torques from a state off by that much,
  // open loop, so the offset grows (u 1.6e-9, s 2.6e-9 at the end). The torque split's QR unrolled
  // instead of as loops, rounding otherwise, gave 5.1e-10, 1.1e-9 and 1.7e-9. Halving the step does not
  // shrink it (a sample lands nearer the pole): why this run once looked like a convergence of
  // order 1.6. So: every run agrees to 1e-12 up to its worst-conditioned sample; ID-1 and ID-3
  // (whose worst, cond 1.7e7 near its end, moves nothing) to 2e-12 throughout (measured 3.2e-13 and
  // 7.4e-13); ID-2 after its crossing to 1e-8 (rounding at a singular point, not a wrong dynamics: a
  // wrong term would move u from the start, before the crossing).
  struct Run { int coordinate; double rate, duration; bool crosses_singular; };
  for (const Run& r : {Run{c::x_C, 3.0, 0.494, false}, Run{c::roll, -10 * kDeg, 0.541, true}, Run{c::z_C, -3.0, 0.581, false}}) {
    CommandVector u0;
    std::array<double, 2> worst_s{}, worst_u{};
    double peak_cond = 0, crossing = 0, before_s = 0, before_u = 0, jump = 0;
    for (int exact = 0; exact < 2; ++exact) {
      const double dt = exact ? 1e-4 : 1e-3;
      Scenario sc;
      sc.rates(r.coordinate) = r.rate;
#ifdef WLX_SANITIZED
      // Under the sanitizers, the first 0.1 s of each run: the same paths through the runtime (53 s of
      // a CI run for the whole runs, 11 s for these); the normal tree checks the whole runs' numbers.
      sc.duration = 0.1;
#else
      sc.duration = r.duration;
#endif
      sc.dt = exact ? dt / 2 : dt;
      sc.weighting = Weighting::model_weights();
      sc.stop_on_contact_loss = false;  // as above: the thesis' bilateral contacts
      const Trajectory id = simulate(sc);
      REQUIRE(id.complete);
      std::vector<double> times;
      std::vector<TorqueVector> torques;
      for (const Sample& smp : id.samples) times.push_back(smp.t), torques.push_back(smp.tau);
      for (int k = 0; k < kCommandedCount; ++k) u0(k) = sc.rates(kCommandedSpeeds[static_cast<std::size_t>(k)]);
      Scenario forward = sc;
      forward.weighting.reset();
      forward.dt = dt;
      forward.torques = TorqueTable(std::move(times), std::move(torques));
      const Trajectory fd = simulate(forward);
      CAPTURE(fd.error);
      REQUIRE(fd.complete);
      const std::size_t every = exact ? 2 : 1;  // the kinematic run's samples at the forward run's times
      REQUIRE((fd.samples.size() - 1) * every == id.samples.size() - 1);
      std::size_t peak = 0;
      for (std::size_t k = 0; k < fd.samples.size(); ++k) {
        worst_s[exact] = std::max(worst_s[exact], (fd.samples[k].s - id.samples[k * every].s).cwiseAbs().maxCoeff());
        worst_u[exact] = std::max(worst_u[exact], (fd.samples[k].u - u0).cwiseAbs().maxCoeff());
        if (fd.samples[k].cond_J_beta > fd.samples[peak].cond_J_beta) peak = k;
      }
      if (!exact) continue;
      // Where the condition peaks, and the agreement before and after that step.
      peak_cond = fd.samples[peak].cond_J_beta;
      crossing = fd.samples[peak].t;
      for (std::size_t k = 0; k < peak; ++k) {
        before_s = std::max(before_s, (fd.samples[k].s - id.samples[k * every].s).cwiseAbs().maxCoeff());
        before_u = std::max(before_u, (fd.samples[k].u - u0).cwiseAbs().maxCoeff());
      }
      if (peak + 1 < fd.samples.size()) jump = (fd.samples[peak + 1].u - u0).cwiseAbs().maxCoeff();
    }
    MESSAGE(gen::kCoordinateNames[static_cast<std::size_t>(r.coordinate)] << "' = " << r.rate << ": |s_forward - s_inverse| <= "
            << worst_s[1] << ", |u - u0| <= " << worst_u[1] << " (torques at every stage); " << worst_s[0] << ", "
            << worst_u[0] << " (interpolated at 1 ms); peak cond(J_beta) " << peak_cond << " at t = " << crossing
            << " s: before it |s| <= " << before_s << ", |u| <= " << before_u << "; u just after it " << jump);
    // Approaching the pole, its condition (1.4e5 one sample before) amplifies rounding too: the
    // sanitized tree's build rounds otherwise, and there u reached 1.1e-12 before ID-2's crossing.
    const double before_bound = r.crosses_singular ? 1e-11 : 1e-12;
    CHECK(before_s <= before_bound);
    CHECK(before_u <= before_bound);
    if (r.crosses_singular) {
      CHECK(peak_cond >= 1e6);  // the crossing is where it is said to be
      CHECK(worst_s[1] <= 1e-8);
      CHECK(worst_u[1] <= 1e-8);
    } else {
      CHECK(worst_s[1] <= 2e-12);
      CHECK(worst_u[1] <= 2e-12);
    }
  }
}

TEST_CASE("forward dynamics: a torque table refuses bad rows and times outside it, naming the field") {
  const TorqueVector one = TorqueVector::Ones();
  CHECK_THROWS_WITH_AS(TorqueTable({}, {}), doctest::Contains("at least one"), Error);
  CHECK_THROWS_WITH_AS(TorqueTable({0.0, 1.0}, {one}), doctest::Contains("2 times and 1 rows"), Error);
  CHECK_THROWS_WITH_AS(TorqueTable({0.0, 0.0}, {one, one}), doctest::Contains("must increase: row 1"), Error);
  CHECK_THROWS_WITH_AS(TorqueTable({0.0, NAN}, {one, one}), doctest::Contains("row 1 (t = nan) is not finite"), Error);
  const TorqueTable table({0.0, 1.0}, {TorqueVector::Zero(), 2 * one});
  CHECK((table.at(0.25) - 0.5 * one).cwiseAbs().maxCoeff() <= 1e-15);
  CHECK_THROWS_WITH_AS(table.at(1.5), doctest::Contains("t = 1.5 s is outside the table's times [0, 1] s"), Error);
  // A run with a source that stops answering ends early and says when and why.
  // Cubic: exact for a cubic in t on uneven rows (linear is not), at the ends too.
  const auto cubic = [](double t) { return 2 - t + 3 * t * t - 0.5 * t * t * t; };
  std::vector<double> times{0.0, 0.3, 0.5, 1.1, 1.2, 2.0};
  std::vector<TorqueVector> rows;
  for (double t : times) rows.push_back(cubic(t) * one);
  const TorqueTable smooth(times, rows, TorqueTable::Interpolation::cubic), ramp(times, rows);
  for (double t : {0.01, 0.2, 0.4, 0.8, 1.15, 1.9, 1.999})
    CHECK((smooth.at(t) - cubic(t) * one).cwiseAbs().maxCoeff() <= 1e-14);
  CHECK((ramp.at(0.8) - cubic(0.8) * one).cwiseAbs().maxCoeff() > 1e-2);
  // A run with a source that stops answering ends early and says when and why.
  Scenario sc;
  sc.pair = dynamics_pair();
  sc.duration = 0.01;
  sc.torques = TorqueTable({0.0, 0.005}, {one, one});
  const Trajectory short_table = simulate(sc);
  CHECK(!short_table.complete);
  CHECK(short_table.error.find("stopped at t = 0.0050 s (step 5 of 10): torques: t = 0.0055 s is outside") != std::string::npos);
  sc.weighting = Weighting::model_weights();
  CHECK_THROWS_WITH_AS(simulate(sc), doctest::Contains("torques: a run is driven by its rates"), Error);
  sc.weighting.reset();
  sc.rates(c::theta_l5) = 0.1;
  CHECK_THROWS_WITH_AS(simulate(sc), doctest::Contains("rates.theta_l5: a forward-dynamics run commands only z_C, x_C, roll and pitch"), Error);
  sc.rates(c::theta_l5) = 0;
  sc.pair = dependent_pair({"theta_l5", "theta_r5"});
  CHECK_THROWS_WITH_AS(simulate(sc), doctest::Contains("dependent: a forward-dynamics run needs the dependent pair"), Error);
  // A controller that answers NaN stops the run at once, named.
  sc.pair = dynamics_pair();
  sc.torques = [](double, const Coordinates&, const CommandVector&) { return TorqueVector::Constant(NAN).eval(); };
  const Trajectory nan_source = simulate(sc);
  CHECK(!nan_source.complete);
  CHECK(nan_source.error.find("stopped at t = 0.0000 s (step 0 of 10): torques: the torque source gave a non-finite torque") != std::string::npos);
}

TEST_CASE("forward dynamics: forces that are not finite are an error naming u_dot, never NaN accelerations") {
  // Commanded speeds of 1e200 keep s' = T u finite but square past the largest double in the
  // velocity forces b: M stays finite and positive definite, so the error names the forces.
  const Model model;
  Data d;
  Coordinates s = nominal_inputs();
  solve_ik_closed_form(model, s);
  DynamicsTerms terms;
  CommandVector u_dot = CommandVector::Zero();
  forward_dynamics(model, d, s, CommandVector::Zero(), TorqueVector::Zero(), u_dot, terms);
  REQUIRE(u_dot.allFinite());  // the same state at rest: finite accelerations
  CHECK_THROWS_WITH_AS(forward_dynamics(model, d, s, CommandVector::Constant(1e200), TorqueVector::Zero(), u_dot, terms),
                       doctest::Contains("u_dot: the forces on the commanded speeds (b, Q_gravity) are not finite"), Error);
  CHECK(terms.M.allFinite());
}

TEST_CASE("dynamics: ID-3 ends 7 mm above the ground: the cabin would touch it at t ~ 0.583 s") {
  Scenario sc;
  sc.rates(c::z_C) = -3.0;
  sc.duration = 0.581;
  sc.weighting = Weighting::model_weights();
  const Trajectory tr = simulate(sc);
  const double clearance = tr.samples.back().clearance;
  CHECK(clearance == doctest::Approx(0.007).epsilon(0.05));
  CHECK(0.581 + clearance / 3.0 == doctest::Approx(0.583).epsilon(1e-3));
}

TEST_CASE("dynamics: a rank-deficient J_beta and bad weights are clear errors; zero rows get zero torque") {
  ActuatorJacobian J = ActuatorJacobian::Zero();
  J(0, 0) = J(1, 1) = J(2, 2) = 1;  // nothing acts on pitch
  CHECK_THROWS_WITH_AS(distribute_torques(J, CommandVector(1, 2, 3, 4), Weighting::model_weights()),
                       "J_beta: the actuator Jacobian has rank 3 < 4 with the model file's weights: the 8 actuators "
                       "cannot produce every generalized force on u = [z_C', x_C', roll', pitch'] in this pose: the speeds "
                       "1 pitch' move no actuator (wheels that roll freely, a joint that is not actuated): actuate a "
                       "joint they move or drive the wheels ({wheel: NAME} under dynamics.actuated), or command fewer speeds",
                       Error);
  // A combination: two actuators see roll' and pitch' only as roll' + 2 pitch'.
  J(2, 2) = 1, J(2, 3) = 2, J(3, 2) = 2, J(3, 3) = 4;
  CHECK_THROWS_WITH_AS(distribute_torques(J, CommandVector(1, 2, 3, 4), Weighting::model_weights()),
                       doctest::Contains("the speeds 1 roll' - 0.5 pitch' move no actuator"), Error);
  J = ActuatorJacobian::Zero();
  J(0, 0) = J(1, 1) = J(2, 2) = 1;
  J(3, 3) = 2;
  const TorqueVector tau = distribute_torques(J, CommandVector(1, 2, 3, 4), Weighting::contribution());
  for (int r = 4; r < 8; ++r) CHECK(tau(r) == 0.0);
  CHECK((J.transpose() * tau - CommandVector(1, 2, 3, 4)).norm() <= 1e-15);
  CHECK_THROWS_WITH_AS(Weighting::diagonal_of(TorqueVector::Constant(-1)),
                       "weighting[0]: a weight must be positive and finite, got -1", Error);
  Eigen::Matrix<double, 8, 8> W = Eigen::Matrix<double, 8, 8>::Identity();
  W(7, 7) = -1;
  CHECK_THROWS_WITH_AS(Weighting::matrix_of(W), "weighting: the weight matrix must be positive definite", Error);
}

TEST_CASE("weighting 3 keeps the contacts: on ID-1..3 its smallest contact margin is at least the better of weightings 1 and 2 at every step") {
  // The three runs share their motion (inverse dynamics: the torques follow it), so their samples
  // pair up. Weighting 3 maximises the smallest of every contact's normal force and friction
  // margin over the weight; weighting 1's torques are feasible for it (z = 0), so it may not fall
  // below them beyond the cutting planes' tolerance (1e-10); weighting 2's are feasible at the
  // penalty 1e-7 |z_2|^2 / 2 of the tie-break, with |z_2| below 3 here: 1e-6 bounds it.
  struct Run { const char* id; int coordinate; double rate, duration; };
  const Model model;
  for (const Run& r : {Run{"ID-1", c::x_C, 3.0, 0.494}, Run{"ID-2", c::roll, -10 * kDeg, 0.541}, Run{"ID-3", c::z_C, -3.0, 0.581}}) {
    std::vector<Trajectory> runs;
    for (const Weighting& w : {Weighting::model_weights(), Weighting::contribution(), Weighting::contacts()}) {
      Scenario sc;
      sc.rates(r.coordinate) = r.rate;
      sc.duration = r.duration;
      sc.weighting = w;
      sc.stop_on_contact_loss = false;  // weightings 1 and 2 may lift a contact: compare every step
      runs.push_back(simulate(sc));
      CAPTURE(runs.back().error);
      REQUIRE(runs.back().complete);
    }
    REQUIRE(runs[0].samples.size() == runs[2].samples.size());
    double worst_1 = 1e300, worst_2 = 1e300, lowest[3] = {1e300, 1e300, 1e300}, normal[3] = {1e300, 1e300, 1e300},
           friction[3] = {1e300, 1e300, 1e300}, residual = 0;
    for (std::size_t k = 0; k < runs[0].samples.size(); ++k) {
      double m[3];
      for (int w = 0; w < 3; ++w) {
        const Sample& smp = runs[static_cast<std::size_t>(w)].samples[k];
        m[w] = smallest_contact_margin(model, smp.forces);
        lowest[w] = std::min(lowest[w], m[w]);
        normal[w] = std::min(normal[w], smp.forces.normal.minCoeff());
        friction[w] = std::min(friction[w], smp.forces.friction_margin.minCoeff());
        residual = std::max(residual, smp.momentum_residual);  // weighting 3's torques produce Q* too
      }
      worst_1 = std::min(worst_1, m[2] - m[0]);
      worst_2 = std::min(worst_2, m[2] - m[1]);
    }
    MESSAGE(std::string(r.id) << ": smallest contact margin / weight, weightings 1, 2, 3: " << lowest[0] << ", " << lowest[1] << ", "
                 << lowest[2] << "; smallest normal force (N) " << normal[0] << ", " << normal[1] << ", " << normal[2]
                 << "; smallest friction margin (N) " << friction[0] << ", " << friction[1] << ", " << friction[2]
                 << "; weighting 3 minus the better, worst step: " << std::min(worst_1, worst_2));
    CHECK(worst_1 >= -1e-10);
    CHECK(worst_2 >= -1e-6);
    CHECK(lowest[2] >= std::max(lowest[0], lowest[1]) - 1e-6);
    CHECK(residual <= 1e-9);
  }
}
