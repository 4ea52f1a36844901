#include "wlx/ik_verification.hpp"

#include "wlx/error.hpp"
#include "wlx/kinematics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

std::vector<int> limb_joints(Limb limb) {
  const LimbBlock b = limb_block(limb);
  return {b.joints.begin(), b.joints.begin() + b.size};
}

}  // namespace

int IkSweep::points() const { return static_cast<int>(std::lround(std::abs(to - from) / step)) + 1; }

double IkSweep::value(int k) const {
  const int n = points();
  return n == 1 ? from : from + (to - from) * k / (n - 1);
}

const std::vector<IkSweep>& model_ik_sweeps() { return settings().ik_sweeps; }

const IkSweep* find_ik_sweep(const std::string& id) {
  for (const auto& s : model_ik_sweeps())
    if (s.id == id) return &s;
  return nullptr;
}

Coordinates ik_sweep_inputs() {
  Coordinates s = nominal_inputs();  // the dependent joints at Newton's start values
  for (int k = 0; k < kInputCount; ++k) s(k) = settings().sweep_start[static_cast<std::size_t>(k)];
  return s;
}

LimbCheck analytic_check(const Model& model, Data& data, Limb limb, const Coordinates& s) {
  forward_kinematics(model, data, s);
  LimbCheck check;
  double squared = 0;
  const LimbBlock b = limb_block(limb);
  for (int i = 0; i < b.size; ++i) {
    const gen::ClosureRowInfo& row = gen::kClosureRows[static_cast<std::size_t>(b.rows[static_cast<std::size_t>(i)])];
    if (row.kind == gen::RowKind::point) {
      const double e = frame_position(data, row.frame)(row.axis) - s(row.target);
      squared += e * e;
    } else if (row.kind == gen::RowKind::level) {
      check.level_error = std::max(check.level_error, std::abs(frame_rotation(data, row.frame)(2, row.axis)));
    }
  }
  check.position_error = std::sqrt(squared);
  return check;
}

IkSweepResult run_ik_sweep(const Model& model, Data& data, const IkSweep& sweep) {
  IkSweepResult result;
  result.sweep = sweep;
  // Without a closed form, the "closed form" below would be Newton's method again (solve_ik_closed_form
  // falls back to it): comparing the two would prove nothing, so only Newton's result is measured.
  result.closed_form = has_closed_form(sweep.limb);
  const int input = coordinate_index(sweep.input);
  const auto joints = limb_joints(sweep.limb);
  Coordinates start = ik_sweep_inputs();
  // One branch per limb all along: the model's choice at the start pose (within the joints' ranges
  // where a branch is), so that the closed form and Newton's continuation follow the same one.
  Branches requested;  // the sweep's own branch for its limb, if it names one
  if (sweep.branch >= 0) requested.limb[static_cast<std::size_t>(sweep.limb)] = sweep.branch;
  const Branches branches = resolve_branches(model, start, requested);
  solve_ik_closed_form(model, start, branches);  // the assembled start pose, as in MOBILE
  Coordinates warm = start, previous = start;
  long iterations = 0;
  result.branch = branches.limb[static_cast<std::size_t>(sweep.limb)];
  int previous_branch = result.branch;
  for (int k = 0; k < sweep.points(); ++k) {
    IkSweepPoint pt;
    pt.value = sweep.value(k);
    // The closed form reads only the inputs; other limbs without one start Newton from the
    // previous point's solution (continuation).
    Coordinates s = previous;
    s(input) = pt.value;
    if (result.closed_form) {
      solve_ik_closed_form(model, s, branches);
      previous = s;
      pt.closed_form = s;
      pt.check_closed_form = analytic_check(model, data, sweep.limb, s);
    }

    Coordinates n = warm;  // continuation: start from the previous point's Newton solution
    n(input) = pt.value;
    const NewtonReport report = solve_ik_newton(model, data, n);
    pt.newton = n;
    pt.newton_iterations = report.iterations[static_cast<std::size_t>(sweep.limb)];
    pt.newton_branch = classify_branch(model, sweep.limb, n);
    pt.check_newton = analytic_check(model, data, sweep.limb, n);
    if (result.closed_form)
      for (int j : joints)
        pt.newton_difference =
            std::max(pt.newton_difference, std::abs(std::remainder(s(j) - n(j), 2 * std::numbers::pi)));
    warm = n;
    const Coordinates& solution = result.solution(pt);
    for (int j : joints)
      if (!within_range(solution, j)) {
        if (pt.within_limits && result.first_outside.empty())
          result.first_outside = fmt::format("at {} = {:.6g}: {}", sweep.input, pt.value, describe_outside_limits(solution, j));
        pt.within_limits = false;
      }
    if (!pt.within_limits) ++result.outside_limits;
    forward_kinematics(model, data, solution);
    for (int w = 0; w < kWheelCount; ++w)  // element by element: compiles for no wheels too
      for (int i = 0; i < 2; ++i)
        pt.contacts(2 * w + i) = data.frame_positions(i, gen::kWheels[static_cast<std::size_t>(w)].contact_frame);

    Coordinates cold = start;  // the thesis' way: every point from the same start pose
    cold(input) = pt.value;
    try {
      NewtonOptions backtracking;  // Newton with backtracking (the thesis' method), whose basins the cold starts show
      backtracking.method = NewtonOptions::Method::backtracking;
      solve_ik_newton(model, data, cold, backtracking);
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
    if (pt.cold_newton_branch != result.branch) ++result.cold_start_off_default;
    result.points.push_back(pt);
  }
  result.mean_newton_iterations = static_cast<double>(iterations) / static_cast<double>(result.points.size());
  return result;
}

WLX_MODEL_NAMESPACE_END
