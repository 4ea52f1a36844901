// The inverse kinematics' algorithms written once for both runtimes: the model's own (wlx/ik.hpp,
// compiled per model at its fixed sizes) and the one compiled once for every model
// (wlx/generic/ik.hpp, at run-time sizes). They see the model through a problem P that each
// runtime defines over its own Model and Data:
//
//   using Vector;                        the coordinates' vector type
//   static constexpr int kLimbSize;      the largest limb's size (the limb steps' fixed size N)
//   static constexpr int kLimbCapacity;  a bound of limb_count(): the size of per-limb arrays
//   int limb_count() const;  int coordinate_count() const;  int input_count() const;
//   IkLimb limb(int l) const;            its rows, joints and the inputs its rows read
//   std::string_view limb_title(int l) const;
//   std::string_view coordinate_name(int k) const;  std::string_view coordinate_unit(int k) const;
//   double lower(int k) const;  double upper(int k) const;   the joints' ranges
//   double dependent_start(int k) const;                     Newton's start of coordinate k
//   int default_branch(int l) const;                         -1: none given
//   bool has_closed_form(int l) const;  int closed_form_branches(int l) const;
//   std::string_view closed_form_failure(int l, int stage) const;   stage 1 or 2
//   bool has_fused_ik() const;                               every limb has a closed form
//   ClosedFormStatus solve_limb(int l, int branch, Vector& s, ClosedFormFailure& why);
//   ClosedFormStatus solve_all(const int* branches, Vector& s, ClosedFormFailure& why);
//   void evaluate_closure(const Vector& s, bool with_jacobian);
//   double Phi(int row) const;  double dPhi_ds(int row, int k) const;  bool Phi_finite() const;
//
// Nothing here allocates beyond what copying P::Vector does (nothing at fixed sizes).
#pragma once

#include "wlx/error.hpp"
#include "wlx/ik_options.hpp"
#include "wlx/limb_steps.hpp"
#include "wlx/model_code.hpp"

#include <fmt/format.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>

