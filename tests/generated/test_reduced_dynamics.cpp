// reduced_dynamics (the composite-rigid-body pass in the joints' own frames, projected on the
// commanded speeds) against Kane's sums written out over the bodies' full Jacobians from bodies()
// (itself checked against exact derivatives in test_bodies.cpp).
#include "../helpers/kane_over_bodies.hpp"
#include "../helpers/random.hpp"

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
  if (a.size() == 0) return 0;  // a model without wheels or closure rows: nothing to compare
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
    const gen::Coordinates s = test::random_coordinates(rng);
    gen::Coordinates sdot = test::random_rates(rng);
    std::vector<bool> dense;
    const gen::RateBasis T = structured_basis(rng, dense);
    // The inputs held in a step (T's zero rows) do not move: s' = T u is zero there, and the
    // recursions in the joints' own frames leave their joints out.
    for (int j = 0; j < gen::kCoordinateCount; ++j)
      if (T.row(j).isZero()) sdot(j) = 0;
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
  gen::ClosureVector conv, conv_alone;
  gen::WheelVector C_conv, C_conv_alone;
  gen::reduced_dynamics(s, sdot, T, p,
                        {.dPhi_ds_dot_sdot = &conv, .C_dot_sdot = &C_conv, .M = &M, .b_velocity = &b, .B_bias = &B, .Q_gravity = &Q});
  // The convective terms share their own temporaries in a scope of their own (emit_function.cpp):
  // each alone, and the lane code's outputs without them.
  gen::reduced_dynamics(s, sdot, T, p, {.dPhi_ds_dot_sdot = &conv_alone});
  gen::reduced_dynamics(s, sdot, T, p, {.C_dot_sdot = &C_conv_alone});
  gen::reduced_dynamics(s, sdot, T, p, {.M = &M_alone});
  gen::reduced_dynamics(s, sdot, T, p, {.b_velocity = &b_alone});
  gen::reduced_dynamics(s, sdot, T, p, {.B_bias = &B_alone});
  gen::reduced_dynamics(s, sdot, T, p, {.Q_gravity = &Q_alone});
  CHECK(conv == conv_alone);
  CHECK(C_conv == C_conv_alone);
  CHECK(M == M_alone);
  CHECK(b == b_alone);
  CHECK(B == B_alone);
  CHECK(Q == Q_alone);
}

// generalized_forces (the recursive Newton-Euler pass: spatial velocities and accelerations out
// along the chains, wrenches back) against two independent references: Kane's sums over the bodies'
// Jacobians, M u' + b_velocity + B s''_bias - Q_gravity for s'' = T u' + s''_bias, and tau, the
// bodies' equations projected through their full Jacobians, J^T (D (J s'' + J_dot s') + ...).
TEST_CASE("generalized_forces: Q* = M u' + b - Q_gravity of Kane's sums, tau = the bodies' forces through their Jacobians") {
  std::mt19937_64 rng(83);
  std::uniform_real_distribution<double> any(-2, 2);
  const gen::Params p;
  test::KaneSums ref;
  gen::CommandVector Qstar, Qstar_alone;
  gen::Coordinates tau;
  double worst_Q = 0, worst_tau = 0, held = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    std::vector<bool> dense;
    const gen::RateBasis T = structured_basis(rng, dense);
    // s' = T u, as in a step: the held inputs' rates are zero (their joints are left out).
    gen::CommandVector u, u_dot;
    for (int k = 0; k < gen::kCommandedCount; ++k) u(k) = any(rng), u_dot(k) = any(rng);
    const gen::Coordinates sdot = T * u;
    gen::Coordinates bias = gen::Coordinates::Zero();  // s''_bias lives on the dense coordinates
    for (int j = 0; j < gen::kCoordinateCount; ++j)
      if (dense[static_cast<std::size_t>(j)]) bias(j) = any(rng);
    const gen::Coordinates sddot = T * u_dot + bias;
    gen::generalized_forces(s, sdot, sddot, T, p, {.Qstar = &Qstar, .tau = &tau});
    gen::generalized_forces(s, sdot, sddot, T, p, {.Qstar = &Qstar_alone});
    CHECK(Qstar == Qstar_alone);
    test::kane_over_bodies(p, s, sdot, T, ref);
    const gen::CommandVector kane = ref.M * u_dot + ref.b_velocity + ref.B * bias - ref.Q_gravity;
    worst_Q = std::max(worst_Q, relative(Qstar, kane));
    // tau over the bodies' Jacobians, in K0: force m (a + g e_z), moment R (I alpha_b + omega_b x I omega_b).
    gen::Coordinates tau_ref = gen::Coordinates::Zero();
    for (int i = 0; i < gen::kBodyCount; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const auto& info = gen::kBodyMass[k];
      const double m = p.*info.mass;
      const Eigen::Vector3d I(p.*info.inertia[0], p.*info.inertia[1], p.*info.inertia[2]);
      const Eigen::Matrix3d& R = ref.R[k];
      const Eigen::Vector3d a = ref.Jv[k] * sddot + ref.Jv_dot.col(i);
      const Eigen::Vector3d omega = R.transpose() * (ref.Jw[k] * sdot);
      const Eigen::Vector3d alpha = R.transpose() * (ref.Jw[k] * sddot + ref.Jw_dot.col(i));
      const Eigen::Vector3d force = m * (a + Eigen::Vector3d(0, 0, p.*gen::kGravity));
      const Eigen::Vector3d moment = R * (I.cwiseProduct(alpha) + omega.cross(I.cwiseProduct(omega)));
      tau_ref.noalias() += ref.Jv[k].transpose() * force + ref.Jw[k].transpose() * moment;
    }
    // The held inputs (T's zero rows) move nothing in a step: generalized_forces leaves them 0.
    for (int j = 0; j < gen::kCoordinateCount; ++j)
      if (T.row(j).isZero()) {
        held = std::max(held, std::abs(tau(j)));
        tau_ref(j) = 0;
      }
    worst_tau = std::max(worst_tau, relative(tau, tau_ref));
  }
  // Relative to the largest entry, as above: the two formulations differ in the order of their sums.
  MESSAGE("largest relative differences: Q* " << worst_Q << ", tau " << worst_tau);
  CHECK(worst_Q <= 1e-12);
  CHECK(worst_tau <= 1e-12);
  CHECK(held == 0);
}
