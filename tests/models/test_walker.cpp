// The second built-in model, models/walker.yaml, passes the checks the excavator passes: its
// generated kinematics against an independent chain written here (tests/helpers/walker_chain.hpp),
// every Jacobian and convective term against exact derivatives (jets), the closed-form IK that
// wlx-gen derived for it against Newton's method, the dependent rates against the wheel
// constraints and finite differences, and the inverse dynamics against power and energy balances.
#include "../helpers/balance_checks.hpp"
#include "../helpers/random.hpp"
#include "../helpers/walker_chain.hpp"

#include <doctest/doctest.h>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/ik_verification.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>
#include <wlx/simulation.hpp>

#include <Eigen/SVD>

#include <cmath>
#include <numbers>

using namespace wlx;
namespace c = gen::coord;

namespace {

// A random admissible state around the nominal one: cabin moved and tilted, feet moved (turned
// with the cabin's yaw), ground levels and steering moved; dependents by the closed form.
Coordinates random_state(std::mt19937_64& rng, const Model& model) {
  std::uniform_real_distribution<double> u(-1, 1);
  for (;;) {
    Coordinates s = nominal_inputs();
    s(c::x_C) = u(rng);
    s(c::y_C) = u(rng);
    s(c::z_C) = 1.8 + 0.2 * u(rng);
    s(c::yaw) = u(rng);
    s(c::pitch) = 0.1 * u(rng);
    s(c::roll) = 0.1 * u(rng);
    const double cy = std::cos(s(c::yaw)), sy = std::sin(s(c::yaw));
    for (double side : {1.0, -1.0}) {
      const double ahead = 3.2 + 0.3 * u(rng), across = side * (1.4 + 0.2 * u(rng));
      s(side > 0 ? c::foot_x_l : c::foot_x_r) = s(c::x_C) + cy * ahead - sy * across;
      s(side > 0 ? c::foot_y_l : c::foot_y_r) = s(c::y_C) + sy * ahead + cy * across;
      s(side > 0 ? c::foot_z_l : c::foot_z_r) = 0.2 * u(rng);
    }
    s(c::ground_l) = 0.1 * u(rng);
    s(c::ground_r) = 0.15 + 0.1 * u(rng);
    s(c::slew_l) = 0.2 * u(rng);
    s(c::slew_r) = 0.2 * u(rng);
    s(c::steer_l) = 0.2 * u(rng);
    s(c::steer_r) = 0.2 * u(rng);
    try {
      solve_ik_closed_form(model, s);
      return s;
    } catch (const Error&) {
    }
  }
}

}  // namespace

TEST_CASE("walker: every frame of the generated FK matches the independent chain at 1000 configurations") {
  std::mt19937_64 rng(101);
  const gen::Params p;
  gen::FramePositions pos;
  gen::FrameRotations R;
  double worst = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng);
    gen::kinematics(s, p, {.positions = &pos, .rotations = &R});
    std::array<double, gen::kCoordinateCount> x;
    for (int k = 0; k < gen::kCoordinateCount; ++k) x[static_cast<std::size_t>(k)] = s(k);
    const auto ref = test::walker_kinematics(x, p);
    for (int f = 0; f < gen::kFrameCount; ++f)
      for (int i = 0; i < 3; ++i) {
        worst = std::max(worst, std::abs(pos(i, f) - ref.frames[static_cast<std::size_t>(f)].r[i]));
        for (int j = 0; j < 3; ++j) worst = std::max(worst, std::abs(R[static_cast<std::size_t>(f)](i, j) - ref.frames[static_cast<std::size_t>(f)].R[i][j]));
      }
  }
  MESSAGE("max |FK - reference| = " << worst);
  CHECK(worst <= 1e-12);  // positions up to ~15 m from random coordinates in [-5, 5] m: rounding ~1e-14
}

