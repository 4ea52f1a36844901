// The fused kinematic update computes exactly what kinematics, closure and nonholonomic compute.
#include "../support/random.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/all.hpp>

using namespace wlx;

TEST_CASE("kinematic_update: identical to the separate functions") {
  // Same expressions, same emitted arithmetic per output (CSE only shares; it does not
  // reassociate), so the results agree to rounding of shared temporaries: 1e-13 absolute.
  std::mt19937_64 rng(70);
  const gen::Params p;
  gen::FramePositions pos_a, pos_b;
  gen::FrameRotations rot_a, rot_b;
  gen::ClosureVector phi_a, phi_b;
  gen::ClosureJacobian J_a, J_b;
  gen::WheelRows C_a, C_b;
  double worst = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    gen::kinematic_update(s, p, &pos_a, &rot_a, &phi_a, &J_a, &C_a);
    gen::kinematics(s, p, &pos_b, &rot_b);
    gen::closure(s, p, &phi_b, &J_b);
    gen::nonholonomic(s, p, &C_b, nullptr);
    worst = std::max({worst, (pos_a - pos_b).cwiseAbs().maxCoeff(), (phi_a - phi_b).cwiseAbs().maxCoeff(),
                      (J_a - J_b).cwiseAbs().maxCoeff(), (C_a - C_b).cwiseAbs().maxCoeff()});
    for (int f = 0; f < gen::kFrameCount; ++f) worst = std::max(worst, (rot_a[f] - rot_b[f]).cwiseAbs().maxCoeff());
  }
  CHECK(worst <= 1e-13);
  // Requesting only some outputs computes the same values for those (the shared temporaries
  // are still evaluated when an output needs them).
  const gen::Coordinates s = test::random_coordinates(rng);
  gen::kinematic_update(s, p, &pos_a, &rot_a, &phi_a, &J_a, &C_a);
  J_b.setConstant(7.0);
  C_b.setConstant(7.0);
  gen::kinematic_update(s, p, nullptr, nullptr, nullptr, &J_b, &C_b);
  CHECK(J_a == J_b);
  CHECK(C_a == C_b);
}