namespace wlx {
namespace ik_algorithms {

inline double wrap(double a) {
  constexpr double kPi = std::numbers::pi;
  if (a > -kPi && a <= kPi) return a;  // the usual case, without the slow remainder
  a = std::remainder(a, 2 * kPi);
  return a == -kPi ? kPi : a;
}

template <class P>
void require_finite(const P& p, const typename P::Vector& s, int k) {
  if (!std::isfinite(s(k))) throw Error(std::string(p.coordinate_name(k)), fmt::format("must be a finite number, got {}", s(k)));
}

// Turns a generated solver's failure into the error that names the limb and the reason.
template <class P>
[[noreturn]] void throw_failure(const P& p, int limb, int branch, ClosedFormStatus status, const ClosedFormFailure& why) {
  switch (status) {
    case ClosedFormStatus::out_of_reach:
      throw Error(std::string(p.limb_title(limb)),
                  fmt::format(fmt::runtime(p.closed_form_failure(limb, std::clamp(why.stage, 1, 2))), fmt::arg("value", why.value),
                              fmt::arg("low", why.low), fmt::arg("high", why.high), fmt::arg("aux", why.aux)),
                  ErrorKind::out_of_reach);
    case ClosedFormStatus::residual:
      throw Error(std::string(p.limb_title(limb)),
                  fmt::format("the closed-form solution does not satisfy the model: the limb's closure residual is {:.3e}, "
                              "above the tolerance {:.1e}",
                              why.value, why.high));
    case ClosedFormStatus::ok:
    case ClosedFormStatus::bad_branch: break;
  }
  throw Error("branch", fmt::format("{} has no branch {}", p.limb_title(limb), branch));
}

template <class P>
int branch_count(const P& p, int limb) {
  return p.has_closed_form(limb) ? p.closed_form_branches(limb) : 1;
}

template <class P>
void check_branch(const P& p, int limb, int branch) {
  if (branch < 0 || branch >= branch_count(p, limb))
    throw Error("branch", fmt::format("{} has branches 0 to {}, got {}", p.limb_title(limb), branch_count(p, limb) - 1, branch));
}

template <class P>
void check_inputs_and_branch(const P& p, int limb, int branch, const typename P::Vector& s) {
  const IkLimb l = p.limb(limb);
  for (int i = 0; i < l.input_count; ++i) require_finite(p, s, l.inputs[i]);
  check_branch(p, limb, branch);
}

// Whether coordinate k of s lies within its range (bounds included); a NaN lies within none.
template <class P>
bool within_range(const P& p, const typename P::Vector& s, int k) noexcept {
  return s(k) >= p.lower(k) && s(k) <= p.upper(k);  // false for NaN too
}

template <class P>
int first_outside_limits(const P& p, const typename P::Vector& s) noexcept {
  for (int k = 0; k < p.coordinate_count(); ++k)
    if (!within_range(p, s, k)) return k;
  return -1;
}

template <class P>
std::string describe_outside_limits(const P& p, const typename P::Vector& s, int k) {
  return fmt::format("{} = {:.6g} is outside its range [{:.6g}, {:.6g}]", p.coordinate_name(k), s(k), p.lower(k), p.upper(k));
}

template <class P>
bool limb_has_limits(const P& p, int limb) {
  const IkLimb l = p.limb(limb);
  for (int j = 0; j < l.size; ++j)
    if (std::isfinite(p.lower(l.joints[j])) || std::isfinite(p.upper(l.joints[j]))) return true;
  return false;
}

template <class P>
bool limb_within_limits(const P& p, int limb, const typename P::Vector& s) {
  const IkLimb l = p.limb(limb);
  for (int j = 0; j < l.size; ++j)
    if (!within_range(p, s, l.joints[j])) return false;
  return true;
}

// What both of Newton's algorithms below keep per limb across their iterations.
template <class P>
using LimbFlags = std::array<bool, static_cast<std::size_t>(P::kLimbCapacity)>;

template <class P>
struct NewtonProgress {
  std::array<int, static_cast<std::size_t>(P::kLimbCapacity)> iterations{};
  double residual = 0;
  bool converged = false;  // Newton's method ran and converged on every limb it was given
  LimbFlags<P> done{}, stalled{};
};

// The limbs Newton's method solved (solve_newton: the report's own type fills in from this).
template <class P, class Report>
void fill_report(const P& p, const NewtonProgress<P>& progress, Report& report) {
  for (int l = 0; l < p.limb_count(); ++l) report.iterations[static_cast<std::size_t>(l)] = progress.iterations[static_cast<std::size_t>(l)];
  report.residual = progress.residual;
  report.converged = progress.converged;
}

template <class P>
double limb_residual(const P& p, const IkLimb& l) {
  double r = 0;
  for (int i = 0; i < l.size; ++i) r = std::max(r, std::abs(p.Phi(l.rows[i])));
  return r;
}

template <class P>
double half_square(const P& p, const IkLimb& l) {
  double f = 0;
  for (int i = 0; i < l.size; ++i) f += 0.5 * p.Phi(l.rows[i]) * p.Phi(l.rows[i]);
  return f;
}

template <int N>
using LimbMatrix = Eigen::Matrix<double, N, N>;
template <int N>
using LimbVector = Eigen::Matrix<double, N, 1>;

// The limb's block of dPhi/ds (its rows against its own dependent joints) and its residual; a
// smaller limb is padded with a unit diagonal and a zero residual.
template <class P>
void limb_system(const P& p, const IkLimb& l, LimbMatrix<P::kLimbSize>& J, LimbVector<P::kLimbSize>& r) {
  J.setIdentity();
  r.setZero();
  for (int i = 0; i < l.size; ++i) {
    const int row = l.rows[i];
    r(i) = p.Phi(row);
    for (int j = 0; j < l.size; ++j) J(i, j) = p.dPhi_ds(row, l.joints[j]);
  }
}

template <class P>
void copy_limb_joints(const P& p, int limb, const typename P::Vector& from, typename P::Vector& s) {
  const IkLimb l = p.limb(limb);
  for (int j = 0; j < l.size; ++j) s(l.joints[j]) = from(l.joints[j]);
}

template <class P>
Error not_converged(const P& p, int limb, bool no_descent, double residual, int iterations, const NewtonOptions& options) {
  return Error(std::string(p.limb_title(limb)),
               fmt::format("Newton's method did not converge{} (residual {:.3e} after {} iterations, tolerance "
                           "{:.1e}): the target may be out of reach or the start too far from a solution; try a target "
                           "nearer the limb's workspace, approach it in smaller steps from a solved pose, or give the "
                           "limb a start nearer a solution (`start:` in the model file's limb)",
                           no_descent ? ": no step lowers the residual any more" : "", residual, iterations,
                           options.tolerance),
               ErrorKind::out_of_reach);
}

template <class P>
void require_finite_closure(const P& p) {
  if (!p.Phi_finite()) throw Error("", "closure residual is not finite: the starting guess is unusable");
}

// Whether a limb with this residual is done: within the tolerance, or, once it stalled or ran out
// of iterations, within the floor tolerance.
inline bool limb_done(double residual, bool stalled, bool out_of_steps, const NewtonOptions& options) {
  return residual <= options.tolerance || ((stalled || out_of_steps) && residual <= options.floor_tolerance);
}

// The thesis' method (NewtonOptions::Method::backtracking): full Newton steps, each halved until
// max |Phi| of its limb decreases.
template <class P>
void newton_backtracking(P& p, typename P::Vector& s, const NewtonOptions& options, NewtonProgress<P>& progress) {
  constexpr int N = P::kLimbSize;
  constexpr auto kCapacity = static_cast<std::size_t>(P::kLimbCapacity);
  const int limbs = p.limb_count();
  while (true) {
    p.evaluate_closure(s, true);
    require_finite_closure(p);
    bool all_done = true;
    std::array<LimbVector<N>, kCapacity> step;
    std::array<double, kCapacity> before{};
    for (int limb = 0; limb < limbs; ++limb) {
      const auto l = static_cast<std::size_t>(limb);
      if (progress.done[l]) continue;  // a converged limb stays converged: the limbs do not couple
      const IkLimb idx = p.limb(limb);
      before[l] = limb_residual(p, idx);
      const bool out_of_steps = progress.iterations[l] >= options.max_iterations;
      progress.done[l] = limb_done(before[l], progress.stalled[l], out_of_steps, options);
      if (progress.done[l]) continue;
      all_done = false;
      if (out_of_steps) throw not_converged(p, limb, false, before[l], progress.iterations[l], options);
      LimbMatrix<N> J;
      LimbVector<N> r;
      limb_system(p, idx, J, r);
      if (!limb_steps::newton_step<N>(J, r, step[l])) {
        // At a singular pose (straight leg, lever at 90 deg): Levenberg-Marquardt's step.
        const double mu = 1e-8 * std::max(1.0, J.squaredNorm());
        step[l] = limb_steps::regularized_step<N>(J, r, mu);
      }
      ++progress.iterations[l];
    }
    if (all_done) return;
    // Damping: halve a limb's step until its residual decreases.
    std::array<double, kCapacity> lambda;
    lambda.fill(1.0);
    LimbFlags<P> accepted = progress.done;
    const typename P::Vector start = s;
    for (int halving = 0; halving < 40; ++halving) {
      for (int limb = 0; limb < limbs; ++limb) {
        const auto l = static_cast<std::size_t>(limb);
        if (accepted[l]) continue;
        const IkLimb idx = p.limb(limb);
        for (int j = 0; j < idx.size; ++j) s(idx.joints[j]) = start(idx.joints[j]) + lambda[l] * step[l](j);
      }
      p.evaluate_closure(s, false);
      bool all_accepted = true;
      for (int limb = 0; limb < limbs; ++limb) {
        const auto l = static_cast<std::size_t>(limb);
        if (accepted[l]) continue;
        const double after = limb_residual(p, p.limb(limb));
        if (after < before[l] || !std::isfinite(before[l])) accepted[l] = true;
        else lambda[l] *= 0.5;
        all_accepted = all_accepted && accepted[l];
      }
      if (all_accepted) break;
    }
    for (int limb = 0; limb < limbs; ++limb) {
      const auto l = static_cast<std::size_t>(limb);
      progress.stalled[l] = !progress.done[l] && !accepted[l];
      // No step length lowered the residual: stay where the residual was lowest.
      if (progress.stalled[l]) copy_limb_joints(p, limb, start, s);
    }
  }
}

// Damped Newton (Levenberg-Marquardt): a limb's step solves (J^T J + mu I) dx = -J^T r. With mu
// small it is Newton's step (quadratic convergence near a regular solution), with mu large a short
// gradient step, so the method also descends from a far or singular start (a straight leg). mu
// follows the gain ratio of each step (Nielsen's rule), one generated closure evaluation serving
// the trial steps of every limb at once.
template <class P>
void newton_levenberg_marquardt(P& p, typename P::Vector& s, const NewtonOptions& options, NewtonProgress<P>& progress) {
  constexpr int N = P::kLimbSize;
  constexpr auto kCapacity = static_cast<std::size_t>(P::kLimbCapacity);
  const int limbs = p.limb_count();
  std::array<double, kCapacity> mu{}, nu{};
  nu.fill(2);
  p.evaluate_closure(s, true);
  require_finite_closure(p);
  std::array<LimbVector<N>, kCapacity> step, gradient;
  std::array<double, kCapacity> before{};
  while (true) {
    bool all_done = true;
    for (int limb = 0; limb < limbs; ++limb) {
      const auto l = static_cast<std::size_t>(limb);
      if (progress.done[l]) continue;
      const IkLimb idx = p.limb(limb);
      const double residual = limb_residual(p, idx);
      const bool out_of_steps = progress.iterations[l] >= options.max_iterations;
      progress.done[l] = limb_done(residual, progress.stalled[l], out_of_steps, options);
      if (progress.done[l]) continue;
      if (progress.stalled[l] || out_of_steps)
        throw not_converged(p, limb, progress.stalled[l], residual, progress.iterations[l], options);
      all_done = false;
      LimbMatrix<N> J;
      LimbVector<N> r;
      limb_system(p, idx, J, r);
      gradient[l] = J.transpose() * r;
      if (mu[l] == 0) mu[l] = 1e-9 * std::max(1.0, J.colwise().squaredNorm().maxCoeff());  // nearly Newton's step first
      // As the least-squares problem [J; sqrt(mu) I] dx = [-r; 0], by QR (limb_steps.hpp).
      step[l] = limb_steps::damped_step<N>(J, r, mu[l]);
      before[l] = half_square(p, idx);
      ++progress.iterations[l];
    }
    if (all_done) return;
    const typename P::Vector start = s;
    for (int limb = 0; limb < limbs; ++limb) {
      const auto l = static_cast<std::size_t>(limb);
      if (progress.done[l]) continue;
      const IkLimb idx = p.limb(limb);
      for (int j = 0; j < idx.size; ++j) s(idx.joints[j]) += step[l](j);
    }
    p.evaluate_closure(s, true);
    bool restore = false;
    for (int limb = 0; limb < limbs; ++limb) {
      const auto l = static_cast<std::size_t>(limb);
      if (progress.done[l]) continue;
      const double after = half_square(p, p.limb(limb));
      // The decrease the linear model predicts: dx^T (mu dx - g) / 2 > 0.
      const double predicted = 0.5 * step[l].dot(mu[l] * step[l] - gradient[l]);
      const double gain = predicted > 0 ? (before[l] - after) / predicted : -1;
      if (std::isfinite(after) && after < before[l] && gain > 0) {
        mu[l] *= std::max(1.0 / 3, 1 - std::pow(2 * gain - 1, 3));
        nu[l] = 2;
      } else {
        copy_limb_joints(p, limb, start, s);
        restore = true;
        mu[l] *= nu[l];
        nu[l] *= 2;
        // No damping helps any more: the residual is at its floor (or a local minimum).
        progress.stalled[l] = nu[l] > 1e6 || !std::isfinite(mu[l]);  // twenty rejected steps in a row
      }
    }
    if (restore) p.evaluate_closure(s, true);  // Phi and dPhi/ds where every limb now stands
    require_finite_closure(p);
  }
}

// Angles into (-pi, pi], but only where that keeps the closure: a row such as theta_4 + theta_5 = 0
// holds for theta_4 = -pi, not for its wrapped +pi, when the input theta_5 is pi.
template <class P>
void wrap_angles_keeping_closure(P& p, const LimbFlags<P>& active, const NewtonOptions& options, typename P::Vector& s) {
  const int limbs = p.limb_count();
  std::array<double, static_cast<std::size_t>(P::kLimbCapacity)> converged{};
  for (int limb = 0; limb < limbs; ++limb)
    if (active[static_cast<std::size_t>(limb)]) converged[static_cast<std::size_t>(limb)] = limb_residual(p, p.limb(limb));
  const typename P::Vector unwrapped = s;
  for (int limb = 0; limb < limbs; ++limb) {
    if (!active[static_cast<std::size_t>(limb)]) continue;
    const IkLimb idx = p.limb(limb);
    for (int j = 0; j < idx.size; ++j)
      if (p.coordinate_unit(idx.joints[j]) == "rad") s(idx.joints[j]) = wrap(s(idx.joints[j]));
  }
  p.evaluate_closure(s, false);
  bool reverted = false;
  for (int limb = 0; limb < limbs; ++limb) {
    const auto l = static_cast<std::size_t>(limb);
    if (!active[l] || limb_residual(p, p.limb(limb)) <= std::max(options.tolerance, 2 * converged[l])) continue;
    copy_limb_joints(p, limb, unwrapped, s);
    reverted = true;
  }
  if (reverted) p.evaluate_closure(s, false);
}

// Newton's method on the closure, limb by limb (the limbs decouple: each limb's rows involve only
// its own joints), from the dependent joints in s, by the algorithm options.method names; then the
// angles wrapped and the result checked.
template <class P>
NewtonProgress<P> newton(P& p, const LimbFlags<P>& active, typename P::Vector& s, const NewtonOptions& options) {
  for (int k = 0; k < p.coordinate_count(); ++k) require_finite(p, s, k);
  NewtonProgress<P> progress;
  const int limbs = p.limb_count();
  for (int limb = 0; limb < limbs; ++limb) progress.done[static_cast<std::size_t>(limb)] = !active[static_cast<std::size_t>(limb)];
  if (options.method == NewtonOptions::Method::backtracking) newton_backtracking(p, s, options, progress);
  if (options.method == NewtonOptions::Method::levenberg_marquardt) newton_levenberg_marquardt(p, s, options, progress);
  wrap_angles_keeping_closure(p, active, options, s);
  for (int limb = 0; limb < limbs; ++limb) {
    if (!active[static_cast<std::size_t>(limb)]) continue;
    const double r = limb_residual(p, p.limb(limb));
    // Never a success whose residual is above what Newton accepts.
    if (!(r <= options.floor_tolerance))
      throw Error(std::string(p.limb_title(limb)),
                  fmt::format("Newton's result does not satisfy the closure: residual {:.3e} above {:.1e}", r,
                              options.floor_tolerance));
    progress.residual = std::max(progress.residual, r);
  }
  progress.converged = true;
  return progress;
}

// s with its dependent joints at the model's start values for Newton's method.
template <class P>
typename P::Vector dependent_start(const P& p, typename P::Vector s) {
  for (int k = p.input_count(); k < p.coordinate_count(); ++k) s(k) = p.dependent_start(k);
  return s;
}

// The limbs marked in `limbs`, first from the joints in s (continuation along a sweep or a run),
// then, if that fails, from the model's start values; with a finite options.max_jump, a result
// whose joints moved further than that from the joints in s is an error naming the limb and joint.
template <class P>
NewtonProgress<P> solve_newton_limbs(P& p, const LimbFlags<P>& limbs, typename P::Vector& s, const NewtonOptions& options) {
  using Vector = typename P::Vector;
  const int limb_count = p.limb_count();
  // From the joints in s (the previous solution along a sweep or a run: continuation), else, when
  // that fails or s holds no usable guess, from the model file's start values.
  bool usable = true;
  for (int limb = 0; limb < limb_count; ++limb)
    if (limbs[static_cast<std::size_t>(limb)]) {
      const IkLimb idx = p.limb(limb);
      for (int j = 0; j < idx.size; ++j) usable = usable && std::isfinite(s(idx.joints[j]));
    }
  const Vector previous = s;
  // Continuation follows one solution: a result whose joints moved further than options.max_jump
  // from the previous solution is another root (angles compared on the circle: results are wrapped).
  const auto check_jump = [&](const Vector& result, bool restarted) {
    if (!usable || !(options.max_jump < std::numeric_limits<double>::infinity())) return;
    for (int limb = 0; limb < limb_count; ++limb) {
      if (!limbs[static_cast<std::size_t>(limb)]) continue;
      const IkLimb idx = p.limb(limb);
      for (int j = 0; j < idx.size; ++j) {
        const int k = idx.joints[j];
        const std::string_view unit = p.coordinate_unit(k);
        const double move = std::abs(unit == "rad" ? wrap(result(k) - previous(k)) : result(k) - previous(k));
        if (!(move <= options.max_jump))
          throw Error(std::string(p.limb_title(limb)),
                      fmt::format("Newton's method {} another solution: {} moved from {:.6g} to {:.6g} {} between two "
                                  "evaluations, more than a continuation step's bound of {} {} (the limb passes near a "
                                  "singular pose, where two solutions meet, or the steps are too long)",
                                  restarted ? "lost the solution it followed and, from the start values, found" : "jumped to",
                                  p.coordinate_name(k), previous(k), result(k), unit, options.max_jump, unit));
      }
    }
  };
  if (usable) {
    Vector warm = s;
    bool converged = false;
    NewtonProgress<P> progress;
    try {
      progress = newton(p, limbs, warm, options);
      converged = true;
    } catch (const Error&) {
      // fall through to the model's start values, whose error is the one reported
    }
    if (converged) {
      check_jump(warm, false);
      s = warm;
      return progress;
    }
  }
  const Vector fresh = dependent_start(p, s);
  Vector cold = s;  // s stays the previous solution when this one is refused
  for (int limb = 0; limb < limb_count; ++limb)
    if (limbs[static_cast<std::size_t>(limb)]) {
      const IkLimb idx = p.limb(limb);
      for (int j = 0; j < idx.size; ++j) cold(idx.joints[j]) = fresh(idx.joints[j]);
    }
  const NewtonProgress<P> progress = newton(p, limbs, cold, options);
  check_jump(cold, true);
  s = cold;
  return progress;
}

// One limb's dependent joints in s from its inputs in s: its closed form on `branch`, or Newton's
// method for a limb without one.
template <class P>
void solve_limb_closed_form(P& p, int limb, int branch, typename P::Vector& s) {
  check_inputs_and_branch(p, limb, branch, s);
  if (!p.has_closed_form(limb)) {  // wlx-gen found no closed form for this limb
    LimbFlags<P> newton{};
    newton[static_cast<std::size_t>(limb)] = true;
    solve_newton_limbs(p, newton, s, {});
    return;
  }
  ClosedFormFailure why;
  const ClosedFormStatus status = p.solve_limb(limb, branch, s, why);
  if (status != ClosedFormStatus::ok) throw_failure(p, limb, branch, status, why);
}

// The model's choice of branch for each limb at the inputs in s (wlx/ik.hpp, resolve_branches):
// `branches` holds the requested ones (kModelsChoice: the model's) and receives the choice.
template <class P, class Branches>
void resolve_branches(P& p, const typename P::Vector& s, Branches& branches, LimbFlags<P>* outside) {
  for (int limb = 0; limb < p.limb_count(); ++limb) {
    const auto l = static_cast<std::size_t>(limb);
    const int preferred = std::max(p.default_branch(limb), 0);
    bool leaves = false;
    if (branches[l] == kModelsChoice) {
      branches[l] = preferred;
      if (limb_has_limits(p, limb)) {
        leaves = true;
        // The default branch first, then the others in order: the first within the ranges wins.
        for (int k = -1; k < branch_count(p, limb) && leaves; ++k) {
          const int b = k < 0 ? preferred : k;
          if (k == preferred) continue;
          typename P::Vector candidate = s;
          try {
            solve_limb_closed_form(p, limb, b, candidate);
          } catch (const Error&) {
            continue;
          }
          if (limb_within_limits(p, limb, candidate)) branches[l] = b, leaves = false;
        }
      }
    } else if (outside != nullptr && limb_has_limits(p, limb)) {
      typename P::Vector candidate = s;
      try {
        solve_limb_closed_form(p, limb, branches[l], candidate);
        leaves = !limb_within_limits(p, limb, candidate);
      } catch (const Error&) {
      }
    }
    if (outside != nullptr) (*outside)[l] = leaves;
  }
}

// All limbs, each on its branch (resolved first where the model chooses); those without a closed
// form by Newton's method from the dependent joints in s. Returns Newton's progress (nothing done
// when every limb has a closed form).
template <class P, class Branches>
NewtonProgress<P> solve_ik_closed_form(P& p, typename P::Vector& s, Branches branches, const NewtonOptions* newton_options) {
  bool choose = false;
  for (int limb = 0; limb < p.limb_count(); ++limb) choose = choose || branches[static_cast<std::size_t>(limb)] == kModelsChoice;
  if (choose) resolve_branches(p, s, branches, static_cast<LimbFlags<P>*>(nullptr));
  // Every limb with a closed form in one generated pass (the body's pose and the sines and cosines
  // computed once); the limbs without one then by Newton's method from the dependent joints in s.
  if (s.head(p.input_count()).allFinite()) {  // the usual case: only the branches to check
    for (int limb = 0; limb < p.limb_count(); ++limb) check_branch(p, limb, branches[static_cast<std::size_t>(limb)]);
  } else {
    for (int limb = 0; limb < p.limb_count(); ++limb) check_inputs_and_branch(p, limb, branches[static_cast<std::size_t>(limb)], s);
  }
  ClosedFormFailure why;
  const ClosedFormStatus status = p.solve_all(branches.data(), s, why);
  if (status != ClosedFormStatus::ok) throw_failure(p, why.limb, branches[static_cast<std::size_t>(why.limb)], status, why);
  if (p.has_fused_ik()) return {};
  LimbFlags<P> newton{};
  for (int limb = 0; limb < p.limb_count(); ++limb) newton[static_cast<std::size_t>(limb)] = !p.has_closed_form(limb);
  return solve_newton_limbs(p, newton, s, newton_options ? *newton_options : NewtonOptions{});
}

// Which branch of the closed form a solution lies on (the branch whose solution is nearest).
template <class P>
int classify_branch(P& p, int limb, const typename P::Vector& s) {
  const IkLimb idx = p.limb(limb);
  int best = 0;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int b = 0; b < branch_count(p, limb); ++b) {
    typename P::Vector candidate = s;
    try {
      solve_limb_closed_form(p, limb, b, candidate);
    } catch (const Error&) {
      continue;
    }
    double distance = 0;
    for (int j = 0; j < idx.size; ++j) distance = std::max(distance, std::abs(wrap(candidate(idx.joints[j]) - s(idx.joints[j]))));
    if (distance < best_distance) best_distance = distance, best = b;
  }
  return best;
}

}  // namespace ik_algorithms
}  // namespace wlx
