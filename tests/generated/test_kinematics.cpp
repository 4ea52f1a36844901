// Generated forward kinematics against an independent chain and the thesis' printed equations.
#include "../helpers/random.hpp"
#include "../helpers/reference_chain.hpp"

#include <doctest/doctest.h>
#include <wlx/gen/kinematics.hpp>

#include <cmath>

using namespace wlx;

namespace {

std::array<double, gen::kCoordinateCount> as_array(const gen::Coordinates& s) {
  std::array<double, gen::kCoordinateCount> a;
  for (int i = 0; i < gen::kCoordinateCount; ++i) a[static_cast<std::size_t>(i)] = s(i);
  return a;
}

}  // namespace

TEST_CASE("kinematics: every frame matches the reference chain at 1000 random configurations") {
  // Coordinates up to 5 m and lever arms up to ~4 m: positions reach ~15 m, so rounding is
  // ~15 * 2.2e-16 per operation over some tens of operations; 1e-12 m leaves room and still
  // catches any wrong sign, axis or length.
  std::mt19937_64 rng(1);
  const gen::Params p;
  gen::FramePositions pos;
  gen::FrameRotations rot;
  double worst_r = 0, worst_R = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    gen::kinematics(s, p, {.positions = &pos, .rotations = &rot});
    const auto ref = test::reference_kinematics(as_array(s), p);
    for (int f = 0; f < gen::kFrameCount; ++f) {
      for (int i = 0; i < 3; ++i) {
        worst_r = std::max(worst_r, std::abs(pos(i, f) - ref.frames[f].r[i]));
        for (int j = 0; j < 3; ++j) worst_R = std::max(worst_R, std::abs(rot[f](i, j) - ref.frames[f].R[i][j]));
      }
    }
  }
  MESSAGE("max position error " << worst_r << " m, max rotation error " << worst_R);
  CHECK(worst_r <= 1e-12);
  CHECK(worst_R <= 1e-14);
}

TEST_CASE("kinematics: positions only, rotations only") {
  std::mt19937_64 rng(2);
  const gen::Params p;
  const gen::Coordinates s = test::random_coordinates(rng);
  gen::FramePositions pos_both, pos_only;
  gen::FrameRotations rot_both, rot_only;
  gen::kinematics(s, p, {.positions = &pos_both, .rotations = &rot_both});
  gen::kinematics(s, p, {.positions = &pos_only});
  gen::kinematics(s, p, {.rotations = &rot_only});
  CHECK(pos_only == pos_both);
  for (int f = 0; f < gen::kFrameCount; ++f) CHECK(rot_only[f] == rot_both[f]);
}

TEST_CASE("kinematics: the left foot follows the thesis' printed equations 3.9-3.11") {
  // Transcribed from the thesis (chapter 3.4.1), with ps_i = psi_li and the cabin angles.
  std::mt19937_64 rng(3);
  const gen::Params p;
  gen::FramePositions pos;
  double worst = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    namespace c = gen::coord;
    const double cy = std::cos(s(c::yaw)), sy = std::sin(s(c::yaw)), cp = std::cos(s(c::pitch)),
                 sp = std::sin(s(c::pitch)), cr = std::cos(s(c::roll)), sr = std::sin(s(c::roll));
    const double c1 = std::cos(s(c::psi_l1)), s1 = std::sin(s(c::psi_l1)), c2 = std::cos(s(c::psi_l2)),
                 s2 = std::sin(s(c::psi_l2)), c3 = std::cos(s(c::psi_l3)), s3 = std::sin(s(c::psi_l3)),
                 c4 = std::cos(s(c::psi_l4)), s4 = std::sin(s(c::psi_l4));
    const double reach = p.thighD + c4 * p.legD;
    const double A = p.cyd / 2 + reach * (c1 * s3 + c3 * s1 * s2) + c2 * p.legD * s1 * s4;
    const double B = reach * (s1 * s3 - c1 * c3 * s2) - c1 * c2 * p.legD * s4;
    const double X = p.cxd / 2 + c2 * c3 * reach - p.legD * s2 * s4;
    const double x_F = s(c::x_C) - (cr * sy - cy * sp * sr) * A + B * (sr * sy + cr * cy * sp) + cp * cy * X;  // (3.9)
    const double y_F = s(c::y_C) + (cr * cy + sy * sp * sr) * A - B * (sr * cy - cr * sy * sp) + cp * sy * X;  // (3.10)
    const double z_F = s(c::z_C) - sp * X + cp * sr * A + cp * cr * B;                                        // (3.11)
    gen::kinematics(s, p, {.positions = &pos});
    worst = std::max({worst, std::abs(pos(0, gen::frame::F_l) - x_F), std::abs(pos(1, gen::frame::F_l) - y_F),
                      std::abs(pos(2, gen::frame::F_l) - z_F)});
  }
  MESSAGE("max deviation from eqs. 3.9-3.11: " << worst << " m");
  CHECK(worst <= 1e-12);
}
