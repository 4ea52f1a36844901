#include "wlx/ik_verification.hpp"

#include "wlx/error.hpp"
#include "wlx/kinematics.hpp"

#include <cmath>
#include <numbers>

namespace wlx {

namespace c = gen::coord;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

// The joints a limb's closure solves for.
std::vector<int> limb_joints(Limb limb) {
  switch (limb) {
    case Limb::leg_l: return {c::psi_l2, c::psi_l3, c::psi_l4};
    case Limb::leg_r: return {c::psi_r2, c::psi_r3, c::psi_r4};
    case Limb::wheel_l: return {c::theta_l2, c::theta_l3, c::theta_l4, c::theta_l6};
    case Limb::wheel_r: return {c::theta_r2, c::theta_r3, c::theta_r4, c::theta_r6};
  }
  return {};
}

}  // namespace

int IkSweep::points() const { return static_cast<int>(std::lround(std::abs(to - from) / step)) + 1; }

double IkSweep::value(int k) const {
  const int n = points();
  return n == 1 ? from : from + (to - from) * k / (n - 1);
}

const std::vector<IkSweep>& thesis_ik_sweeps() {
  static const std::vector<IkSweep> sweeps = {
      {"IK-L1", "x_Fl", 1.80, 4.30, 0.01, false, Limb::leg_l},
      {"IK-L2", "y_Fl", -0.50, 3.50, 0.01, false, Limb::leg_l},
      {"IK-L3", "z_Fl", -0.50, 3.50, 0.01, false, Limb::leg_l},
      {"IK-L4", "psi_l1", -30 * kDeg, 30 * kDeg, 0.1 * kDeg, true, Limb::leg_l},
      {"IK-R1", "x_Fr", 1.80, 4.30, 0.01, false, Limb::leg_r},
      {"IK-R2", "y_Fr", 0.50, -3.50, 0.01, false, Limb::leg_r},
      {"IK-R3", "z_Fr", -0.50, 3.50, 0.01, false, Limb::leg_r},
      {"IK-R4", "psi_r1", -30 * kDeg, 30 * kDeg, 0.1 * kDeg, true, Limb::leg_r},
      {"IK-WL1", "z_Wl", 0.90, -0.70, 0.01, false, Limb::wheel_l},
      {"IK-WL2", "theta_l5", -40 * kDeg, 15 * kDeg, 0.1 * kDeg, true, Limb::wheel_l},
      {"IK-WR1", "z_Wr", 0.90, -0.70, 0.01, false, Limb::wheel_r},
      {"IK-WR2", "theta_r5", -40 * kDeg, 15 * kDeg, 0.1 * kDeg, true, Limb::wheel_r},
  };
  return sweeps;
}

const IkSweep* find_ik_sweep(const std::string& id) {
  for (const auto& s : thesis_ik_sweeps())
    if (s.id == id) return &s;
  return nullptr;
}

Coordinates ik_sweep_inputs() {
  Coordinates s = nominal_inputs();
  s(c::z_Wr) = 0.0;
  return s;
}

LimbCheck analytic_check(const Model& model, Limb limb, const Coordinates& s, Data& data) {
  forward_kinematics(model, s, data);
  LimbCheck check;
  switch (limb) {
    case Limb::leg_l:
    case Limb::leg_r: {
      const bool left = limb == Limb::leg_l;
      const Eigen::Vector3d target = left ? Eigen::Vector3d(s(c::x_Fl), s(c::y_Fl), s(c::z_Fl))
                                          : Eigen::Vector3d(s(c::x_Fr), s(c::y_Fr), s(c::z_Fr));
      check.position_error = (frame_position(data, left ? gen::frame::F_l : gen::frame::F_r) - target).norm();
      break;
    }
    case Limb::wheel_l:
    case Limb::wheel_r: {
      const bool left = limb == Limb::wheel_l;
      const int f = left ? gen::frame::W_l : gen::frame::W_r;
      check.position_error = std::abs(frame_position(data, f).z() - s(left ? c::z_Wl : c::z_Wr));
      const Eigen::Matrix3d& R = frame_rotation(data, f);
      check.level_error = std::max(std::abs(R(2, 0)), std::abs(R(2, 1)));
      break;
    }
  }
  return check;
}

IkSweepResult run_ik_sweep(const Model& model, const IkSweep& sweep, Data& data) {
  IkSweepResult result{sweep, {}, 0, 0, 0, 0, 0, 0, 0, 0};
  const int input = coordinate_index(sweep.input);
  const auto joints = limb_joints(sweep.limb);
  Coordinates start = ik_sweep_inputs();
  solve_ik_closed_form(model, start);  // the assembled start pose, as in MOBILE
  Coordinates warm = start;
  long iterations = 0;
  int previous_branch = 0;
  for (int k = 0; k < sweep.points(); ++k) {
    IkSweepPoint pt;
    pt.value = sweep.value(k);
    Coordinates s = ik_sweep_inputs();
    s(input) = pt.value;
    solve_ik_closed_form(model, s);
    pt.closed_form = s;
    pt.check_closed_form = analytic_check(model, sweep.limb, s, data);
    pt.contacts << data.frame_positions(0, gen::frame::W_l), data.frame_positions(1, gen::frame::W_l),
        data.frame_positions(0, gen::frame::W_r), data.frame_positions(1, gen::frame::W_r);

    Coordinates n = warm;  // continuation: start from the previous point's Newton solution
    n(input) = pt.value;
    const NewtonReport report = solve_ik_newton(model, n, data);
    pt.newton = n;
    pt.newton_iterations = report.iterations[static_cast<std::size_t>(sweep.limb)];
    pt.newton_branch = classify_branch(model, sweep.limb, n);
    pt.check_newton = analytic_check(model, sweep.limb, n, data);
    for (int j : joints)
      pt.newton_difference = std::max(pt.newton_difference, std::abs(std::remainder(s(j) - n(j), 2 * std::numbers::pi)));
    warm = n;

    Coordinates cold = start;  // the thesis' way: every point from the same start pose
    cold(input) = pt.value;
    try {
      solve_ik_newton(model, cold, data);
      pt.cold_newton_branch = classify_branch(model, sweep.limb, cold);
    } catch (const Error&) {
      pt.cold_newton_branch = -1;
    }

    result.max_check_closed_form = std::max(result.max_check_closed_form, pt.check_closed_form.position_error);
    result.max_check_newton = std::max(result.max_check_newton, pt.check_newton.position_error);
    result.max_level_error =
        std::max({result.max_level_error, pt.check_closed_form.level_error, pt.check_newton.level_error});
    result.max_newton_difference = std::max(result.max_newton_difference, pt.newton_difference);
    result.max_newton_iterations = std::max(result.max_newton_iterations, pt.newton_iterations);
    iterations += pt.newton_iterations;
    if (k > 0 && pt.newton_branch != previous_branch) ++result.newton_branch_changes;
    previous_branch = pt.newton_branch;
    if (pt.cold_newton_branch != 0) ++result.cold_start_off_default;
    result.points.push_back(pt);
  }
  result.mean_newton_iterations = static_cast<double>(iterations) / static_cast<double>(result.points.size());
  return result;
}

}  // namespace wlx
