#include "wlx/ik.hpp"

#include "wlx/error.hpp"
#include "wlx/kinematics.hpp"
#include "wlx/limb_steps.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

constexpr double kPi = std::numbers::pi;
using LimbMatrix = Eigen::Matrix<double, gen::kMaxLimbSize, gen::kMaxLimbSize>;
using LimbVector = Eigen::Matrix<double, gen::kMaxLimbSize, 1>;

double wrap(double a) {
  if (a > -kPi && a <= kPi) return a;  // the usual case, without the slow remainder
  a = std::remainder(a, 2 * kPi);
  return a == -kPi ? kPi : a;
}

void require_finite(const Coordinates& s, int k) {
  if (!std::isfinite(s(k)))
    throw Error(std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]), fmt::format("must be a finite number, got {}", s(k)));
}

const gen::LimbInfo& info(Limb limb) { return gen::kLimbs[static_cast<std::size_t>(limb)]; }

// Short names for the limb blocks inside this file.
struct LimbIndices {
  std::array<int, gen::kMaxLimbSize> dep;
  std::array<int, gen::kMaxLimbSize> rows;
  int count;
};

LimbIndices indices(Limb limb) {
  const LimbBlock b = limb_block(limb);
  return {b.joints, b.rows, b.size};
}

}  // namespace

LimbBlock limb_block(Limb limb) noexcept {
  const gen::LimbInfo& l = info(limb);
  LimbBlock b;
  b.size = l.size;
  b.rows = l.rows;
  b.joints = l.joints;
  return b;
}

std::string_view limb_name(Limb limb) noexcept { return info(limb).title; }

bool has_closed_form(Limb limb) noexcept { return gen::kClosedForm[static_cast<std::size_t>(limb)].solve != nullptr; }

int branch_count(Limb limb) noexcept {
  const gen::ClosedFormInfo& cf = gen::kClosedForm[static_cast<std::size_t>(limb)];
  return cf.solve == nullptr ? 1 : cf.branches;
}

namespace {

// Turns a generated solver's failure into the error that names the limb and the reason.
[[noreturn]] void throw_failure(Limb limb, int branch, gen::IkStatus status, const gen::IkDiagnostics& why) {
  const gen::ClosedFormInfo& cf = gen::kClosedForm[static_cast<std::size_t>(limb)];
  switch (status) {
    case gen::IkStatus::out_of_reach:
      throw Error(std::string(limb_name(limb)),
                  fmt::format(fmt::runtime(cf.failures[static_cast<std::size_t>(std::clamp(why.stage, 1, 2) - 1)]),
                              fmt::arg("value", why.value), fmt::arg("low", why.low), fmt::arg("high", why.high),
                              fmt::arg("aux", why.aux)),
                  ErrorKind::out_of_reach);
    case gen::IkStatus::residual:
      throw Error(std::string(limb_name(limb)),
                  fmt::format("the closed-form solution does not satisfy the model: the limb's closure residual is {:.3e}, "
                              "above the tolerance {:.1e}",
                              why.value, why.high));
    case gen::IkStatus::ok:
    case gen::IkStatus::bad_branch: break;
  }
  throw Error("branch", fmt::format("{} has no branch {}", limb_name(limb), branch));
}

void check_branch(Limb limb, int branch) {
  if (branch < 0 || branch >= branch_count(limb))
    throw Error("branch", fmt::format("{} has branches 0 to {}, got {}", limb_name(limb), branch_count(limb) - 1, branch));
}

void check_inputs_and_branch(Limb limb, int branch, const Coordinates& s) {
  const gen::LimbInfo& l = info(limb);
  for (int i = 0; i < l.input_count; ++i) require_finite(s, l.inputs[static_cast<std::size_t>(i)]);
  check_branch(limb, branch);
}

}  // namespace

void solve_limb_closed_form(const Model& model, Limb limb, int branch, Coordinates& s) {
  check_inputs_and_branch(limb, branch, s);
  const gen::ClosedFormInfo& cf = gen::kClosedForm[static_cast<std::size_t>(limb)];
  if (cf.solve == nullptr) {  // wlx-gen found no closed form for this limb
    std::array<bool, kLimbCount> newton{};
    newton[static_cast<std::size_t>(limb)] = true;
    Data data;
    solve_newton_limbs(model, data, newton, s, {});
    return;
  }
  gen::IkDiagnostics why;
  const gen::IkStatus status = cf.solve(s, model.params(), branch, s, why);
  if (status != gen::IkStatus::ok) throw_failure(limb, branch, status, why);
}

