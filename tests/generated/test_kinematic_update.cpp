// The fused kinematic update computes exactly what kinematics, closure and nonholonomic compute.
#include "../helpers/random.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/all.hpp>

#include <cmath>
#include <limits>

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
    gen::kinematic_update(s, p, {.positions = &pos_a, .rotations = &rot_a, .Phi = &phi_a, .dPhi_ds = &J_a, .C = &C_a});
    gen::kinematics(s, p, {.positions = &pos_b, .rotations = &rot_b});
    gen::closure(s, p, {.Phi = &phi_b, .dPhi_ds = &J_b});
    gen::nonholonomic(s, p, {.C = &C_b});
    worst = std::max({worst, (pos_a - pos_b).cwiseAbs().maxCoeff(), (phi_a - phi_b).cwiseAbs().maxCoeff(),
                      (J_a - J_b).cwiseAbs().maxCoeff(), (C_a - C_b).cwiseAbs().maxCoeff()});
    for (int f = 0; f < gen::kFrameCount; ++f) worst = std::max(worst, (rot_a[f] - rot_b[f]).cwiseAbs().maxCoeff());
  }
  CHECK(worst <= 1e-13);
  // Requesting only some outputs computes the same values for those (the shared temporaries
  // are still evaluated when an output needs them).
  const gen::Coordinates s = test::random_coordinates(rng);
  gen::kinematic_update(s, p, {.positions = &pos_a, .rotations = &rot_a, .Phi = &phi_a, .dPhi_ds = &J_a, .C = &C_a});
  J_b.setConstant(7.0);
  C_b.setConstant(7.0);
  gen::kinematic_update(s, p, {.dPhi_ds = &J_b, .C = &C_b});
  CHECK(J_a == J_b);
  CHECK(C_a == C_b);
}

namespace {

// With zero_fill = false a function must write exactly its nonzero pattern: every entry it leaves
// untouched (still the NaN sentinel) is zero in the zero-filled result, and every entry it
// writes equals that result: bit for bit in a plain build; within a few ulp where the compiler may
// contract a * b + c into one FMA differently in the two inlined copies (-march=native builds).
template <class Matrix>
void check_pattern(const Matrix& filled, const Matrix& sparse, long& untouched) {
  for (Eigen::Index i = 0; i < filled.size(); ++i) {
    if (std::isnan(sparse.data()[i])) {
      CHECK(filled.data()[i] == 0.0);
      ++untouched;
    } else {
      CHECK(std::abs(sparse.data()[i] - filled.data()[i]) <=
            4 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(filled.data()[i])));
    }
  }
}

}  // namespace

TEST_CASE("zero_fill = false writes the nonzeros only, and the same values") {
  std::mt19937_64 rng(71);
  const gen::Params p;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int trial = 0; trial < 20; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng);
    long untouched = 0;
    gen::ClosureJacobian J_full, J_sparse = gen::ClosureJacobian::Constant(nan);
    gen::WheelRows C_full, C_sparse = gen::WheelRows::Constant(nan), spin_full, spin_sparse = gen::WheelRows::Constant(nan);
    gen::kinematic_update(s, p, {.dPhi_ds = &J_full, .C = &C_full});
    gen::kinematic_update(s, p, {.dPhi_ds = &J_sparse, .C = &C_sparse}, false);
    check_pattern(J_full, J_sparse, untouched);
    check_pattern(C_full, C_sparse, untouched);
    J_sparse.setConstant(nan);
    gen::closure(s, p, {.dPhi_ds = &J_sparse}, false);
    check_pattern(J_full, J_sparse, untouched);
    C_sparse.setConstant(nan);
    gen::nonholonomic(s, p, {.C = &C_full, .spin = &spin_full});
    gen::nonholonomic(s, p, {.C = &C_sparse, .spin = &spin_sparse}, false);
    check_pattern(C_full, C_sparse, untouched);
    check_pattern(spin_full, spin_sparse, untouched);
    gen::BodyJacobians Jv_full, Jw_full, Jv_sparse, Jw_sparse;
    for (auto& m : Jv_sparse) m.setConstant(nan);
    for (auto& m : Jw_sparse) m.setConstant(nan);
    gen::bodies(s, sdot, p, {.Jv = &Jv_full, .Jw = &Jw_full});
    gen::bodies(s, sdot, p, {.Jv = &Jv_sparse, .Jw = &Jw_sparse}, false);
    for (std::size_t b = 0; b < Jv_full.size(); ++b) {
      check_pattern(Jv_full[b], Jv_sparse[b], untouched);
      check_pattern(Jw_full[b], Jw_sparse[b], untouched);
    }
    // Most entries are structural zeros (dPhi/ds alone has 350 of 448), so this is not vacuous.
    CHECK(untouched > 1900);
  }
}
