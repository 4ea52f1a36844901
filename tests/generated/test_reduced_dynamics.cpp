// reduced_dynamics (Kane's sums on the commanded speeds, generated on lanes from the joints'
// twists and the bodies' wrenches) against the same sums written out over the bodies' full
// Jacobians from bodies() (itself checked against exact derivatives in test_bodies.cpp).
#include "../support/kane_over_bodies.hpp"
#include "../support/random.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/all.hpp>

#include <algorithm>
#include <cmath>

using namespace wlx;

namespace {

// A rate basis with the structure the model file fixes (what reduced_dynamics relies on): unit rows
// for the commanded speeds, zero rows for the other inputs, and in the rows of the dependent pair and
// of the dependent joints random entries where kRateBasisPattern allows one (zero elsewhere).
gen::RateBasis structured_basis(std::mt19937_64& rng, std::vector<bool>& dense) {
  std::uniform_real_distribution<double> any(-2, 2);
  gen::RateBasis T = gen::RateBasis::Zero();
  dense.assign(gen::kCoordinateCount, false);
  const auto pair = gen::kPairs[gen::kDynamicsPair].coordinates;
  for (int j = 0; j < gen::kCoordinateCount; ++j) {
    dense[static_cast<std::size_t>(j)] = j >= gen::kInputCount || std::find(pair.begin(), pair.end(), j) != pair.end();
    if (dense[static_cast<std::size_t>(j)])
      for (int k = 0; k < gen::kCommandedCount; ++k)
        if (gen::kRateBasisPattern[static_cast<std::size_t>(j)][static_cast<std::size_t>(k)]) T(j, k) = any(rng);
  }
  for (int k = 0; k < gen::kCommandedCount; ++k) T(gen::kCommanded[static_cast<std::size_t>(k)], k) = 1;
  return T;
}

double relative(const Eigen::MatrixXd& a, const Eigen::MatrixXd& reference) {
  return (a - reference).cwiseAbs().maxCoeff() / std::max(1.0, reference.cwiseAbs().maxCoeff());
}

}  // namespace

TEST_CASE("reduced_dynamics: M, b_velocity, B_bias and Q_gravity equal Kane's sums over the bodies' Jacobians") {
  std::mt19937_64 rng(81);
  const gen::Params p;
  gen::CommandMatrix M;
  gen::CommandVector b, Q;
  gen::CommandRows B;
  gen::ClosureVector conv, conv_ref;
  gen::WheelVector C_conv, C_conv_ref;
  test::KaneSums ref;
  double worst_M = 0, worst_b = 0, worst_B = 0, worst_Q = 0, worst_conv = 0, asymmetry = 0, outside = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng);
    std::vector<bool> dense;
    const gen::RateBasis T = structured_basis(rng, dense);
    gen::reduced_dynamics(s, sdot, T, p,
                          {.dPhi_ds_dot_sdot = &conv, .C_dot_sdot = &C_conv, .M = &M, .b_velocity = &b, .B_bias = &B, .Q_gravity = &Q});
    test::kane_over_bodies(p, s, sdot, T, ref);
    gen::convective(s, sdot, p, {.dPhi_ds_dot_sdot = &conv_ref, .C_dot_sdot = &C_conv_ref});
    // B_bias holds the dense columns only (s''_bias is zero elsewhere); the others must be zero.
    gen::CommandRows B_dense = ref.B;
    for (int j = 0; j < gen::kCoordinateCount; ++j)
      if (!dense[static_cast<std::size_t>(j)]) {
        B_dense.col(j).setZero();
        outside = std::max(outside, B.col(j).cwiseAbs().maxCoeff());
      }
    worst_M = std::max(worst_M, relative(M, ref.M));
    worst_b = std::max(worst_b, relative(b, ref.b_velocity));
    worst_B = std::max(worst_B, relative(B, B_dense));
    worst_Q = std::max(worst_Q, relative(Q, ref.Q_gravity));
    worst_conv = std::max({worst_conv, relative(conv, conv_ref), relative(C_conv, C_conv_ref)});
    asymmetry = std::max(asymmetry, (M - M.transpose()).cwiseAbs().maxCoeff());
  }
  // Relative to the largest entry: masses of tonnes, lever arms of metres and random rates make
  // entries of 1e4 to 1e6; the two sums differ only in their order, a few ulp each.
  MESSAGE("largest relative differences: M " << worst_M << ", b " << worst_b << ", B " << worst_B << ", Q " << worst_Q
                                             << ", convective " << worst_conv);
  CHECK(worst_M <= 1e-12);
  CHECK(worst_b <= 1e-12);
  CHECK(worst_B <= 1e-12);
  CHECK(worst_Q <= 1e-12);
  CHECK(worst_conv <= 1e-12);
  CHECK(asymmetry == 0);  // mirrored from one triangle
  CHECK(outside == 0);
}

TEST_CASE("reduced_dynamics: each output alone is what it is with all of them requested") {
  std::mt19937_64 rng(82);
  const gen::Params p;
  std::vector<bool> dense;
  const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng);
  const gen::RateBasis T = structured_basis(rng, dense);
  gen::CommandMatrix M, M_alone;
  gen::CommandVector b, Q, b_alone, Q_alone;
  gen::CommandRows B, B_alone;
  gen::reduced_dynamics(s, sdot, T, p, {.M = &M, .b_velocity = &b, .B_bias = &B, .Q_gravity = &Q});
  gen::reduced_dynamics(s, sdot, T, p, {.M = &M_alone});
  gen::reduced_dynamics(s, sdot, T, p, {.b_velocity = &b_alone});
  gen::reduced_dynamics(s, sdot, T, p, {.B_bias = &B_alone});
  gen::reduced_dynamics(s, sdot, T, p, {.Q_gravity = &Q_alone});
  CHECK(M == M_alone);
  CHECK(b == b_alone);
  CHECK(B == B_alone);
  CHECK(Q == Q_alone);
}
