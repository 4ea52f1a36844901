// The time integrators of every run (simulation.hpp), on a state of any size: compiled once, into
// the library wlx::numerics, not once per model. A model's run hands them its right-hand side (the
// IK, the dependent rates or forward dynamics, at its fixed sizes) and what to do at each sample;
// the stepping, dopri5's error control and the bookkeeping of a stop are here. Each evaluation of
// the right-hand side costs an IK of every limb and a rate or dynamics solve (microseconds), so the
// state's copies between the run's fixed-size vectors and these (a few dozen numbers) are noise.
#pragma once

#include "wlx/error.hpp"

#include <Eigen/Core>

#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace wlx {

// rk4 and euler take fixed steps of dt (the thesis used euler with 0.001 s). dopri5 is the
// Dormand-Prince 5(4) pair with error control: adaptive steps between the output samples, which
// stay dt apart; each step's local error estimate is kept below tolerance * (1 + |q|).
enum class Integrator { rk4, euler, dopri5 };
std::string_view integrator_name(Integrator integrator) noexcept;
// The integrator of that name ("rk4", "euler", "dopri5"), or nothing.
std::optional<Integrator> integrator_from_name(std::string_view name) noexcept;

// Every run's time grid: throws wlx::Error naming "duration" or "dt" unless both are positive and
// finite and the duration is a whole number of at most 1e8 steps of dt.
void validate_time_grid(double duration, double dt);

namespace integration {

// x' = f(t, x): writes the rate into `rate` (already sized as x). Throws wlx::Error where the state
// leaves the model (a pose out of reach, a singular Jacobian): a fixed step stops the run there,
// dopri5 first retries with smaller steps (its stages reach ahead of the motion).
using Rates = std::function<void(double t, const Eigen::VectorXd& x, Eigen::VectorXd& rate)>;

struct Grid {
  long samples = 0;  // t = 0, dt, ..., (samples - 1) dt
  double dt = 0;
  Integrator integrator = Integrator::rk4;
  double tolerance = 1e-10;  // dopri5 only: local error per step, relative to 1 + |x|
};

// How a run ended: complete, or where and why it stopped (the step that failed: its samples end
// before it), and the integration work.
struct Outcome {
  bool complete = true;
  std::string error;  // "stopped at t = ... s (step k of n): <reason>", when !complete
  double stop_time = 0;     // the time of the step that stopped the run, when !complete
  std::string stop_reason;  // the reason alone, when !complete
  ErrorKind stop_kind = ErrorKind::other;  // what kind of failure stopped it (error.hpp)
  long steps = 0, rejected_steps = 0;  // accepted steps; rejected ones (dopri5 only)
};

// At each sample k (t = k dt): f at (t, x) first, so that the run's right-hand side holds the
// sample's state and rates; then `sample(k, t)`, which records it and may throw wlx::Error to stop
// the run; then the step (or dopri5's steps) to the next sample. After each step every entry of x
// must be finite, else the run stops naming `name(i)` of the first that is not and `drivers()` (what
// drives the motion, for the message). A wlx::Error from f or `sample` stops the run as well.
Outcome integrate(const Rates& f, Eigen::VectorXd x, const Grid& grid, const std::function<void(long k, double t)>& sample,
                  const std::function<std::string(int i)>& name, const std::function<std::string()>& drivers);

}  // namespace integration
}  // namespace wlx