namespace {
bool limb_has_limits(Limb limb) {
  const LimbBlock block = limb_block(limb);
  for (int j = 0; j < block.size; ++j) {
    const auto k = static_cast<std::size_t>(block.joints[static_cast<std::size_t>(j)]);
    if (std::isfinite(settings().lower[k]) || std::isfinite(settings().upper[k])) return true;
  }
  return false;
}
bool limb_within_limits(Limb limb, const Coordinates& s) {
  const LimbBlock block = limb_block(limb);
  for (int j = 0; j < block.size; ++j) {
    const auto k = static_cast<std::size_t>(block.joints[static_cast<std::size_t>(j)]);
    if (!within_range(s, static_cast<int>(k))) return false;
  }
  return true;
}
}  // namespace

bool within_range(const Coordinates& s, int k) noexcept {
  const auto kk = static_cast<std::size_t>(k);
  return s(k) >= settings().lower[kk] && s(k) <= settings().upper[kk];  // false for NaN too
}

int first_outside_limits(const Coordinates& s) noexcept {
  for (int k = 0; k < kCoordinateCount; ++k)
    if (!within_range(s, k)) return k;
  return -1;
}

std::string describe_outside_limits(const Coordinates& s, int k) {
  const auto kk = static_cast<std::size_t>(k);
  return fmt::format("{} = {:.6g} is outside its range [{:.6g}, {:.6g}]", gen::kCoordinateNames[kk], s(k),
                     settings().lower[kk], settings().upper[kk]);
}

Branches resolve_branches(const Model& model, const Coordinates& s, const Branches& requested, std::array<bool, kLimbCount>* outside) {
  Branches out = requested;
  for (Limb limb : kLimbs) {
    const auto l = static_cast<std::size_t>(limb);
    const int preferred = std::max(settings().default_branch[l], 0);
    bool leaves = false;
    if (out.limb[l] == kModelsChoice) {
      out.limb[l] = preferred;
      if (limb_has_limits(limb)) {
        leaves = true;
        // The default branch first, then the others in order: the first within the ranges wins.
        for (int k = -1; k < branch_count(limb) && leaves; ++k) {
          const int b = k < 0 ? preferred : k;
          if (k == preferred) continue;
          Coordinates candidate = s;
          try {
            solve_limb_closed_form(model, limb, b, candidate);
          } catch (const Error&) {
            continue;
          }
          if (limb_within_limits(limb, candidate)) out.limb[l] = b, leaves = false;
        }
      }
    } else if (outside != nullptr && limb_has_limits(limb)) {
      Coordinates candidate = s;
      try {
        solve_limb_closed_form(model, limb, out.limb[l], candidate);
        leaves = !limb_within_limits(limb, candidate);
      } catch (const Error&) {
      }
    }
    if (outside != nullptr) (*outside)[l] = leaves;
  }
  return out;
}

void solve_ik_closed_form(const Model& model, Coordinates& s, const Branches& requested, NewtonReport* newton_report,
                          const NewtonOptions* newton_options) {
  bool choose = false;
  for (int b : requested.limb) choose = choose || b == kModelsChoice;
  const Branches branches = choose ? resolve_branches(model, s, requested) : requested;
  // Every limb with a closed form in one generated pass (the body's pose and the sines and cosines
  // computed once); the limbs without one (gen::kHasFusedIk false) then by Newton's method from
  // the dependent joints in s.
  if (s.head<kInputCount>().allFinite()) {  // the usual case: only the branches to check
    for (Limb limb : kLimbs) check_branch(limb, branches.limb[static_cast<std::size_t>(limb)]);
  } else {
    for (Limb limb : kLimbs) check_inputs_and_branch(limb, branches.limb[static_cast<std::size_t>(limb)], s);
  }
  int failed = 0;
  gen::IkDiagnostics why;
  const gen::IkStatus status = gen::ik_all(s, model.params(), branches.limb, s, failed, why);
  if (status != gen::IkStatus::ok) throw_failure(failed, branches.limb[static_cast<std::size_t>(failed)], status, why);
  if (newton_report != nullptr) *newton_report = NewtonReport{};
  if constexpr (!gen::kHasFusedIk) {
    std::array<bool, kLimbCount> newton{};
    for (Limb limb : kLimbs) newton[static_cast<std::size_t>(limb)] = !has_closed_form(limb);
    Data data;
    const NewtonReport report = solve_newton_limbs(model, data, newton, s, newton_options ? *newton_options : NewtonOptions{});
    if (newton_report != nullptr) *newton_report = report;
  }
}