TEST_CASE("walker: Phi, dPhi/ds, the convective terms and the wheel rows match exact derivatives") {
  std::mt19937_64 rng(102);
  const gen::Params p;
  gen::ClosureVector Phi, conv;
  gen::ClosureJacobian J;
  gen::WheelRows C, spin;
  gen::WheelVector C_conv;
  double worst_phi = 0, worst_J = 0, worst_conv = 0, worst_C = 0, worst_spin = 0, worst_C_conv = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng);
    gen::closure(s, p, {.Phi = &Phi, .dPhi_ds = &J});
    gen::convective(s, sdot, p, {.dPhi_ds_dot_sdot = &conv, .C_dot_sdot = &C_conv});
    gen::nonholonomic(s, p, {.C = &C, .spin = &spin});
    for (int j = 0; j < gen::kCoordinateCount; ++j) {
      const auto ref = test::walker_closure(test::along(s, gen::Coordinates::Unit(j)), p);
      for (int i = 0; i < gen::kClosureCount; ++i) worst_J = std::max(worst_J, std::abs(J(i, j) - ref[static_cast<std::size_t>(i)].d));
    }
    const auto ref = test::walker_closure(test::along(s, sdot), p);
    for (int i = 0; i < gen::kClosureCount; ++i) {
      worst_phi = std::max(worst_phi, std::abs(Phi(i) - ref[static_cast<std::size_t>(i)].v));
      worst_conv = std::max(worst_conv, std::abs(conv(i) - ref[static_cast<std::size_t>(i)].dd));
    }
    // The wheel rows: v_W . n_W, v_W . e_x / radius, and d/dt (v_W . n_W) at zero accelerations.
    const auto k = test::walker_kinematics(test::along(s, sdot), p);
    const int contacts[2] = {gen::frame::contact_l, gen::frame::contact_r};
    for (int w = 0; w < 2; ++w) {
      const auto& P = k.frames[static_cast<std::size_t>(contacts[w])];
      test::Jet lateral = 0, forward = 0;
      for (int i = 0; i < 3; ++i) {
        lateral = lateral + P.R[i][1] * test::Jet(P.r[i].d, P.r[i].dd, 0);
        forward = forward + P.R[i][0] * test::Jet(P.r[i].d, P.r[i].dd, 0);
      }
      worst_C = std::max(worst_C, std::abs((C.row(w) * sdot)(0) - lateral.v));
      worst_spin = std::max(worst_spin, std::abs((spin.row(w) * sdot)(0) - forward.v / p.radius));
      worst_C_conv = std::max(worst_C_conv, std::abs(C_conv(w) - lateral.d));
    }
  }
  MESSAGE("max errors: Phi " << worst_phi << ", dPhi/ds " << worst_J << ", convective " << worst_conv << ", C s' " << worst_C
                             << ", spin s' " << worst_spin << ", (d/dt C) s' " << worst_C_conv);
  CHECK(worst_phi <= 1e-12);
  CHECK(worst_J <= 1e-12);
  CHECK(worst_conv <= 1e-11);  // second derivatives with rates up to 2/s: entries O(100)
  CHECK(worst_C <= 1e-12);
  CHECK(worst_spin <= 1e-12);
  CHECK(worst_C_conv <= 1e-11);
}

TEST_CASE("walker: body CoM, rotation, Jv, Jw and their convective terms match exact derivatives") {
  std::mt19937_64 rng(103);
  const gen::Params p;
  gen::BodyVectors com, Jv_dot, Jw_dot;
  gen::BodyRotations R;
  gen::BodyJacobians Jv, Jw;
  double worst = 0, worst_dd = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng);
    gen::bodies(s, sdot, p,
                {.com = &com, .rotations = &R, .Jv = &Jv, .Jw = &Jw, .Jv_dot_sdot = &Jv_dot, .Jw_dot_sdot = &Jw_dot});
    const auto ref = test::walker_kinematics(test::along(s, sdot), p);
    for (int b = 0; b < gen::kBodyCount; ++b) {
      const auto& P = ref.bodies[static_cast<std::size_t>(b)];
      const auto [omega, alpha] = test::angular_rates(P.R);
      const Eigen::Vector3d v = Jv[static_cast<std::size_t>(b)] * sdot, w = Jw[static_cast<std::size_t>(b)] * sdot;
      for (int i = 0; i < 3; ++i) {
        worst = std::max({worst, std::abs(com(i, b) - P.r[i].v), std::abs(v(i) - P.r[i].d), std::abs(w(i) - omega[i])});
        for (int j = 0; j < 3; ++j) worst = std::max(worst, std::abs(R[static_cast<std::size_t>(b)](i, j) - P.R[i][j].v));
        worst_dd = std::max({worst_dd, std::abs(Jv_dot(i, b) - P.r[i].dd), std::abs(Jw_dot(i, b) - alpha[i])});
      }
    }
  }
  MESSAGE("max errors: pose, Jv s', Jw s' " << worst << "; convective " << worst_dd);
  CHECK(worst <= 1e-12);
  CHECK(worst_dd <= 1e-11);
}

