// Non-holonomic rows C(s), spin rows and (d/dt C) s' against exact derivatives of the reference.
#include "../helpers/random.hpp"
#include "../helpers/reference_chain.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/convective.hpp>
#include <wlx/gen/nonholonomic.hpp>

#include <cmath>

using namespace wlx;

TEST_CASE("nonholonomic: C s' = v_W . n_W, spin s' = v_W . e_x / w, (d/dt C) s' exact") {
  std::mt19937_64 rng(20);
  const gen::Params p;
  gen::WheelRows C, spin;
  gen::ClosureVector conv_phi;
  gen::WheelVector conv_C;
  const int contact[2] = {gen::frame::W_l, gen::frame::W_r};
  double worst_C = 0, worst_spin = 0, worst_conv = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    const gen::Coordinates sdot = test::random_rates(rng);
    gen::nonholonomic(s, p, {.C = &C, .spin = &spin});
    gen::convective(s, sdot, p, {.dPhi_ds_dot_sdot = &conv_phi, .C_dot_sdot = &conv_C});
    const auto ref = test::reference_kinematics(test::along(s, sdot), p);
    for (int w = 0; w < 2; ++w) {
      const auto& P = ref.frames[contact[w]];
      test::V3<double> v, a, n, n_dot, e;
      for (int i = 0; i < 3; ++i) {
        v[i] = P.r[i].d;
        a[i] = P.r[i].dd;
        n[i] = P.R[i][1].v;
        n_dot[i] = P.R[i][1].d;
        e[i] = P.R[i][0].v;
      }
      worst_C = std::max(worst_C, std::abs(C.row(w).dot(sdot) - test::dot(v, n)));
      worst_spin = std::max(worst_spin, std::abs(spin.row(w).dot(sdot) - test::dot(v, e) / p.w));
      worst_conv = std::max(worst_conv, std::abs(conv_C(w) - (test::dot(a, n) + test::dot(v, n_dot))));
    }
  }
  MESSAGE("max errors: C s' " << worst_C << ", spin s' " << worst_spin << ", (d/dt C) s' " << worst_conv);
  CHECK(worst_C <= 1e-12);
  CHECK(worst_spin <= 1e-12);
  CHECK(worst_conv <= 1e-11);
}

TEST_CASE("nonholonomic: C has the structural zeros of the model") {
  // The left wheel's constraint cannot depend on the legs or the right lever.
  std::mt19937_64 rng(21);
  const gen::Params p;
  gen::WheelRows C;
  gen::nonholonomic(test::random_coordinates(rng), p, {.C = &C});
  namespace c = gen::coord;
  for (int j : {c::psi_l2, c::psi_l3, c::psi_l4, c::x_Fl, c::theta_r2, c::theta_r5, c::z_Wl}) CHECK(C(0, j) == 0.0);
  CHECK(C(0, c::theta_l5) != 0.0);
  // theta_2 turns the contact frame about its own x axis through the contact point: no velocity.
  CHECK(C(0, c::theta_l2) == 0.0);
}