int classify_branch(const Model& model, Limb limb, const Coordinates& s) {
  const LimbIndices idx = indices(limb);
  int best = 0;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int b = 0; b < branch_count(limb); ++b) {
    Coordinates candidate = s;
    try {
      solve_limb_closed_form(model, limb, b, candidate);
    } catch (const Error&) {
      continue;
    }
    double distance = 0;
    for (int j = 0; j < idx.count; ++j) {
      const int k = idx.dep[static_cast<std::size_t>(j)];
      distance = std::max(distance, std::abs(wrap(candidate(k) - s(k))));
    }
    if (distance < best_distance) best_distance = distance, best = b;
  }
  return best;
}

namespace {

// What both of Newton's algorithms below keep per limb across their iterations.
struct NewtonProgress {
  NewtonReport report;
  std::array<bool, kLimbCount> done{}, stalled{};
};

double limb_residual(const gen::ClosureVector& Phi, const LimbIndices& idx) {
  double r = 0;
  for (int i = 0; i < idx.count; ++i) r = std::max(r, std::abs(Phi(idx.rows[static_cast<std::size_t>(i)])));
  return r;
}

double half_square(const gen::ClosureVector& Phi, const LimbIndices& idx) {
  double f = 0;
  for (int i = 0; i < idx.count; ++i) f += 0.5 * Phi(idx.rows[static_cast<std::size_t>(i)]) * Phi(idx.rows[static_cast<std::size_t>(i)]);
  return f;
}

// The limb's block of dPhi/ds (its rows against its own dependent joints) and its residual; a
// smaller limb is padded with a unit diagonal and a zero residual.
void limb_system(const Data& data, const LimbIndices& idx, LimbMatrix& J, LimbVector& r) {
  J.setIdentity();
  r.setZero();
  for (int i = 0; i < idx.count; ++i) {
    const int row = idx.rows[static_cast<std::size_t>(i)];
    r(i) = data.Phi(row);
    for (int j = 0; j < idx.count; ++j) J(i, j) = data.dPhi_ds(row, idx.dep[static_cast<std::size_t>(j)]);
  }
}

void copy_limb_joints(Limb limb, const Coordinates& from, Coordinates& s) {
  const auto idx = indices(limb);
  for (int j = 0; j < idx.count; ++j) s(idx.dep[static_cast<std::size_t>(j)]) = from(idx.dep[static_cast<std::size_t>(j)]);
}

Error not_converged(Limb limb, bool no_descent, double residual, int iterations, const NewtonOptions& options) {
  return Error(std::string(limb_name(limb)),
               fmt::format("Newton's method did not converge{} (residual {:.3e} after {} iterations, tolerance "
                           "{:.1e}): the target may be out of reach or the start too far from a solution; try a target "
                           "nearer the limb's workspace, approach it in smaller steps from a solved pose, or give the "
                           "limb a start nearer a solution (`start:` in the model file's limb)",
                           no_descent ? ": no step lowers the residual any more" : "", residual, iterations,
                           options.tolerance),
               ErrorKind::out_of_reach);
}

void require_finite_closure(const Data& data) {
  if (!data.Phi.allFinite()) throw Error("", "closure residual is not finite: the starting guess is unusable");
}

// Whether a limb with this residual is done: within the tolerance, or, once it stalled or ran out
// of iterations, within the floor tolerance.
bool limb_done(double residual, bool stalled, bool out_of_steps, const NewtonOptions& options) {
  return residual <= options.tolerance || ((stalled || out_of_steps) && residual <= options.floor_tolerance);
}

// The thesis' method (NewtonOptions::Method::backtracking): full Newton steps, each halved until
// max |Phi| of its limb decreases.
void newton_backtracking(const Model& model, Coordinates& s, Data& data, const NewtonOptions& options, NewtonProgress& p) {
  while (true) {
    closure(model, data, s, true);
    require_finite_closure(data);
    bool all_done = true;
    std::array<LimbVector, kLimbCount> step;
    std::array<double, kLimbCount> before{};
    for (Limb limb : kLimbs) {
      const auto l = static_cast<std::size_t>(limb);
      if (p.done[l]) continue;  // a converged limb stays converged: the limbs do not couple
      const auto idx = indices(limb);
      before[l] = limb_residual(data.Phi, idx);
      const bool out_of_steps = p.report.iterations[l] >= options.max_iterations;
      p.done[l] = limb_done(before[l], p.stalled[l], out_of_steps, options);
      if (p.done[l]) continue;
      all_done = false;
      if (out_of_steps) throw not_converged(limb, false, before[l], p.report.iterations[l], options);
      LimbMatrix J;
      LimbVector r;
      limb_system(data, idx, J, r);
      if (!limb_steps::newton_step<gen::kMaxLimbSize>(J, r, step[l])) {
        // At a singular pose (straight leg, lever at 90 deg): Levenberg-Marquardt's step.
        const double mu = 1e-8 * std::max(1.0, J.squaredNorm());
        step[l] = limb_steps::regularized_step<gen::kMaxLimbSize>(J, r, mu);
      }
      ++p.report.iterations[l];
    }
    if (all_done) return;
    // Damping: halve a limb's step until its residual decreases.
    std::array<double, kLimbCount> lambda;
    lambda.fill(1.0);
    std::array<bool, kLimbCount> accepted = p.done;
    const Coordinates start = s;
    for (int halving = 0; halving < 40; ++halving) {
      for (Limb limb : kLimbs) {
        const auto l = static_cast<std::size_t>(limb);
        if (accepted[l]) continue;
        const auto idx = indices(limb);
        for (int j = 0; j < idx.count; ++j)
          s(idx.dep[static_cast<std::size_t>(j)]) = start(idx.dep[static_cast<std::size_t>(j)]) + lambda[l] * step[l](j);
      }
      closure(model, data, s, false);
      bool all_accepted = true;
      for (Limb limb : kLimbs) {
        const auto l = static_cast<std::size_t>(limb);
        if (accepted[l]) continue;
        const double after = limb_residual(data.Phi, indices(limb));
        if (after < before[l] || !std::isfinite(before[l])) accepted[l] = true;
        else lambda[l] *= 0.5;
        all_accepted = all_accepted && accepted[l];
      }
      if (all_accepted) break;
    }
    for (Limb limb : kLimbs) {
      const auto l = static_cast<std::size_t>(limb);
      p.stalled[l] = !p.done[l] && !accepted[l];
      // No step length lowered the residual: stay where the residual was lowest.
      if (p.stalled[l]) copy_limb_joints(limb, start, s);
    }
  }
}

// Damped Newton (Levenberg-Marquardt): a limb's step solves (J^T J + mu I) dx = -J^T r. With mu
// small it is Newton's step (quadratic convergence near a regular solution), with mu large a short
// gradient step, so the method also descends from a far or singular start (a straight leg). mu
// follows the gain ratio of each step (Nielsen's rule), one generated closure evaluation serving
// the trial steps of every limb at once.
void newton_levenberg_marquardt(const Model& model, Coordinates& s, Data& data, const NewtonOptions& options,
                                NewtonProgress& p) {
  std::array<double, kLimbCount> mu{}, nu{};
  nu.fill(2);
  closure(model, data, s, true);
  require_finite_closure(data);
  std::array<LimbVector, kLimbCount> step, gradient;
  std::array<double, kLimbCount> before{};
  while (true) {
    bool all_done = true;
    for (Limb limb : kLimbs) {
      const auto l = static_cast<std::size_t>(limb);
      if (p.done[l]) continue;
      const auto idx = indices(limb);
      const double residual = limb_residual(data.Phi, idx);
      const bool out_of_steps = p.report.iterations[l] >= options.max_iterations;
      p.done[l] = limb_done(residual, p.stalled[l], out_of_steps, options);
      if (p.done[l]) continue;
      if (p.stalled[l] || out_of_steps) throw not_converged(limb, p.stalled[l], residual, p.report.iterations[l], options);
      all_done = false;
      LimbMatrix J;
      LimbVector r;
      limb_system(data, idx, J, r);
      gradient[l] = J.transpose() * r;
      if (mu[l] == 0) mu[l] = 1e-9 * std::max(1.0, J.colwise().squaredNorm().maxCoeff());  // nearly Newton's step first
      // As the least-squares problem [J; sqrt(mu) I] dx = [-r; 0], by QR (limb_steps.hpp).
      step[l] = limb_steps::damped_step<gen::kMaxLimbSize>(J, r, mu[l]);
      before[l] = half_square(data.Phi, idx);
      ++p.report.iterations[l];
    }
    if (all_done) return;
    const Coordinates start = s;
    for (Limb limb : kLimbs) {
      const auto l = static_cast<std::size_t>(limb);
      if (p.done[l]) continue;
      const auto idx = indices(limb);
      for (int j = 0; j < idx.count; ++j) s(idx.dep[static_cast<std::size_t>(j)]) += step[l](j);
    }
    closure(model, data, s, true);
    bool restore = false;
    for (Limb limb : kLimbs) {
      const auto l = static_cast<std::size_t>(limb);
      if (p.done[l]) continue;
      const double after = half_square(data.Phi, indices(limb));
      // The decrease the linear model predicts: dx^T (mu dx - g) / 2 > 0.
      const double predicted = 0.5 * step[l].dot(mu[l] * step[l] - gradient[l]);
      const double gain = predicted > 0 ? (before[l] - after) / predicted : -1;
      if (std::isfinite(after) && after < before[l] && gain > 0) {
        mu[l] *= std::max(1.0 / 3, 1 - std::pow(2 * gain - 1, 3));
        nu[l] = 2;
      } else {
        copy_limb_joints(limb, start, s);
        restore = true;
        mu[l] *= nu[l];
        nu[l] *= 2;
        // No damping helps any more: the residual is at its floor (or a local minimum).
        p.stalled[l] = nu[l] > 1e6 || !std::isfinite(mu[l]);  // twenty rejected steps in a row
      }
    }
    if (restore) closure(model, data, s, true);  // Phi and dPhi/ds where every limb now stands
    require_finite_closure(data);
  }
}

// Angles into (-pi, pi], but only where that keeps the closure: a row such as theta_4 + theta_5 = 0
// holds for theta_4 = -pi, not for its wrapped +pi, when the input theta_5 is pi.
void wrap_angles_keeping_closure(const Model& model, const std::array<bool, kLimbCount>& active, const NewtonOptions& options,
                                 Coordinates& s, Data& data) {
  std::array<double, kLimbCount> converged{};
  for (Limb limb : kLimbs)
    if (active[static_cast<std::size_t>(limb)]) converged[static_cast<std::size_t>(limb)] = limb_residual(data.Phi, indices(limb));
  const Coordinates unwrapped = s;
  for (Limb limb : kLimbs) {
    if (!active[static_cast<std::size_t>(limb)]) continue;
    const auto idx = indices(limb);
    for (int j = 0; j < idx.count; ++j)
      if (gen::kCoordinateUnits[static_cast<std::size_t>(idx.dep[static_cast<std::size_t>(j)])] == "rad")
        s(idx.dep[static_cast<std::size_t>(j)]) = wrap(s(idx.dep[static_cast<std::size_t>(j)]));
  }
  closure(model, data, s, false);
  bool reverted = false;
  for (Limb limb : kLimbs) {
    const auto l = static_cast<std::size_t>(limb);
    if (!active[l] || limb_residual(data.Phi, indices(limb)) <= std::max(options.tolerance, 2 * converged[l])) continue;
    copy_limb_joints(limb, unwrapped, s);
    reverted = true;
  }
  if (reverted) closure(model, data, s, false);
}

// Newton's method on the closure, limb by limb (the limbs decouple: each limb's rows involve only
// its own joints), from the dependent joints in s, by the algorithm options.method names; then the
// angles wrapped and the result checked.
NewtonReport newton(const Model& model, std::array<bool, kLimbCount> active, Coordinates& s, Data& data,
                    const NewtonOptions& options) {
  for (int k = 0; k < kCoordinateCount; ++k) require_finite(s, k);
  NewtonProgress progress;
  for (Limb limb : kLimbs) progress.done[static_cast<std::size_t>(limb)] = !active[static_cast<std::size_t>(limb)];
  if (options.method == NewtonOptions::Method::backtracking) newton_backtracking(model, s, data, options, progress);
  if (options.method == NewtonOptions::Method::levenberg_marquardt) newton_levenberg_marquardt(model, s, data, options, progress);
  wrap_angles_keeping_closure(model, active, options, s, data);
  NewtonReport& report = progress.report;
  for (Limb limb : kLimbs) {
    if (!active[static_cast<std::size_t>(limb)]) continue;
    const double r = limb_residual(data.Phi, indices(limb));
    // Never a success whose residual is above what Newton accepts.
    if (!(r <= options.floor_tolerance))
      throw Error(std::string(limb_name(limb)),
                  fmt::format("Newton's result does not satisfy the closure: residual {:.3e} above {:.1e}", r,
                              options.floor_tolerance));
    report.residual = std::max(report.residual, r);
  }
  report.converged = true;
  return report;
}

}  // namespace