TEST_CASE("walker: the derived closed-form IK, every branch, 10^4 random poses: back into the FK, and Newton agrees") {
  // Random joint angles -> FK -> the limb's targets; the closed form of the branch those angles
  // lie on must give them back, and Newton started nearby must converge to the same joints.
  std::mt19937_64 rng(104);
  std::uniform_real_distribution<double> u(-1, 1);
  const Model model;
  Data data;
  int solved = 0, compared = 0;
  double worst_joint = 0, worst_newton = 0;
  for (int trial = 0; trial < 10000; ++trial) {
    Coordinates truth = nominal_inputs();
    truth(c::yaw) = u(rng);
    truth(c::pitch) = 0.3 * u(rng);
    truth(c::roll) = 0.3 * u(rng);
    truth(c::slew_l) = u(rng);
    truth(c::slew_r) = u(rng);
    truth(c::steer_l) = u(rng);
    truth(c::steer_r) = u(rng);
    for (int k = kInputCount; k < kCoordinateCount; ++k) truth(k) = 3.0 * u(rng);
    truth(c::guide_l) = -truth(c::steer_l);
    truth(c::guide_r) = -truth(c::steer_r);
    forward_kinematics(model, data, truth);
    for (int i = 0; i < 3; ++i) {
      truth(c::foot_x_l + i) = data.frame_positions(i, gen::frame::foot_l);
      truth(c::foot_x_r + i) = data.frame_positions(i, gen::frame::foot_r);
    }
    truth(c::ground_l) = data.frame_positions(2, gen::frame::contact_l);
    truth(c::ground_r) = data.frame_positions(2, gen::frame::contact_r);
    // The wheel levers' contact frames must be level for the truth to be a solution: set camber
    // and hub so that they are, by solving (branch 0) and keeping those angles.
    Coordinates level = truth;
    try {
      solve_limb_closed_form(model, gen::limb::lever_l, 0, level);
      solve_limb_closed_form(model, gen::limb::lever_r, 0, level);
    } catch (const Error&) {
      continue;
    }
    truth = level;
    for (Limb limb : kLimbs) {
      const int branch = classify_branch(model, limb, truth);
      Coordinates s = truth;
      for (int k = kInputCount; k < kCoordinateCount; ++k) s(k) = 0;
      solve_limb_closed_form(model, limb, branch, s);
      const LimbBlock b = limb_block(limb);
      for (int j = 0; j < b.size; ++j) {
        const int k = b.joints[static_cast<std::size_t>(j)];
        worst_joint = std::max(worst_joint, std::abs(std::remainder(s(k) - truth(k), 2 * std::numbers::pi)));
      }
      // Newton from 1 mrad away returns to the same joints where the solution is locally unique:
      // skip poses whose limb block of dPhi/ds has a condition number above 1e6 (a stretched leg,
      // aligned axes), where the joints are not determined to better than sqrt(rounding).
      closure(model, data, s, true);
      Eigen::Matrix4d block = Eigen::Matrix4d::Identity();
      for (int i = 0; i < b.size; ++i)
        for (int j = 0; j < b.size; ++j)
          block(i, j) = data.dPhi_ds(b.rows[static_cast<std::size_t>(i)], b.joints[static_cast<std::size_t>(j)]);
      const Eigen::JacobiSVD<Eigen::Matrix4d> svd(block);
      ++solved;
      if (svd.singularValues()(0) > 1e6 * svd.singularValues()(3)) continue;
      Coordinates n = s;
      for (int j = 0; j < b.size; ++j) n(b.joints[static_cast<std::size_t>(j)]) += 1e-3 * u(rng);
      solve_limb_newton(model, data, limb, n);
      // Near a nearly straight knee the other root is closer than the start's offset: compare with
      // the closed form of the branch Newton arrived on.
      Coordinates same_branch = n;
      solve_limb_closed_form(model, limb, classify_branch(model, limb, n), same_branch);
      for (int j = 0; j < b.size; ++j) {
        const int k = b.joints[static_cast<std::size_t>(j)];
        worst_newton = std::max(worst_newton, std::abs(std::remainder(same_branch(k) - n(k), 2 * std::numbers::pi)));
      }
      ++compared;
    }
  }
  MESSAGE(solved << " limb solves; max |closed form - truth| " << worst_joint << " rad; " << compared
                 << " compared with Newton: max |closed form - Newton| " << worst_newton << " rad");
  CHECK(solved > 20000);
  CHECK(compared > solved / 2);
  // Joints are recovered to rounding amplified by the limb's conditioning; random angles come
  // close to singular poses (stretched legs), so 1e-7 rad, while the closure itself holds to 1e-9
  // m by the generated check.
  CHECK(worst_joint <= 1e-7);
  CHECK(worst_newton <= 1e-9);  // Newton stops at |Phi| <= 1e-13; cond <= 1e6 bounds the joint error by 1e-7
}

