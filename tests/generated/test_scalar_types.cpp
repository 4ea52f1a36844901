// The generated functions as templates on the scalar type: float agrees with double to float
// precision, the float IK solves what the double IK solves, and a dual number (Jet) through the
// generated closure and body functions gives the generated Jacobians and convective terms.
#include "../helpers/jet_eigen.hpp"
#include "../helpers/random.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/all.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

using namespace wlx;

namespace {

// max |a - b| / max(1, max |b|): float's error relative to the output's scale.
template <typename A, typename B>
double scaled_difference(const A& a, const B& b) {
  return (a.template cast<double>() - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

}  // namespace

TEST_CASE("float: every generated function agrees with double to float precision") {
  // Both evaluate at the same point (the float coordinates, widened), so the difference is float's
  // arithmetic alone. Float's unit roundoff is 6e-8; outputs are sums of a few dozen products of
  // sines and lengths up to 5 m, each rounding once: 2e-6 of the output's scale is about 30
  // roundoffs, and a wrong term in the float path (a double constant truncated, a missed cast)
  // would show as 1e-3 or more.
  std::mt19937_64 rng(31);
  const gen::Params p;
  double worst[6] = {};
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::CoordinatesOf<float> s_f = test::random_coordinates(rng).cast<float>();
    const gen::CoordinatesOf<float> sdot_f = test::random_rates(rng).cast<float>();
    const gen::Coordinates s = s_f.cast<double>(), sdot = sdot_f.cast<double>();

    gen::FramePositionsOf<float> pos_f;
    gen::FramePositions pos;
    gen::kinematics(s_f, p, {.positions = &pos_f});
    gen::kinematics(s, p, {.positions = &pos});
    worst[0] = std::max(worst[0], scaled_difference(pos_f, pos));

    gen::ClosureVectorOf<float> Phi_f;
    gen::ClosureJacobianOf<float> J_f;
    gen::ClosureVector Phi;
    gen::ClosureJacobian J;
    gen::closure(s_f, p, {.Phi = &Phi_f, .dPhi_ds = &J_f});
    gen::closure(s, p, {.Phi = &Phi, .dPhi_ds = &J});
    worst[1] = std::max({worst[1], scaled_difference(Phi_f, Phi), scaled_difference(J_f, J)});

    gen::WheelRowsOf<float> C_f;
    gen::WheelRows C;
    gen::nonholonomic(s_f, p, {.C = &C_f});
    gen::nonholonomic(s, p, {.C = &C});
    worst[2] = std::max(worst[2], scaled_difference(C_f, C));

    gen::ClosureVectorOf<float> conv_f;
    gen::ClosureVector conv;
    gen::convective(s_f, sdot_f, p, {.dPhi_ds_dot_sdot = &conv_f});
    gen::convective(s, sdot, p, {.dPhi_ds_dot_sdot = &conv});
    worst[3] = std::max(worst[3], scaled_difference(conv_f, conv));

    gen::BodyVectorsOf<float> com_f;
    gen::BodyJacobiansOf<float> Jv_f;
    gen::BodyVectors com;
    gen::BodyJacobians Jv;
    gen::bodies(s_f, sdot_f, p, {.com = &com_f, .Jv = &Jv_f});
    gen::bodies(s, sdot, p, {.com = &com, .Jv = &Jv});
    worst[4] = std::max(worst[4], scaled_difference(com_f, com));
    for (int b = 0; b < gen::kBodyCount; ++b)
      worst[4] = std::max(worst[4], scaled_difference(Jv_f[static_cast<std::size_t>(b)], Jv[static_cast<std::size_t>(b)]));

    float lowest_f = 0;
    double lowest = 0;
    gen::clearance(s_f, p, {.lowest = &lowest_f});
    gen::clearance(s, p, {.lowest = &lowest});
    worst[5] = std::max(worst[5], std::abs(double(lowest_f) - lowest) / std::max(1.0, std::abs(lowest)));
  }
  MESSAGE("float vs double, relative to scale: kinematics " << worst[0] << ", closure " << worst[1] << ", nonholonomic "
                                                            << worst[2] << ", convective " << worst[3] << ", bodies "
                                                            << worst[4] << ", clearance " << worst[5]);
  for (double w : worst) CHECK(w <= 2e-6);
}

TEST_CASE("float: the closed-form IK solves what double solves, to the float IK's tolerance") {
  // Cabin poses and foot targets around the nominal state (0.3 m, 10 degrees), every limb on
  // branch 0. The float solution put into the closure in double must meet ik_tolerance<float>()
  // (2.3e-5 m: rounding leaves about 1e-6 at these lengths), and its joints must agree with the
  // double solution to 2e-5 rad (measured 1.9e-6: float roundoff amplified by the limbs here).
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<double> offset(-0.3, 0.3), tilt(-10 * std::numbers::pi / 180, 10 * std::numbers::pi / 180);
  const gen::Params p;
  double worst_residual = 0, worst_joint = 0;
  int solved = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    gen::Coordinates s = gen::Coordinates::Zero();
    for (int k = 0; k < gen::kInputCount; ++k) s(k) = gen::kNominalInputs[static_cast<std::size_t>(k)];
    for (int k : {gen::coord::x_C, gen::coord::y_C, gen::coord::z_C, gen::coord::x_Fl, gen::coord::y_Fl, gen::coord::z_Fl,
                  gen::coord::x_Fr, gen::coord::y_Fr, gen::coord::z_Fr})
      s(k) += offset(rng);
    for (int k : {gen::coord::yaw, gen::coord::pitch, gen::coord::roll, gen::coord::psi_l1, gen::coord::psi_r1}) s(k) += tilt(rng);
    gen::CoordinatesOf<float> s_f = s.cast<float>();
    s = s_f.cast<double>();  // the same targets in both
    std::array<int, gen::kLimbCount> branches{};
    int failed = 0;
    gen::IkDiagnostics why;
    if (gen::ik_all(s, p, branches, s, failed, why) != gen::IkStatus::ok) continue;
    REQUIRE(gen::ik_all(s_f, p, branches, s_f, failed, why) == gen::IkStatus::ok);
    ++solved;
    gen::ClosureVector Phi;
    gen::closure(s_f.cast<double>().eval(), p, {.Phi = &Phi});
    worst_residual = std::max(worst_residual, Phi.cwiseAbs().maxCoeff());
    worst_joint = std::max(worst_joint, (s_f.cast<double>() - s).tail<gen::kDependentCount>().cwiseAbs().maxCoeff());
  }
  MESSAGE(solved << " poses: float IK closure residual (in double) " << worst_residual << " m, joints vs double "
                 << worst_joint << " rad");
  CHECK(solved >= 1000);
  CHECK(worst_residual <= double(gen::ik_tolerance<float>()));
  CHECK(worst_joint <= 2e-5);
}

