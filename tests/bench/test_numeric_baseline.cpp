// The numeric baseline the benchmarks compare against computes the same quantities: a ratio
// against a baseline that computed something else would mean nothing.
#include "../../bench/numeric_baseline.hpp"
#include "../helpers/random.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/all.hpp>

using namespace wlx;

TEST_CASE("numeric baseline: frames, Jacobians, C(s), convective terms and bodies agree with the generated code") {
  // The baseline's central differences (h = 1e-6) are good to ~1e-9, its second differences
  // (h = 1e-4) to ~1e-6; the tolerances follow.
  std::mt19937_64 rng(80);
  const gen::Params p;
  baseline::Frames w;
  gen::FramePositions pos;
  gen::ClosureJacobian J, Jn;
  gen::WheelRows C, Cn;
  gen::ClosureVector conv, conv_n;
  gen::WheelVector Cc, Cc_n;
  gen::BodyJacobians Jv, Jw, Jv_n, Jw_n;
  double e_pos = 0, e_J = 0, e_C = 0, e_conv = 0, e_body = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng);
    baseline::frames(p, s, w);
    gen::kinematics(s, p, {.positions = &pos});
    for (int f = 0; f < gen::kFrameCount; ++f) e_pos = std::max(e_pos, (pos.col(f) - w.r[f]).cwiseAbs().maxCoeff());
    gen::closure(s, p, {.dPhi_ds = &J});
    baseline::closure_jacobian(p, s, Jn, w);
    e_J = std::max(e_J, (J - Jn).cwiseAbs().maxCoeff());
    gen::nonholonomic(s, p, {.C = &C});
    baseline::nonholonomic_rows(p, s, Cn, w);
    e_C = std::max(e_C, (C - Cn).cwiseAbs().maxCoeff());
    gen::convective(s, sdot, p, {.dPhi_ds_dot_sdot = &conv, .C_dot_sdot = &Cc});
    baseline::convective(p, s, sdot, conv_n, Cc_n, w);
    e_conv = std::max({e_conv, (conv - conv_n).cwiseAbs().maxCoeff() / (1 + conv.cwiseAbs().maxCoeff()),
                       (Cc - Cc_n).cwiseAbs().maxCoeff() / (1 + Cc.cwiseAbs().maxCoeff())});
    gen::bodies(s, sdot, p, {.Jv = &Jv, .Jw = &Jw});
    baseline::body_jacobians(p, s, Jv_n, Jw_n, w);
    for (int k = 0; k < gen::kBodyCount; ++k)
      e_body = std::max({e_body, (Jv[k] - Jv_n[k]).cwiseAbs().maxCoeff(), (Jw[k] - Jw_n[k]).cwiseAbs().maxCoeff()});
  }
  MESSAGE("baseline vs generated: positions " << e_pos << ", dPhi/ds " << e_J << ", C " << e_C << ", convective (rel.) "
                                               << e_conv << ", body Jacobians " << e_body);
  CHECK(e_pos <= 1e-12);
  CHECK(e_J <= 1e-7);
  CHECK(e_C <= 1e-7);
  CHECK(e_conv <= 1e-4);
  CHECK(e_body <= 1e-7);
}

TEST_CASE("numeric baseline: Newton with finite-difference Jacobians solves the nominal pose") {
  const gen::Params p;
  baseline::Frames w;
  gen::Coordinates s = gen::Coordinates::Zero();
  s(gen::coord::z_C) = 2;
  s(gen::coord::x_Fl) = s(gen::coord::x_Fr) = 3.5;
  s(gen::coord::y_Fl) = 1.5;
  s(gen::coord::y_Fr) = -1.5;
  s(gen::coord::z_Wr) = 0.05;
  s(gen::coord::psi_l4) = s(gen::coord::psi_r4) = 1.0;  // start with bent knees
  s(gen::coord::theta_l6) = s(gen::coord::theta_r6) = -0.5;
  s(gen::coord::theta_l3) = s(gen::coord::theta_r3) = 0.5;
  const int iterations = baseline::newton_ik(p, s, w);
  CHECK(iterations < 50);
  CHECK(baseline::closure(p, s, w).cwiseAbs().maxCoeff() <= 1e-12);
}
