// The verification of the inverse kinematics (the thesis' method, thesis 3.4): sweep one input,
// solve the dependent joints, put them back into the forward kinematics and measure the distance
// to the target; here with both the closed form and Newton's method, or with Newton's method
// alone for a limb that has no closed form (has_closed_form). The sweeps are the model file's
// (settings().ik_sweeps).
#pragma once

#include "wlx/ik.hpp"

#include <string>
#include <vector>

WLX_MODEL_NAMESPACE_BEGIN

// The model's sweeps (its file's ik_sweeps: settings().ik_sweeps; IkSweep is in settings.hpp).
const std::vector<IkSweep>& model_ik_sweeps();
const IkSweep* find_ik_sweep(const std::string& id);

// The initial state of the IK sweeps (the model file's ik_sweeps.start).
Coordinates ik_sweep_inputs();

// The analytic check of one limb: put the solution into the generated forward kinematics and
// measure the target error: over the limb's point rows the distance |r_F - target| (m), over its
// level rows the largest |(R e_axis).e_z| (dimensionless), reported separately.
struct LimbCheck {
  double position_error = 0;  // m
  double level_error = 0;     // wheels only
};
LimbCheck analytic_check(const Model& model, Data& data, Limb limb, const Coordinates& s);

// The closed-form fields of a point (closed_form, check_closed_form, newton_difference) hold
// nothing for a limb without a closed form (IkSweepResult::closed_form false): zeros; the point's
// solution (IkSweepResult::solution) is then Newton's.
struct IkSweepPoint {
  double value = 0;                 // the swept input
  Coordinates closed_form = Coordinates::Zero();  // all coordinates
  Coordinates newton;               // Newton, warm-started from the previous point (continuation)
  Eigen::Matrix<double, 2 * kWheelCount, 1> contacts;  // per wheel x, y of its contact point (at solution())
  LimbCheck check_closed_form, check_newton;
  double newton_difference = 0;     // max |closed form - Newton| over the limb's joints (rad)
  int newton_iterations = 0;
  int newton_branch = 0;            // branch of the continued Newton result
  int cold_newton_branch = -1;      // branch Newton reaches from the sweep's start pose (-1: no convergence)
  bool within_limits = true;        // the limb's joints within their ranges (closed form)
};

struct IkSweepResult {
  IkSweep sweep;
  bool closed_form = true;  // the swept limb has a closed form; false: Newton's method alone, nothing compared
  std::vector<IkSweepPoint> points;
  // The solution a point shows: the closed form's, or Newton's where the limb has no closed form.
  const Coordinates& solution(const IkSweepPoint& p) const { return closed_form ? p.closed_form : p.newton; }
  double max_check_closed_form = 0, max_check_newton = 0, max_level_error = 0, max_newton_difference = 0;
  double mean_newton_iterations = 0;
  int max_newton_iterations = 0;
  int newton_branch_changes = 0;       // along the continued path
  int cold_start_off_default = 0;      // points where a cold start lands off the sweep's branch
  int branch = 0;                      // the limb's branch along the sweep: the model's choice at its start pose
  int outside_limits = 0;              // points where a joint of the limb leaves its range
  std::string first_outside;           // the first of them, in words (describe_outside_limits), or ""
};

IkSweepResult run_ik_sweep(const Model& model, Data& data, const IkSweep& sweep);

WLX_MODEL_NAMESPACE_END
