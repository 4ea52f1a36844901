// Dependent rates of the non-holonomic wheels at velocity and acceleration level.
#include "../helpers/units.hpp"

#include <doctest/doctest.h>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/nonholonomic.hpp>
#include <wlx/simulation.hpp>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <cmath>
#include <limits>
#include <numbers>

using namespace wlx;
namespace c = gen::coord;

namespace {

using test::kDeg;

Coordinates assembled(Coordinates s, const Model& model = Model()) {
  solve_ik_closed_form(model, s);
  return s;
}

}  // namespace

TEST_CASE("nonholonomic: the thesis' nominal figures: cond(J_beta) ~ 7e2 and yaw' ~ 34 deg/s for theta_l5' = 0.5 deg/s") {
  const Model model;
  Data d;
  const Coordinates s = assembled(nominal_inputs());
  Coordinates sdot = Coordinates::Zero();
  sdot(c::theta_l5) = 0.5 * kDeg;
  solve_dependent_rates(model, d, s, sdot, named_pair("A"));
  MESSAGE("cond(J_beta) = " << d.cond_J_beta << ", yaw' = " << sdot(c::yaw) / kDeg << " deg/s");
  CHECK(d.cond_J_beta == doctest::Approx(7e2).epsilon(0.1));
  CHECK(sdot(c::yaw) / kDeg == doctest::Approx(34).epsilon(0.03));
  CHECK(sdot(c::theta_l5) == 0.5 * kDeg);  // commanded rates come back untouched
  // Both constraints hold, and so does the linearised closure.
  CHECK(sideways_velocity(model, d, s, sdot).cwiseAbs().maxCoeff() <= 1e-15);
  gen::closure(s, model.params(), {.dPhi_ds = &d.dPhi_ds});
  CHECK((d.dPhi_ds * sdot).cwiseAbs().maxCoeff() <= 1e-15);
}

TEST_CASE("nonholonomic: both wheels level under a level cabin: J_beta singular, a clear error") {
  const Model model;
  Data d;
  Coordinates s = nominal_inputs();
  s(c::z_Wr) = 0.0;
  s = assembled(s);
  Coordinates sdot = Coordinates::Zero();
  sdot(c::roll) = 0.1;
  try {
    solve_dependent_rates(model, d, s, sdot, named_pair("A"));
    FAIL("no error for a singular J_beta");
  } catch (const Error& e) {
    const std::string m = e.what();
    CHECK(e.field() == "dependent");
    CHECK(m.find("J_beta for the dependent pair (y_C', yaw') is singular: condition number") != std::string::npos);
    CHECK(m.find("exceeds the threshold 1e+10") != std::string::npos);
    // The hint names the ground levels and the nominal pose's raised wheel, from the model file.
    CHECK(m.find("Raise one wheel (z_Wl, z_Wr; the model's nominal pose has z_Wr = 0.05 m) or choose another "
                 "dependent pair.") != std::string::npos);
  }
  // A documented, configurable threshold: below the nominal 7e2, even the nominal state is singular.
  NonholonomicOptions strict;
  strict.max_condition = 100;
  const Coordinates nominal = assembled(nominal_inputs());
  CHECK_THROWS_AS(solve_dependent_rates(model, d, nominal, sdot, named_pair("A"), strict), Error);
}

