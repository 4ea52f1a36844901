// The time integrators (integration.hpp), compiled once into wlx::numerics.
#include "wlx/integration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace wlx {

std::string_view integrator_name(Integrator integrator) noexcept {
  switch (integrator) {
    case Integrator::rk4: return "rk4";
    case Integrator::euler: return "euler";
    case Integrator::dopri5: return "dopri5";
  }
  return "?";
}

std::optional<Integrator> integrator_from_name(std::string_view name) noexcept {
  for (Integrator i : {Integrator::rk4, Integrator::euler, Integrator::dopri5})
    if (integrator_name(i) == name) return i;
  return std::nullopt;
}

void validate_time_grid(double duration, double dt) {
  if (!(std::isfinite(duration) && duration > 0))
    throw Error("duration", fmt::format("must be a positive number of seconds, got {}", duration));
  if (!(std::isfinite(dt) && dt > 0)) throw Error("dt", fmt::format("must be a positive number of seconds, got {}", dt));
  if (duration / dt > 1e8)
    throw Error("dt", fmt::format("{} s over {} s is {:.3g} steps, more than the limit of 1e8", dt, duration, duration / dt));
  if (std::abs(duration / dt - std::round(duration / dt)) > 1e-6 * (duration / dt))
    throw Error("dt", fmt::format("the duration {} s is not a whole number of steps of {} s", duration, dt));
}