TEST_CASE("walker: the model's IK sweeps: closed form and Newton agree to 1e-12, every point checked in the FK") {
  const Model model;
  Data data;
  REQUIRE(model_ik_sweeps().size() == 10);
  for (const IkSweep& sweep : model_ik_sweeps()) {
    CAPTURE(sweep.id);
    const IkSweepResult r = run_ik_sweep(model, data, sweep);
    MESSAGE(sweep.id << ": " << r.points.size() << " points, analytic check " << r.max_check_closed_form << " m, level "
                     << r.max_level_error << ", |closed form - Newton| " << r.max_newton_difference << " rad");
    CHECK(r.max_check_closed_form <= 1e-12);
    CHECK(r.max_check_newton <= 1e-12);
    CHECK(r.max_level_error <= 1e-12);
    CHECK(r.max_newton_difference <= 1e-12);
  }
}

TEST_CASE("walker: dependent rates keep both wheels from sliding and match finite differences of a run") {
  std::mt19937_64 rng(105);
  const Model model;
  Data d;
  double worst_side = 0, worst_closure = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Coordinates s = random_state(rng, model);
    Coordinates sdot = test::random_rates(rng);
    sdot.tail(kDependentCount).setZero();
    try {
      solve_dependent_rates(model, d, s, sdot, default_pair());
    } catch (const Error&) {
      continue;  // a singular J_beta is refused with its reason (tested with the excavator)
    }
    // Rounding in the solve scales with cond(J_beta) and the rates: measure relative to both.
    const double scale = d.cond_J_beta * sdot.cwiseAbs().maxCoeff();
    gen::WheelRows C;
    gen::nonholonomic(s, model.params(), {.C = &C});
    worst_side = std::max(worst_side, (C * sdot).cwiseAbs().maxCoeff() / scale);
    closure(model, d, s, true);
    worst_closure = std::max(worst_closure, (d.dPhi_ds * sdot).cwiseAbs().maxCoeff() / scale);
  }
  MESSAGE("max |v_W . n_W| / (cond |s'|) " << worst_side << ", max |dPhi/ds s'| / (cond |s'|) " << worst_closure);
  // ~1e-16 per operation, times lever arms of a few metres and sums of ~30 terms.
  CHECK(worst_side <= 1e-14);
  CHECK(worst_closure <= 1e-14);

  // Steering and rolling from the nominal state with dt = 1e-5: the central differences' error,
  // about dt^2 times the third derivative, is far below the bounds, and RK4 is converged.
  Scenario sc;
  sc.rates(c::steer_l) = 0.5 * std::numbers::pi / 180;
  sc.rates(c::roll) = 3 * std::numbers::pi / 180;
  sc.duration = 0.002;
  sc.dt = 1e-5;
  const Trajectory tr = simulate(sc);
  REQUIRE(tr.complete);
  double worst_v = 0, scale_v = 0, worst_a = 0, scale_a = 0;
  for (std::size_t k = 1; k + 1 < tr.samples.size(); ++k) {
    const Coordinates fd_v = (tr.samples[k + 1].s - tr.samples[k - 1].s) / (2 * sc.dt);
    const Coordinates fd_a = (tr.samples[k + 1].sdot - tr.samples[k - 1].sdot) / (2 * sc.dt);
    Coordinates sdot = tr.samples[k].sdot, sddot = Coordinates::Zero();
    solve_dependent_rates(model, d, tr.samples[k].s, sdot, sc.pair);
    solve_dependent_accelerations(model, d, tr.samples[k].s, sdot, sddot, sc.pair);
    worst_v = std::max(worst_v, (fd_v - sdot).cwiseAbs().maxCoeff());
    worst_a = std::max(worst_a, (fd_a - sddot).cwiseAbs().maxCoeff());
    scale_v = std::max(scale_v, sdot.cwiseAbs().maxCoeff());
    scale_a = std::max(scale_a, sddot.cwiseAbs().maxCoeff());
  }
  MESSAGE("finite differences: rates " << worst_v << " (scale " << scale_v << "), accelerations " << worst_a << " (scale "
                                       << scale_a << ")");
  CHECK(worst_v <= 1e-7 * scale_v);  // central differences, dt = 1e-4: error ~dt^2 |s'''|
  CHECK(worst_a <= 1e-6 * scale_a);
  CHECK(scale_a > 1e-3);
}

