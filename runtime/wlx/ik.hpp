// Inverse kinematics of the limbs: the closed form that wlx-gen derived from the model's chains
// (the generated ik.hpp, with every branch), and the thesis' iterative method, Newton's method
// on the generated Phi and dPhi/ds. A limb for which wlx-gen found no closed form is solved by
// Newton's method in both.
//
// Every closed-form solution has been put back into the limb's closure rows by the generated
// code: one that does not satisfy them (residual above gen::kIkTolerance) is an error here,
// never a result.
#pragma once

#include "wlx/ik_options.hpp"
#include "wlx/model.hpp"

#include <array>
#include <limits>
#include <string>
#include <string_view>

WLX_MODEL_NAMESPACE_BEGIN

// The options and constants both runtimes share (wlx/ik_options.hpp), by this model's name too
// (wlx::<model>::NewtonOptions, as before they were shared).
using ::wlx::kContinuationJump;
using ::wlx::kModelsChoice;
using ::wlx::NewtonOptions;
using ::wlx::NonholonomicOptions;

// A limb: an index into gen::kLimbs (gen::limb::<name>).
using Limb = int;
inline constexpr int kLimbCount = gen::kLimbCount;
inline constexpr std::array<Limb, kLimbCount> kLimbs = [] {
  std::array<Limb, kLimbCount> all{};
  for (int k = 0; k < kLimbCount; ++k) all[static_cast<std::size_t>(k)] = k;
  return all;
}();
std::string_view limb_name(Limb limb) noexcept;  // the model file's title: "left leg", ...

// Whether wlx-gen derived a closed form for the limb (the generated gen::kClosedForm[limb].solve).
// A limb without one is solved by Newton's method wherever the closed form is asked for (below),
// so what a command reports as the method that ran comes from here, not from what was asked.
bool has_closed_form(Limb limb) noexcept;

// The branches of a limb's closed form (1 without one). What each bit selects is in the
// generated gen::kClosedForm[limb].bits; branch 0 takes, in every equation, the root nearest the
// joint's zero.
int branch_count(Limb limb) noexcept;

// A limb's rows in Phi and its dependent joints (its block of dPhi/ds is square).
struct LimbBlock {
  int size = 0;
  std::array<int, gen::kMaxLimbSize> rows{};
  std::array<int, gen::kMaxLimbSize> joints{};
};
LimbBlock limb_block(Limb limb) noexcept;

// A generated solver's outcome in the terms both runtimes share (wlx/ik_options.hpp).
ClosedFormStatus closed_form_status(gen::IkStatus status) noexcept;

struct NewtonReport;

// Which branch each limb's closed form takes, indexed by Limb; kModelsChoice (wlx/ik_options.hpp)
// leaves it to the model (resolve_branches). Default-constructed: every limb the model's choice.
struct Branches {
  std::array<int, kLimbCount> limb = [] {
    std::array<int, kLimbCount> all{};
    for (int& b : all) b = kModelsChoice;
    return all;
  }();
};

// The model's choice of branch for a limb at the inputs in s: its default branch (the model
// file's limbs[].branch, else 0) when that solution keeps the limb's joints within their ranges
// (settings().lower, upper), else the first branch from 0 that does, else (none does, or none
// solves) the default branch. A limb whose joints have no ranges takes its default branch
// without solving anything. Every branch given in `requested` stays as it is. `outside[limb]`,
// when given, says whether the limb's chosen solution leaves a range.
Branches resolve_branches(const Model& model, const Coordinates& s, const Branches& requested = {},
                          std::array<bool, kLimbCount>* outside = nullptr);
// Whether coordinate k of s lies within its range (settings().lower, upper, bounds included); a
// NaN lies within none. The one range test of the IK, the sweeps and the runs.
bool within_range(const Coordinates& s, int k) noexcept;
// The first of s's coordinates outside its range (settings().lower, upper), or -1.
int first_outside_limits(const Coordinates& s) noexcept;
// "kfe_rf = 1.15 rad is outside its range [-2.8, -0.4]": what first_outside_limits found.
std::string describe_outside_limits(const Coordinates& s, int coordinate);

// Solves one limb's dependent joints in s from its inputs in s. Throws wlx::Error when the target
// is out of reach (naming the limb, what the target asks and what the limb reaches), an input is
// not finite, or the branch does not exist.
void solve_limb_closed_form(const Model& model, Limb limb, int branch, Coordinates& s);
// All limbs, each on its branch in `branches` (the model's choice where kModelsChoice:
// resolve_branches); those without a closed form by Newton's method from the dependent joints in s
// (then from the model file's start values), whose report goes to `newton` when given (zero
// iterations for the limbs solved in closed form), with `newton_options` when given (a run's
// continuation bound).
void solve_ik_closed_form(const Model& model, Coordinates& s, const Branches& branches = {},
                          NewtonReport* newton = nullptr, const NewtonOptions* newton_options = nullptr);

// Which branch of the closed form a solution lies on (the branch whose solution is nearest).
int classify_branch(const Model& model, Limb limb, const Coordinates& s);

// NewtonOptions and kContinuationJump, the bound of a run's continuation: wlx/ik_options.hpp.

struct NewtonReport {
  std::array<int, kLimbCount> iterations{};  // per limb
  double residual = 0;                        // max |Phi| over the solved limbs' equations at the end
  bool converged = false;
};

// Newton's method on Phi with the generated dPhi/ds, limb by limb (the limbs decouple), damped
// (Levenberg-Marquardt) so that it also descends from a far or singular start, starting from the
// dependent joints already in s (warm start). Throws wlx::Error if a limb does not converge within
// max_iterations (naming the limb, its residual and what to try).
NewtonReport solve_ik_newton(const Model& model, Data& data, Coordinates& s, const NewtonOptions& options = {});
// The same for the limbs marked in `limbs`, first from the joints in s (continuation along a sweep
// or a run), then, if that fails, from the model file's start values (settings().dependent_start).
// With a finite options.max_jump, a result whose joints moved further than that from the joints in
// s (on either path) is an error naming the limb and the joint.
NewtonReport solve_newton_limbs(const Model& model, Data& data, const std::array<bool, kLimbCount>& limbs, Coordinates& s,
                                const NewtonOptions& options = {});
// s with its dependent joints at the model file's start values for Newton's method.
Coordinates dependent_start(Coordinates s);
// The same for one limb only; the other limbs' joints are left as they are.
NewtonReport solve_limb_newton(const Model& model, Data& data, Limb limb, Coordinates& s,
                               const NewtonOptions& options = {});

WLX_MODEL_NAMESPACE_END