namespace integration {
namespace {

using Eigen::VectorXd;

// The Dormand-Prince 5(4) pair (Hairer, Norsett, Wanner, Solving ODEs I, table 5.2): the nodes c_i,
// the stages, the 5th-order weights (= the last stage row: first same as last) and the difference
// to the embedded 4th-order weights, which estimates the local error.
namespace dopri {
constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176, a65 = -5103.0 / 18656;
constexpr double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784, b6 = 11.0 / 84;
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200, e6 = 22.0 / 525,
                 e7 = -1.0 / 40;
}  // namespace dopri

// The stages of one run, allocated once: every step reuses them.
struct Stages {
  explicit Stages(Eigen::Index n) : k1(n), k2(n), k3(n), k4(n), k5(n), k6(n), k7(n), arg(n), next(n), error(n) {}
  VectorXd k1, k2, k3, k4, k5, k6, k7, arg, next, error;
};

// Advances x from t to t + span with Dormand-Prince steps under error control. `h` carries the step
// size from one call to the next; s.k1 = f(t, x) on entry.
void dopri5_span(const Rates& f, VectorXd& x, Stages& s, double t, double span, double tolerance, double& h, Outcome& out) {
  using namespace dopri;
  const double end = t + span;
  double now = t;
  int rejected_in_a_row = 0;
  while (now < end) {
    const bool last = h >= (end - now) * (1 - 1e-12);  // finish the span rather than leave a sliver
    const double step = last ? end - now : h;
    double scaled = 0;
    std::string failure;  // a stage that left the workspace (unreachable pose, singular J_beta)
    ErrorKind failure_kind = ErrorKind::other;
    try {
      s.arg = x + step * a21 * s.k1;
      f(now + c2 * step, s.arg, s.k2);
      s.arg = x + step * (a31 * s.k1 + a32 * s.k2);
      f(now + c3 * step, s.arg, s.k3);
      s.arg = x + step * (a41 * s.k1 + a42 * s.k2 + a43 * s.k3);
      f(now + c4 * step, s.arg, s.k4);
      s.arg = x + step * (a51 * s.k1 + a52 * s.k2 + a53 * s.k3 + a54 * s.k4);
      f(now + c5 * step, s.arg, s.k5);
      s.arg = x + step * (a61 * s.k1 + a62 * s.k2 + a63 * s.k3 + a64 * s.k4 + a65 * s.k5);
      f(now + step, s.arg, s.k6);
      s.next = x + step * (b1 * s.k1 + b3 * s.k3 + b4 * s.k4 + b5 * s.k5 + b6 * s.k6);
      f(now + step, s.next, s.k7);
      s.error = step * (e1 * s.k1 + e3 * s.k3 + e4 * s.k4 + e5 * s.k5 + e6 * s.k6 + e7 * s.k7);
      scaled = (s.error.array().abs() / (tolerance * (1 + x.array().abs().max(s.next.array().abs())))).maxCoeff();
      if (!std::isfinite(scaled)) {  // an overflow, not an error estimate: shrink, and say so if it persists
        failure = "a stage of the step became non-finite (inf or NaN)";
        scaled = 1e10;
      }
    } catch (const Error& e) {
      // The stages reach ahead of the step (up to 3.7 step lengths with these coefficients), so
      // a long step can probe poses the motion itself never reaches: reject and shrink. A real
      // failure shrinks the step to nothing and is reported below.
      failure = e.what();
      failure_kind = e.kind();
      scaled = 1e10;
    }
    // The usual controller: the error scales as step^5; a safety factor and bounded changes.
    const double factor = std::clamp(0.9 * std::pow(std::max(scaled, 1e-10), -0.2), 0.2, 5.0);
    if (scaled <= 1) {
      x = s.next;
      s.k1 = s.k7;  // first same as last
      now = last ? end : now + step;
      ++out.steps;
      rejected_in_a_row = 0;
      if (!last || factor < 1) h = step * factor;  // a step clipped to the sample time says little
    } else {
      ++out.rejected_steps;
      h = step * std::min(factor, 0.5);
      if (++rejected_in_a_row > 60 || h < 1e-14 * std::max(1.0, std::abs(end))) {
        if (!failure.empty())
          throw Error("", fmt::format("at t = {:.6f} s (adaptive step {:.3g} s): {}", now, step, failure), failure_kind);
        throw Error("tolerance", fmt::format("the adaptive step fell to {:.3g} s at t = {:.6f} s without meeting the "
                                             "tolerance {:.3g}: the motion is not smooth here (a singular J_beta or a "
                                             "limb at its reach); use rk4 with a small dt or loosen the tolerance",
                                             h, now, tolerance));
      }
    }
  }
}

}  // namespace

Outcome integrate(const Rates& f, VectorXd x, const Grid& grid, const std::function<void(long k, double t)>& sample,
                  const std::function<std::string(int i)>& name, const std::function<std::string()>& drivers) {
  Outcome out;
  Stages s(x.size());
  const long n = grid.samples;
  const double dt = grid.dt;
  double h = dt;  // dopri5's step, adapted as it goes
  for (long k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    try {
      f(t, x, s.k1);
      sample(k, t);
      if (k + 1 == n) break;
      if (grid.integrator == Integrator::euler) {
        x += dt * s.k1;
        ++out.steps;
      } else if (grid.integrator == Integrator::rk4) {
        s.arg = x + 0.5 * dt * s.k1;
        f(t + 0.5 * dt, s.arg, s.k2);
        s.arg = x + 0.5 * dt * s.k2;
        f(t + 0.5 * dt, s.arg, s.k3);
        s.arg = x + dt * s.k3;
        f(t + dt, s.arg, s.k4);
        x += dt / 6 * (s.k1 + 2 * s.k2 + 2 * s.k3 + s.k4);
        ++out.steps;
      } else {
        dopri5_span(f, x, s, t, dt, grid.tolerance, h, out);
      }
      // Checked after every step: an overflow is reported in the step that made it.
      for (Eigen::Index i = 0; i < x.size(); ++i)
        if (!std::isfinite(x(i)))
          throw Error(name(static_cast<int>(i)), fmt::format("became non-finite ({}) in the step to t = {:.6f} s; {}", x(i),
                                                             static_cast<double>(k + 1) * dt, drivers()));
    } catch (const Error& e) {
      out.complete = false;
      out.error = fmt::format("stopped at t = {:.4f} s (step {} of {}): {}", t, k, n - 1, e.what());
      out.stop_time = t;
      out.stop_reason = e.what();
      out.stop_kind = e.kind();
      break;
    }
  }
  return out;
}

}  // namespace integration
}  // namespace wlx