TEST_CASE("nonholonomic: every regular pair of the 8 solves, singular ones are errors") {
  const Model model;
  Data d;
  const Coordinates s = assembled(nominal_inputs());
  int regular = 0, singular = 0;
  for (std::size_t i = 0; i < gen::kPairCandidates.size(); ++i)
    for (std::size_t j = i + 1; j < gen::kPairCandidates.size(); ++j) {
      const DependentPair pair{{gen::kPairCandidates[i], gen::kPairCandidates[j]}};
      CAPTURE(pair.label());
      Coordinates sdot = Coordinates::Zero();
      for (int k : gen::kPairCandidates) sdot(k) = 0.01 * (k + 1);  // some commanded motion
      sdot(pair.index[0]) = sdot(pair.index[1]) = 0;
      const Coordinates commanded = sdot;
      try {
        solve_dependent_rates(model, d, s, sdot, pair);
      } catch (const Error&) {
        ++singular;
        CHECK(!(d.cond_J_beta <= 1e10));
        continue;
      }
      ++regular;
      // The closed-form condition number against Eigen's SVD (Jacobi: singular values to a few ulp
      // of sigma_max, so sigma_min, and the ratio, to a few ulp times the condition number).
      const Eigen::Vector2d sv = Eigen::JacobiSVD<Eigen::Matrix2d>(d.J_beta).singularValues();
      CHECK(std::abs(d.cond_J_beta - sv(0) / sv(1)) <= 1e-15 * d.cond_J_beta * d.cond_J_beta + 4e-16 * d.cond_J_beta);
      CHECK(sideways_velocity(model, d, s, sdot).cwiseAbs().maxCoeff() <= 1e-13 * std::max(1.0, d.cond_J_beta / 1e3));
      for (int k : gen::kPairCandidates)
        if (k != pair.index[0] && k != pair.index[1]) CHECK(sdot(k) == commanded(k));
    }
  MESSAGE(regular << " of 28 pairs regular at the nominal pose, " << singular << " singular");
  CHECK(regular + singular == 28);
  CHECK(regular >= 2);
}

TEST_CASE("nonholonomic: the closed-form condition number against the SVD, nearly equal singular values included") {
  // R(a) diag(1, 1 + e) R(b): condition number 1 + e exactly (up to the rounding of the product).
  // The textbook sqrt(E^2 - 4 det^2) form loses half the digits here (about 1e-8 for e = 1e-9). The
  // bound: a few ulp, times the condition number (the determinant of an ill-conditioned matrix is
  // only that accurate).
  for (double e : {0.0, 1e-12, 1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e8}) {
    for (double a : {0.0, 0.3, 2.0}) {
      CAPTURE(e);
      CAPTURE(a);
      const Eigen::Matrix2d J = Eigen::Rotation2Dd(a).toRotationMatrix() * Eigen::Vector2d(1.0, 1.0 + e).asDiagonal() *
                                Eigen::Rotation2Dd(1.1 - a).toRotationMatrix();
      const double expected = 1.0 + e;
      CHECK(std::abs(condition_number(J) - expected) <= 8e-16 * expected * expected);
      CHECK(condition_number(J.transpose()) == doctest::Approx(expected).epsilon(8e-16 * expected));
    }
  }
  CHECK(condition_number(Eigen::Matrix2d::Zero()) == std::numeric_limits<double>::infinity());
  CHECK(condition_number(Eigen::Matrix2d{{1.0, 2.0}, {2.0, 4.0}}) == std::numeric_limits<double>::infinity());
}

