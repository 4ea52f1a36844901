// The inverse kinematics' and the dependent rates' options, and the view of a limb, that both runtimes share (the model's
// own, wlx/ik.hpp, and the one compiled once for every model, wlx/generic/ik.hpp): nothing here
// depends on a model's sizes.
#pragma once

#include <limits>

namespace wlx {

// The outcome of a generated closed-form solver (the generated gen::IkStatus, model by model).
enum class ClosedFormStatus { ok = 0, out_of_reach, bad_branch, residual };

// Why a closed form failed (the generated gen::IkDiagnostics) and for which limb.
struct ClosedFormFailure {
  int limb = -1;
  int stage = 0;  // which equation failed (1-based, ModelCodeClosedForm::failures); 0: the residual check
  double value = 0, low = 0, high = 0, aux = 0;
};

// "Leave the branch to the model" (resolve_branches).
inline constexpr int kModelsChoice = -1;

struct NewtonOptions {
  double tolerance = 1e-13;  // on max |Phi| of the limb, in m or rad
  // A limb whose residual no damped step can lower any more has reached its rounding floor; it
  // counts as converged if that floor is below this (ill-conditioned poses amplify rounding). So
  // does a limb still below it when max_iterations run out: at a singular pose (a leg stretched
  // or folded flat) the convergence is linear, and the last digits take hundreds of steps.
  double floor_tolerance = 1e-10;
  int max_iterations = 100;  // steps tried per limb (accepted or not)
  // levenberg_marquardt: damped steps that also descend from far or singular starts (the default).
  // backtracking: full Newton steps, each halved until the limb's max |Phi| decreases: the
  // thesis' method, whose basins of attraction its cold starts show (docs/excavator.md section 4).
  enum class Method { levenberg_marquardt, backtracking };
  Method method = Method::levenberg_marquardt;
  // Continuation (solve_newton_limbs from the previous solution): the largest move of a dependent
  // joint (rad or m) that still counts as following the same solution. A larger one is an error
  // naming the limb, never a silent switch to another root. Infinite: no check (a one-off solve).
  double max_jump = std::numeric_limits<double>::infinity();
};

// The bound of a run's continuation (simulate, the report's runs): between two evaluations of the
// integrator no dependent joint of a limb solved by Newton's method moves more than half a radian
// (or half a metre). A run's evaluations lie a step apart; a move that large is another root.
inline constexpr double kContinuationJump = 0.5;

struct NonholonomicOptions {
  // J_beta counts as singular above this condition number. The thesis scenarios reach 2.7e7
  // (ST-A1- crossing its singular point on the 1 ms grid); 1e10 leaves a wide margin while
  // stopping rates that would be rounding noise amplified by more than 1e10 * 1e-16 = 1e-6.
  double max_condition = 1e10;
};

// One limb as the algorithms see it.
struct IkLimb {
  int size = 0;                  // rows = joints
  const int* rows = nullptr;     // its closure rows
  const int* joints = nullptr;   // its dependent coordinates, in the order of the rows' unknowns
  int input_count = 0;
  const int* inputs = nullptr;   // the input coordinates its rows read
};

}  // namespace wlx