TEST_CASE("walker: inverse dynamics: J_beta^T tau = Q*, power and energy balances") {
  std::mt19937_64 rng(106);
  std::uniform_real_distribution<double> d4(-0.5, 0.5);
  const Model model;
  Data d;
  DynamicsTerms t;
  double worst_balance = 0, worst_power = 0, worst_energy = 0;
  for (int trial = 0; trial < 10; ++trial) {
    Scenario sc;
    sc.initial = random_state(rng, model);
    CommandVector u(d4(rng), d4(rng), d4(rng), d4(rng)), u_dot(d4(rng), d4(rng), d4(rng), d4(rng));
    inverse_dynamics(model, d, sc.initial, u, u_dot, t);
    const TorqueVector tau = distribute_torques(t.J_beta, t.Qstar, Weighting::model_weights());
    worst_balance = std::max(worst_balance, (t.J_beta.transpose() * tau - t.Qstar).norm() / t.Qstar.norm());
    worst_power = std::max(worst_power, std::abs(tau.dot(t.J_beta * u) - t.Qstar.dot(u)) / (t.Qstar.norm() * u.norm()));
    worst_energy = std::max(worst_energy, test::energy_balance_error(model, sc.initial, u));
  }
  MESSAGE("J^T tau = Q*: " << worst_balance << ", power: " << worst_power << ", energy: " << worst_energy);
  CHECK(worst_balance <= 1e-9);  // least-norm solve of a 4 x 8 system with cond(J_beta) up to ~1e4
  CHECK(worst_power <= 1e-9);
  CHECK(worst_energy <= 1e-6);  // five-point stencil at dt = 1e-5 on a motion with |s'| <= 1
  CHECK(model.total_mass() == doctest::Approx(4200 + 2 * (110 + 80 + 190)).epsilon(1e-15));
}

TEST_CASE("walker: unreachable targets get the derived messages") {
  const Model model;
  Coordinates s = nominal_inputs();
  s(c::foot_x_l) = 9.0;
  try {
    solve_ik_closed_form(model, s);
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "left leg");
    CHECK(std::string(e.what()).find("foot_l out of reach") != std::string::npos);
    CHECK(std::string(e.what()).find("abduct_l and lift_l") != std::string::npos);
  }
  s = nominal_inputs();
  s(c::ground_r) = 5.0;
  try {
    solve_ik_closed_form(model, s);
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.field() == "right wheel lever");
    CHECK(std::string(e.what()).find("ground_r = 5.0000 m is out of reach") != std::string::npos);
  }
}