TEST_CASE("nonholonomic: pair names are validated") {
  CHECK(dependent_pair({"theta_l5", "theta_r5"}).index == named_pair("B").index);
  const auto message = [](const char* a, const char* b) {
    try {
      dependent_pair({a, b});
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(message("y_C", "y_C") == "dependent: the dependent rates must differ, got 'y_C' twice");
  try {
    dependent_pair({"y_C"});
    FAIL("one name accepted for two wheels");
  } catch (const Error& e) {
    CHECK(std::string(e.what()) ==
          "dependent: needs 2 names, one dependent rate per wheel, got 1: choose from x_C, y_C, z_C, yaw, pitch, roll, "
          "theta_l5, theta_r5");
  }
  CHECK(message("y_C", "psi_l2") ==
        "dependent: 'psi_l2' cannot be a dependent rate: choose 2 of x_C, y_C, z_C, yaw, pitch, roll, theta_l5, theta_r5");
}

TEST_CASE("nonholonomic: rates and accelerations against finite differences along an integrated trajectory") {
  // ST-A2+-like motion plus roll, RK4 with dt = 1e-4: central differences of the samples have
  // error ~dt^2 |s'''| / 6 ~ 1e-8 relative; the integration itself is converged far below that.
  Scenario sc;
  sc.rates(c::theta_l5) = 0.5 * kDeg;
  sc.rates(c::roll) = 3 * kDeg;
  sc.duration = 0.02;
  sc.dt = 1e-4;
  const Trajectory tr = simulate(sc);
  REQUIRE(tr.complete);
  const Model model;
  Data d;
  double worst_v = 0, worst_a = 0, scale_v = 0, scale_a = 0;
  for (std::size_t k = 1; k + 1 < tr.samples.size(); ++k) {
    const auto& prev = tr.samples[k - 1];
    const auto& now = tr.samples[k];
    const auto& next = tr.samples[k + 1];
    const Coordinates fd_v = (next.s - prev.s) / (2 * sc.dt);
    const Coordinates fd_a = (next.sdot - prev.sdot) / (2 * sc.dt);
    Coordinates sdot = now.sdot;
    solve_dependent_rates(model, d, now.s, sdot, sc.pair);
    Coordinates sddot = Coordinates::Zero();  // constant commanded rates
    solve_dependent_accelerations(model, d, now.s, sdot, sddot, sc.pair);
    worst_v = std::max(worst_v, (fd_v - now.sdot).cwiseAbs().maxCoeff());
    worst_a = std::max(worst_a, (fd_a - sddot).cwiseAbs().maxCoeff());
    scale_v = std::max(scale_v, now.sdot.cwiseAbs().maxCoeff());
    scale_a = std::max(scale_a, sddot.cwiseAbs().maxCoeff());
  }
  MESSAGE("max |finite difference - analytic|: rates " << worst_v << " (scale " << scale_v << "), accelerations "
                                                        << worst_a << " (scale " << scale_a << ")");
  CHECK(worst_v <= 1e-7 * scale_v);
  CHECK(worst_a <= 1e-6 * scale_a);
  CHECK(scale_a > 1e-3);  // the acceleration check is not vacuous
}

TEST_CASE("nonholonomic: a limb at a singular pose is named") {
  const Model model;
  Data d;
  Coordinates s = nominal_inputs();
  s(c::x_Fl) = 1.5 + 3.5;  // left foot exactly at full reach: straight leg
  s(c::z_Fl) = 2.0;
  s = assembled(s);
  Coordinates sdot = Coordinates::Zero();
  sdot(c::roll) = 0.1;
  try {
    solve_dependent_rates(model, d, s, sdot, named_pair("A"));
    FAIL("no error at a straight leg");
  } catch (const Error& e) {
    CHECK(e.field() == "left leg");
    CHECK(std::string(e.what()).find("a chain stretched straight or folded") != std::string::npos);
  }
}

TEST_CASE("nonholonomic: contact velocities match finite differences of the contact positions") {
  // ST-A2+-like run at dt = 1e-4: central differences of x_W, y_W good to ~1e-8 m/s.
  Scenario sc;
  sc.rates(c::theta_l5) = 0.5 * kDeg;
  sc.rates(c::roll) = 2 * kDeg;
  sc.duration = 0.01;
  sc.dt = 1e-4;
  const Trajectory tr = simulate(sc);
  REQUIRE(tr.complete);
  double worst = 0, scale = 0;
  for (std::size_t k = 1; k + 1 < tr.samples.size(); ++k) {
    const Eigen::Vector4d fd = (tr.samples[k + 1].contacts - tr.samples[k - 1].contacts) / (2 * sc.dt);
    const auto& v = tr.samples[k].contact_velocity;
    worst = std::max({worst, std::abs(fd(0) - v(0, 0)), std::abs(fd(1) - v(1, 0)), std::abs(fd(2) - v(0, 1)),
                      std::abs(fd(3) - v(1, 1))});
    scale = std::max(scale, v.cwiseAbs().maxCoeff());
    CHECK(std::abs(v(2, 0)) <= 1e-15);  // the ground levels do not move (the frame is level to rounding)
  }
  MESSAGE("contact velocity vs finite differences: " << worst << " m/s (velocities up to " << scale << " m/s)");
  CHECK(scale > 0.1);
  CHECK(worst <= 1e-7 * scale);
}
