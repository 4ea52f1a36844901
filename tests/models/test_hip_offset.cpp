// The excavator with its front hips lowered by hip_z = -0.2 m, made the way a user would make it:
// one parameter and one translation edited in models/excavator.yaml (tests/models/
// hip_offset_variant.cmake), regenerated, and the unchanged runtime compiled for it. The closed-form
// IK, Newton's method, the non-holonomic rates and the inverse dynamics must all follow, which is
// checked here against geometry computed in the test.
#include "../helpers/balance_checks.hpp"

#include <doctest/doctest.h>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>

#include <cmath>
#include <numbers>
#include <random>

using namespace wlx;
namespace c = gen::coord;
namespace f = gen::frame;

TEST_CASE("hip offset: the edited model file reached the generated code") {
  const Params p;
  CHECK(p.hip_z == -0.2);
  CHECK(gen::kModelName == "excavator_hip");
  // The hips at r_C + R_C (cxd/2, +-cyd/2, hip_z) for any cabin pose, by the generated FK.
  std::mt19937_64 rng(201);
  std::uniform_real_distribution<double> u(-1, 1);
  const Model model;
  Data data;
  double worst = 0;
  for (int trial = 0; trial < 100; ++trial) {
    Coordinates s = Coordinates::Zero();
    for (int k = 0; k < 6; ++k) s(k) = u(rng);
    for (int k = kInputCount; k < kCoordinateCount; ++k) s(k) = u(rng);
    forward_kinematics(model, data, s);
    const Eigen::Matrix3d& R_C = data.frame_rotations[f::C];
    const Eigen::Vector3d r_C(s(c::x_C), s(c::y_C), s(c::z_C));
    for (const auto& [frame, side] : {std::pair{f::hip_l, 1.0}, std::pair{f::hip_r, -1.0}}) {
      const Eigen::Vector3d expected = r_C + R_C * Eigen::Vector3d(p.cxd / 2, side * p.cyd / 2, p.hip_z);
      worst = std::max(worst, (data.frame_positions.col(frame) - expected).norm());
    }
  }
  CHECK(worst <= 1e-14);
}

TEST_CASE("hip offset: closed-form IK and Newton follow it") {
  const Model model;
  const Params& p = model.params();
  Data data;
  Coordinates s = nominal_inputs();
  solve_ik_closed_form(model, s);
  forward_kinematics(model, data, s);
  // The nominal feet reached, and the knee of the law of cosines over the hip-foot distance,
  // which the offset changes: from (cxd/2, cyd/2, z_C + hip_z) to (x_Fl, y_Fl, z_Fl).
  CHECK((data.frame_positions.col(f::F_l) - Eigen::Vector3d(s(c::x_Fl), s(c::y_Fl), s(c::z_Fl))).norm() <= 1e-12);
  CHECK((data.frame_positions.col(f::F_r) - Eigen::Vector3d(s(c::x_Fr), s(c::y_Fr), s(c::z_Fr))).norm() <= 1e-12);
  const double d = (Eigen::Vector3d(s(c::x_Fl), s(c::y_Fl), s(c::z_Fl)) -
                    Eigen::Vector3d(p.cxd / 2, p.cyd / 2, s(c::z_C) + p.hip_z)).norm();
  const double knee = std::acos((d * d - p.thighD * p.thighD - p.legD * p.legD) / (2 * p.thighD * p.legD));
  CHECK(s(c::psi_l4) == doctest::Approx(knee).epsilon(1e-12));
  CHECK(d == doctest::Approx(std::sqrt(2.0 * 2.0 + 1.8 * 1.8)).epsilon(1e-15));  // the excavator's: |(2, 0, -2)|
  // Newton from 0.01 rad away returns to the same joints.
  Coordinates n = s;
  for (int k = kInputCount; k < kCoordinateCount; ++k) n(k) += 0.01;
  n(c::theta_l4) = -n(c::theta_l5) + 0.01;
  const NewtonReport report = solve_ik_newton(model, data, n);
  CHECK(report.converged);
  CHECK((n.tail(kDependentCount) - s.tail(kDependentCount)).cwiseAbs().maxCoeff() <= 1e-10);
  // The parameter is a run-time one too: hip_z = 0 is the excavator, whose nominal knee follows
  // from its hip-foot distance |(2, 0, -2)| = sqrt(8) m.
  Params flat;
  flat.hip_z = 0;
  Coordinates e = nominal_inputs();
  solve_ik_closed_form(Model(flat), e);
  CHECK(e(c::psi_l4) == doctest::Approx(std::acos((8 - 4 - 2.25) / 6)).epsilon(1e-12));
}

TEST_CASE("hip offset: the dependent rates keep the wheels rolling; the dynamics balance energy") {
  const Model model;
  Data d;
  Coordinates s = nominal_inputs();
  solve_ik_closed_form(model, s);
  Coordinates sdot = Coordinates::Zero();
  sdot(c::roll) = 0.1;
  sdot(c::theta_l5) = 0.05;
  solve_dependent_rates(model, d, s, sdot, default_pair());
  gen::WheelRows C;
  gen::nonholonomic(s, model.params(), {.C = &C});
  const double scale = d.cond_J_beta * sdot.cwiseAbs().maxCoeff();
  CHECK((C * sdot).cwiseAbs().maxCoeff() <= 1e-14 * scale);
  closure(model, d, s, true);
  CHECK((d.dPhi_ds * sdot).cwiseAbs().maxCoeff() <= 1e-14 * scale);
  CHECK(test::energy_balance_error(model, s, CommandVector(0.1, -0.2, 0.05, 0.03)) <= 1e-6);
}