TEST_CASE("Jet: a dual number through the generated functions gives their generated Jacobians") {
  // s(t) = s + t u in Jets: d/dt Phi = dPhi/ds u, d2/dt2 Phi = (d/dt dPhi/ds) u (the convective
  // output with sdot = u); likewise the bodies' CoM against Jv u and Jv' u. Both sides are the
  // same derivative computed two ways, rounding apart: entries O(10) (O(100) for second
  // derivatives), so 1e-12 (1e-11) is a few hundred roundoffs.
  std::mt19937_64 rng(33);
  const gen::Params p;
  double worst_first = 0, worst_second = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng), u = test::random_rates(rng);
    gen::CoordinatesOf<test::Jet> s_jet;
    for (int i = 0; i < gen::kCoordinateCount; ++i) s_jet(i) = test::Jet(s(i), u(i), 0.0);

    gen::ClosureVectorOf<test::Jet> Phi_jet;
    gen::closure(s_jet, p, {.Phi = &Phi_jet});
    gen::ClosureJacobian J;
    gen::ClosureVector conv;
    gen::closure(s, p, {.dPhi_ds = &J});
    gen::convective(s, u, p, {.dPhi_ds_dot_sdot = &conv});
    const gen::ClosureVector Ju = J * u;
    for (int i = 0; i < gen::kClosureCount; ++i) {
      worst_first = std::max(worst_first, std::abs(Phi_jet(i).d - Ju(i)));
      worst_second = std::max(worst_second, std::abs(Phi_jet(i).dd - conv(i)));
    }

    gen::BodyVectorsOf<test::Jet> com_jet;
    gen::bodies(s_jet, gen::CoordinatesOf<test::Jet>(u.cast<test::Jet>()), p, {.com = &com_jet});
    gen::BodyJacobians Jv;
    gen::BodyVectors Jv_dot_u;
    gen::bodies(s, u, p, {.Jv = &Jv, .Jv_dot_sdot = &Jv_dot_u});
    for (int b = 0; b < gen::kBodyCount; ++b) {
      const Eigen::Vector3d v = Jv[static_cast<std::size_t>(b)] * u;
      for (int k = 0; k < 3; ++k) {
        worst_first = std::max(worst_first, std::abs(com_jet(k, b).d - v(k)));
        worst_second = std::max(worst_second, std::abs(com_jet(k, b).dd - Jv_dot_u(k, b)));
      }
    }
  }
  MESSAGE("Jet vs generated Jacobians: first derivatives " << worst_first << ", second " << worst_second);
  CHECK(worst_first <= 1e-12);
  CHECK(worst_second <= 1e-11);
}
