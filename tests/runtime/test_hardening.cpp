// Issue 14 in the runtime: non-finite values are caught in the step where they arise (with the
// time, the quantity and what drives it, and the samples before kept), and the torque split does
// not depend on a uniform scale of the weights.
#include <doctest/doctest.h>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/simulation.hpp>

#include <cmath>
#include <random>
#include <string>

using namespace wlx;
namespace c = gen::coord;

namespace {

// A full-rank 8 x 4 actuator Jacobian with entries of different sizes, like a real pose's.
ActuatorJacobian sample_jacobian() {
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> entry(-1, 1);
  ActuatorJacobian J;
  for (int r = 0; r < 8; ++r)
    for (int k = 0; k < 4; ++k) J(r, k) = entry(rng) * (1 + r % 3);
  return J;
}

double relative_difference(const TorqueVector& a, const TorqueVector& b) { return (a - b).norm() / b.norm(); }

}  // namespace

TEST_CASE("hardening: an input that overflows in a step stops the run there, naming it, the time and the rate") {
  // Explicit Euler with dt = 1e4 s: z_Wl' = 1e305 m/s (finite, and so is every rate derived from it
  // at t = 0) makes z_Wl = 1e309 = inf in the first step, before any right-hand side sees it.
  Scenario sc;
  sc.integrator = Integrator::euler;
  sc.rates(c::z_Wl) = 1e305;
  sc.duration = 2e4;
  sc.dt = 1e4;
  const Trajectory tr = simulate(sc);
  CAPTURE(tr.error);
  CHECK(!tr.complete);
  CHECK(tr.error.find("z_Wl: became non-finite (inf) in the step to t = 10000.000000 s") != std::string::npos);
  CHECK(tr.error.find("largest commanded rate z_Wl' = 1e+305") != std::string::npos);
  // The sample at t = 0 was computed before the overflow: kept, and finite.
  REQUIRE(tr.samples.size() == 1);
  CHECK(tr.samples[0].t == 0.0);
  CHECK(tr.samples[0].s.allFinite());
}

TEST_CASE("hardening: a sample quantity that is not finite is named where it arises (here a torque at t = 0)") {
  // A cabin of 1e308 kg: its gravity load m g l overflows in Q*, so the torques cannot be finite.
  Scenario sc;
  sc.params.m_M1 = 1e308;
  sc.params.Ixx_M1 = sc.params.Iyy_M1 = sc.params.Izz_M1 = 1e308;
  sc.weighting = Weighting::model_weights();
  sc.rates(c::z_C) = 0.01;
  sc.duration = 0.01;
  Trajectory tr;
  try {
    tr = simulate(sc);
  } catch (const Error& e) {  // a model may refuse such a mass up front: equally acceptable
    MESSAGE("refused up front: " << e.what());
    return;
  }
  CAPTURE(tr.error);
  CHECK(!tr.complete);
  CHECK(tr.samples.empty());
  CHECK(tr.error.find("stopped at t = 0.0000 s") != std::string::npos);
  CHECK(tr.error.find("became non-finite") != std::string::npos);
  const bool names_a_dynamics_column = tr.error.find("tau_") != std::string::npos || tr.error.find("Qstar_") != std::string::npos;
  CHECK(names_a_dynamics_column);
  CHECK(tr.error.find("heaviest body 1e+308 kg") != std::string::npos);
}

TEST_CASE("hardening: weights scaled uniformly (1e-300 to 1e300) give the same torques; no false rank loss") {
  const ActuatorJacobian J = sample_jacobian();
  const CommandVector Qstar(1e4, -3e3, 2e4, 5e3);
  TorqueVector w;
  w << 0.01, 100, 1, 0.01, 100, 1, 0.01, 0.01;  // weighting 1's spread
  const TorqueVector reference = distribute_torques(J, Qstar, Weighting::diagonal_of(w));
  // The solution is the same point for every scale; what differs is the rounding of w / max(w)
  // (one division per weight, <= 1 ulp) carried through a QR of a well-conditioned 8 x 4 matrix:
  // far below 1e-12 relative. Before normalization 1e-300 failed with "rank 0".
  for (double scale : {1e-300, 1e-200, 1e-100, 3.0, 1e100, 1e200, 1e300}) {
    CAPTURE(scale);
    const TorqueVector tau = distribute_torques(J, Qstar, Weighting::diagonal_of(w * scale));
    CHECK(tau.allFinite());
    CHECK(relative_difference(tau, reference) <= 1e-12);
  }
  // The extremes: every weight 1e308 or 1e-307 is weighting with the identity.
  const TorqueVector identity = distribute_torques(J, Qstar, Weighting::diagonal_of(TorqueVector::Ones()));
  for (double weight : {1e-307, 1e-305, 1e306, 1e308}) {
    CAPTURE(weight);
    TorqueVector tau;
    REQUIRE_NOTHROW(tau = distribute_torques(J, Qstar, Weighting::diagonal_of(TorqueVector::Constant(weight))));
    CHECK(relative_difference(tau, identity) <= 1e-12);
  }
  // The same for a full weight matrix (symmetric positive definite, off-diagonal terms).
  Eigen::Matrix<double, 8, 8> W = Eigen::Matrix<double, 8, 8>::Identity() * 4;
  for (int r = 0; r + 1 < 8; ++r) W(r, r + 1) = W(r + 1, r) = 1;
  const TorqueVector matrix_reference = distribute_torques(J, Qstar, Weighting::matrix_of(W));
  for (double scale : {1e-300, 1e300}) {
    CAPTURE(scale);
    const TorqueVector tau = distribute_torques(J, Qstar, Weighting::matrix_of(W * scale));
    CHECK(relative_difference(tau, matrix_reference) <= 1e-12);
  }
  // And every split solves J^T tau = Q*: the scale did not change the problem solved.
  CHECK((J.transpose() * matrix_reference - Qstar).norm() <= 1e-9 * Qstar.norm());
}

TEST_CASE("hardening: an Error keeps its field and its reason apart") {
  const wlx::Error named("legD", "must be positive, got -1");
  CHECK(std::string(named.what()) == "legD: must be positive, got -1");
  CHECK(named.field() == "legD");
  CHECK(named.reason() == "must be positive, got -1");
  const wlx::Error unnamed("", "closure residual is not finite");
  CHECK(std::string(unnamed.what()) == "closure residual is not finite");
  CHECK(unnamed.field().empty());
  CHECK(unnamed.reason() == "closure residual is not finite");  // not cut by a field's length
}
