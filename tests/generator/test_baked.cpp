// `wlx-gen --bake-defaults` output (built into the build tree in namespace wlx::baked) computes
// the same as the committed symbolic headers at the default parameters.
#include "../helpers/random.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/all.hpp>
#include WLX_BAKED_ALL

TEST_CASE("baked parameters: same results as the symbolic headers at docs/excavator.md's defaults") {
  std::mt19937_64 rng(40);
  const wlx::gen::Params p;
  wlx::baked::Params ignored;
  ignored.cxd = ignored.cyd = ignored.thighD = ignored.legD = ignored.wl = ignored.w = 123.0;  // must not matter
  double worst = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const wlx::gen::Coordinates s = wlx::test::random_coordinates(rng), sdot = wlx::test::random_rates(rng);
    wlx::gen::ClosureJacobian J1, J2;
    wlx::gen::ClosureVector c1, c2;
    wlx::gen::BodyJacobians Jv1, Jv2;
    wlx::gen::closure(s, p, {.dPhi_ds = &J1});
    wlx::baked::closure(s, ignored, {.dPhi_ds = &J2});
    wlx::gen::convective(s, sdot, p, {.dPhi_ds_dot_sdot = &c1});
    wlx::baked::convective(s, sdot, ignored, {.dPhi_ds_dot_sdot = &c2});
    wlx::gen::bodies(s, sdot, p, {.Jv = &Jv1});
    wlx::baked::bodies(s, sdot, ignored, {.Jv = &Jv2});
    worst = std::max({worst, (J1 - J2).cwiseAbs().maxCoeff(), (c1 - c2).cwiseAbs().maxCoeff()});
    for (int b = 0; b < wlx::gen::kBodyCount; ++b) worst = std::max(worst, (Jv1[b] - Jv2[b]).cwiseAbs().maxCoeff());
  }
  // Constant folding may round 0.5*cxd differently from a run-time product: a few ulps.
  CHECK(worst <= 1e-12);
}