Coordinates dependent_start(Coordinates s) {
  const Settings& settings_in_use = settings();
  for (int k = kInputCount; k < kCoordinateCount; ++k) s(k) = settings_in_use.dependent_start[static_cast<std::size_t>(k - kInputCount)];
  return s;
}

NewtonReport solve_newton_limbs(const Model& model, Data& data, const std::array<bool, kLimbCount>& limbs, Coordinates& s,
                                const NewtonOptions& options) {
  // From the joints in s (the previous solution along a sweep or a run: continuation), else, when
  // that fails or s holds no usable guess, from the model file's start values.
  bool usable = true;
  for (Limb limb : kLimbs)
    if (limbs[static_cast<std::size_t>(limb)]) {
      const auto idx = indices(limb);
      for (int j = 0; j < idx.count; ++j) usable = usable && std::isfinite(s(idx.dep[static_cast<std::size_t>(j)]));
    }
  const Coordinates previous = s;
  // Continuation follows one solution: a result whose joints moved further than options.max_jump
  // from the previous solution is another root (angles compared on the circle: results are wrapped).
  const auto check_jump = [&](const Coordinates& result, bool restarted) {
    if (!usable || !(options.max_jump < std::numeric_limits<double>::infinity())) return;
    for (Limb limb : kLimbs) {
      if (!limbs[static_cast<std::size_t>(limb)]) continue;
      const auto idx = indices(limb);
      for (int j = 0; j < idx.count; ++j) {
        const int k = idx.dep[static_cast<std::size_t>(j)];
        const std::string_view unit = gen::kCoordinateUnits[static_cast<std::size_t>(k)];
        const double move = std::abs(unit == "rad" ? wrap(result(k) - previous(k)) : result(k) - previous(k));
        if (!(move <= options.max_jump))
          throw Error(std::string(limb_name(limb)),
                      fmt::format("Newton's method {} another solution: {} moved from {:.6g} to {:.6g} {} between two "
                                  "evaluations, more than a continuation step's bound of {} {} (the limb passes near a "
                                  "singular pose, where two solutions meet, or the steps are too long)",
                                  restarted ? "lost the solution it followed and, from the start values, found"
                                            : "jumped to",
                                  gen::kCoordinateNames[static_cast<std::size_t>(k)], previous(k), result(k), unit,
                                  options.max_jump, unit));
      }
    }
  };
  if (usable) {
    Coordinates warm = s;
    bool converged = false;
    NewtonReport report;
    try {
      report = newton(model, limbs, warm, data, options);
      converged = true;
    } catch (const Error&) {
      // fall through to the model's start values, whose error is the one reported
    }
    if (converged) {
      check_jump(warm, false);
      s = warm;
      return report;
    }
  }
  const Coordinates fresh = dependent_start(s);
  Coordinates cold = s;  // s stays the previous solution when this one is refused
  for (Limb limb : kLimbs)
    if (limbs[static_cast<std::size_t>(limb)]) {
      const auto idx = indices(limb);
      for (int j = 0; j < idx.count; ++j) cold(idx.dep[static_cast<std::size_t>(j)]) = fresh(idx.dep[static_cast<std::size_t>(j)]);
    }
  const NewtonReport report = newton(model, limbs, cold, data, options);
  check_jump(cold, true);
  s = cold;
  return report;
}

NewtonReport solve_ik_newton(const Model& model, Data& data, Coordinates& s, const NewtonOptions& options) {
  std::array<bool, kLimbCount> all;
  all.fill(true);
  return newton(model, all, s, data, options);
}

NewtonReport solve_limb_newton(const Model& model, Data& data, Limb limb, Coordinates& s,
                               const NewtonOptions& options) {
  std::array<bool, kLimbCount> active{};
  active[static_cast<std::size_t>(limb)] = true;
  return newton(model, active, s, data, options);
}

WLX_MODEL_NAMESPACE_END
