// Closure equations and their Jacobian and convective terms, checked with exact derivatives
// (Taylor jets) of the independent reference chain, and with finite differences.
#include "../helpers/random.hpp"
#include "../helpers/reference_chain.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/closure.hpp>
#include <wlx/gen/convective.hpp>

#include <cmath>

using namespace wlx;

TEST_CASE("closure: Phi, dPhi/ds and (d/dt dPhi/ds) s' match exact derivatives of the reference") {
  // Entries are O(10) (lever arms of a few metres times unit rates); rounding in both
  // evaluations stays below 1e-13, so 1e-12 catches any wrong term.
  std::mt19937_64 rng(10);
  const gen::Params p;
  gen::ClosureVector Phi, conv;
  gen::ClosureJacobian J;
  gen::WheelVector C_conv;
  double worst_phi = 0, worst_J = 0, worst_conv = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    const gen::Coordinates sdot = test::random_rates(rng);
    gen::closure(s, p, {.Phi = &Phi, .dPhi_ds = &J});
    gen::convective(s, sdot, p, {.dPhi_ds_dot_sdot = &conv, .C_dot_sdot = &C_conv});
    for (int j = 0; j < gen::kCoordinateCount; ++j) {
      const auto ref = test::reference_closure(test::along(s, gen::Coordinates::Unit(j)), p);
      for (int i = 0; i < gen::kClosureCount; ++i) worst_J = std::max(worst_J, std::abs(J(i, j) - ref[i].d));
    }
    const auto ref = test::reference_closure(test::along(s, sdot), p);
    for (int i = 0; i < gen::kClosureCount; ++i) {
      worst_phi = std::max(worst_phi, std::abs(Phi(i) - ref[i].v));
      worst_conv = std::max(worst_conv, std::abs(conv(i) - ref[i].dd));
    }
  }
  MESSAGE("max errors: Phi " << worst_phi << ", dPhi/ds " << worst_J << ", convective " << worst_conv);
  CHECK(worst_phi <= 1e-12);
  CHECK(worst_J <= 1e-12);
  CHECK(worst_conv <= 1e-11);  // second derivatives with rates up to 2/s: entries O(100)
}

TEST_CASE("closure: dPhi/ds agrees with central finite differences of the generated Phi") {
  // Central differences with h = 1e-6 have truncation error ~h^2 * |Phi'''| ~ 1e-11 and
  // cancellation error ~1e-16 * |Phi| / h ~ 1e-9: 1e-7 is the honest bound for this check.
  std::mt19937_64 rng(11);
  const gen::Params p;
  gen::ClosureVector plus, minus;
  gen::ClosureJacobian J;
  double worst = 0;
  const double h = 1e-6;
  for (int trial = 0; trial < 100; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    gen::closure(s, p, {.dPhi_ds = &J});
    for (int j = 0; j < gen::kCoordinateCount; ++j) {
      gen::closure(s + h * gen::Coordinates::Unit(j), p, {.Phi = &plus});
      gen::closure(s - h * gen::Coordinates::Unit(j), p, {.Phi = &minus});
      worst = std::max(worst, ((plus - minus) / (2 * h) - J.col(j)).cwiseAbs().maxCoeff());
    }
  }
  MESSAGE("max |dPhi/ds - central difference| = " << worst);
  CHECK(worst <= 1e-7);
}

TEST_CASE("closure: the guidance rows are exactly theta_4 + theta_5") {
  const gen::Params p;
  gen::Coordinates s = gen::Coordinates::Zero();
  s(gen::coord::theta_l4) = 0.25;
  s(gen::coord::theta_l5) = -0.25;
  s(gen::coord::theta_r4) = 0.5;
  gen::ClosureVector Phi;
  gen::closure(s, p, {.Phi = &Phi});
  CHECK(Phi(9) == 0.0);
  CHECK(Phi(13) == 0.5);
}
