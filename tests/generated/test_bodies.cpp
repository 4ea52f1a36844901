// Body kinematics for the dynamics against exact derivatives of the reference chain.
#include "../helpers/random.hpp"
#include "../helpers/reference_chain.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/bodies.hpp>

#include <cmath>

using namespace wlx;


TEST_CASE("bodies: CoM, rotation, Jv, Jw and their convective terms match exact derivatives") {
  std::mt19937_64 rng(30);
  const gen::Params p;
  gen::BodyVectors com, Jv_dot, Jw_dot;
  gen::BodyRotations R;
  gen::BodyJacobians Jv, Jw;
  double worst_pose = 0, worst_v = 0, worst_w = 0, worst_a = 0, worst_alpha = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    const gen::Coordinates sdot = test::random_rates(rng);
    gen::bodies(s, sdot, p,
                {.com = &com, .rotations = &R, .Jv = &Jv, .Jw = &Jw, .Jv_dot_sdot = &Jv_dot, .Jw_dot_sdot = &Jw_dot});
    const auto ref = test::reference_kinematics(test::along(s, sdot), p);
    for (int b = 0; b < gen::kBodyCount; ++b) {
      const auto& P = ref.bodies[b];
      const auto [omega, alpha] = test::angular_rates(P.R);
      const Eigen::Vector3d v = Jv[b] * sdot, w = Jw[b] * sdot;
      for (int i = 0; i < 3; ++i) {
        worst_pose = std::max(worst_pose, std::abs(com(i, b) - P.r[i].v));
        for (int j = 0; j < 3; ++j) worst_pose = std::max(worst_pose, std::abs(R[b](i, j) - P.R[i][j].v));
        worst_v = std::max(worst_v, std::abs(v(i) - P.r[i].d));
        worst_w = std::max(worst_w, std::abs(w(i) - omega[i]));
        worst_a = std::max(worst_a, std::abs(Jv_dot(i, b) - P.r[i].dd));
        worst_alpha = std::max(worst_alpha, std::abs(Jw_dot(i, b) - alpha[i]));
      }
    }
  }
  MESSAGE("max errors: pose " << worst_pose << ", Jv s' " << worst_v << ", Jw s' " << worst_w << ", Jv_dot s' "
                              << worst_a << ", Jw_dot s' " << worst_alpha);
  CHECK(worst_pose <= 1e-12);
  CHECK(worst_v <= 1e-12);
  CHECK(worst_w <= 1e-12);
  CHECK(worst_a <= 1e-11);
  CHECK(worst_alpha <= 1e-11);
}

TEST_CASE("bodies: each Jacobian column alone matches the exact partial derivative") {
  // Jv s' checks the columns only in combination; here each column is checked on its own.
  std::mt19937_64 rng(31);
  const gen::Params p;
  gen::BodyJacobians Jv;
  double worst = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    gen::bodies(s, gen::Coordinates::Zero(), p, {.Jv = &Jv});
    for (int j = 0; j < gen::kCoordinateCount; ++j) {
      const auto ref = test::reference_kinematics(test::along(s, gen::Coordinates::Unit(j)), p);
      for (int b = 0; b < gen::kBodyCount; ++b)
        for (int i = 0; i < 3; ++i) worst = std::max(worst, std::abs(Jv[b](i, j) - ref.bodies[b].r[i].d));
    }
  }
  CHECK(worst <= 1e-12);
}
