// The double overloads of the generated functions take an AVX2 + FMA build of the same body on a
// CPU that has them (types.hpp). Both builds evaluate the same expressions; fused multiply-adds
// only round once where the portable build rounds twice, so they agree to rounding, and on such a
// CPU they must differ somewhere (else the overload did not switch).
#include "../helpers/random.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/all.hpp>

#include <algorithm>
#include <cmath>

using namespace wlx;

namespace {

bool accelerated() {
#if defined(WLX_GEN_MULTIVERSION)
  return gen::detail::has_avx2_fma();
#else
  return false;
#endif
}

// Largest |a - b| over the entries, and whether any bit differs.
struct Comparison {
  double worst = 0;
  bool differs = false;
  template <class A, class B>
  void add(const A& a, const B& b) {
    worst = std::max(worst, (a - b).cwiseAbs().maxCoeff());
    differs = differs || !(a.array() == b.array()).all();
  }
  // Relative to the largest entry (at least 1): for the dynamics' terms, whose size is the masses'.
  template <class A, class B>
  void add_scaled(const A& a, const B& b) {
    add(a / std::max(1.0, a.cwiseAbs().maxCoeff()), b / std::max(1.0, a.cwiseAbs().maxCoeff()));
  }
};

}  // namespace

TEST_CASE("multiversion: the AVX2 + FMA build of every generated function agrees with the portable one") {
  std::mt19937_64 rng(71);
  const gen::Params p;
  gen::ClosureJacobian J_a, J_b;
  gen::WheelRows C_a, C_b;
  gen::ClosureVector conv_a, conv_b;
  gen::WheelVector C_conv_a, C_conv_b;
  gen::BodyJacobians Jv_a, Jv_b;
  gen::BodyVectors com_a, com_b, a_a, a_b;
  gen::CommandMatrix M_a, M_b;
  gen::CommandVector b_a, b_b, Q_a, Q_b;
  gen::CommandRows B_a, B_b;
  Comparison c;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng);
    gen::dynamics_update(s, p, {.dPhi_ds = &J_a, .C = &C_a});
    gen::dynamics_update<double>(s, p, {.dPhi_ds = &J_b, .C = &C_b});
    c.add(J_a, J_b);
    c.add(C_a, C_b);
    gen::bodies(s, sdot, p, {.com = &com_a, .Jv = &Jv_a, .Jv_dot_sdot = &a_a});
    gen::bodies<double>(s, sdot, p, {.com = &com_b, .Jv = &Jv_b, .Jv_dot_sdot = &a_b});
    c.add(com_a, com_b);
    c.add(a_a, a_b);
    for (int i = 0; i < gen::kBodyCount; ++i) c.add(Jv_a[static_cast<std::size_t>(i)], Jv_b[static_cast<std::size_t>(i)]);
    const gen::RateBasis T = gen::RateBasis::Random();
    gen::reduced_dynamics(s, sdot, T, p,
                          {.dPhi_ds_dot_sdot = &conv_a, .C_dot_sdot = &C_conv_a, .M = &M_a, .b_velocity = &b_a,
                           .B_bias = &B_a, .Q_gravity = &Q_a});
    gen::reduced_dynamics<double>(s, sdot, T, p,
                                  {.dPhi_ds_dot_sdot = &conv_b, .C_dot_sdot = &C_conv_b, .M = &M_b,
                                   .b_velocity = &b_b, .B_bias = &B_b, .Q_gravity = &Q_b});
    c.add(conv_a, conv_b);
    c.add(C_conv_a, C_conv_b);
    c.add_scaled(M_a, M_b);
    c.add_scaled(b_a, b_b);
    c.add_scaled(B_a, B_b);
    c.add_scaled(Q_a, Q_b);
    gen::kinematic_update(s, p, {.dPhi_ds = &J_a, .C = &C_a});
    gen::kinematic_update<double>(s, p, {.dPhi_ds = &J_b, .C = &C_b});
    c.add(J_a, J_b);
    c.add(C_a, C_b);
    gen::convective(s, sdot, p, {.dPhi_ds_dot_sdot = &conv_a});
    gen::convective<double>(s, sdot, p, {.dPhi_ds_dot_sdot = &conv_b});
    c.add(conv_a, conv_b);
  }
  // Coordinates within +-pi rad and +-5 m, rates +-2: entries up to about 1e2 (convective terms), so
  // 1e-12 is a few ulp of the largest; a wrong expression would be off by far more. The dynamics'
  // terms (masses of tonnes) are compared relative to their largest entry.
  MESSAGE("AVX2 + FMA build in use: " << accelerated() << "; largest difference " << c.worst);
  CHECK(c.worst <= 1e-12);
  CHECK(c.differs == accelerated());
}

TEST_CASE("multiversion: the closed-form IK's AVX2 + FMA build agrees with the portable one") {
  std::mt19937_64 rng(72);
  std::uniform_real_distribution<double> nudge(-0.05, 0.05);
  const gen::Params p;
  Comparison c;
  int solved = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    gen::Coordinates s = gen::Coordinates::Zero();
    for (int i = 0; i < gen::kInputCount; ++i) s(i) = gen::kNominalInputs[static_cast<std::size_t>(i)] + nudge(rng);
    gen::Coordinates out_a = s, out_b = s;
    int failed_a = -1, failed_b = -1;
    gen::IkDiagnostics why_a, why_b;
    const std::array<int, gen::kLimbCount> branches{};
    const gen::IkStatus a = gen::ik_all(s, p, branches, out_a, failed_a, why_a);
    const gen::IkStatus b = gen::ik_all<double>(s, p, branches, out_b, failed_b, why_b);
    REQUIRE(a == b);
    REQUIRE(failed_a == failed_b);
    if (a != gen::IkStatus::ok) continue;
    ++solved;
    c.add(out_a, out_b);
  }
  MESSAGE("solved " << solved << " of 1000; largest difference " << c.worst);
  CHECK(solved >= 900);  // the nominal pose nudged by 5 cm / 0.05 rad stays in reach
  CHECK(c.worst <= 1e-12);
  CHECK(c.differs == accelerated());
}
