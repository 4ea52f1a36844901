#include "wlx/forward_dynamics.hpp"

#include "wlx/error.hpp"
#include "wlx/simulation.hpp"

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

WLX_MODEL_NAMESPACE_BEGIN

void forward_dynamics(const Model& model, Data& d, const Coordinates& s, const CommandVector& u, const TorqueVector& tau,
                      CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options) {
#if !__has_include(<wlx/gen/reduced_dynamics.hpp>)
  static_cast<void>(model), static_cast<void>(d), static_cast<void>(s), static_cast<void>(u), static_cast<void>(tau);
  static_cast<void>(u_dot), static_cast<void>(out), static_cast<void>(options);
  throw_no_dynamics_section();
#else
  for (int r = 0; r < kActuatedCount; ++r)
    if (!std::isfinite(tau(r)))
      throw Error(fmt::format("tau.{}", kActuatorNames[static_cast<std::size_t>(r)]),
                  fmt::format("must be a finite number, got {}", tau(r)));
  equations_of_motion(model, d, s, u, out, options);  // M, b, Q_gravity, J_beta; s'' at u' = 0
  out.Qstar.noalias() = out.J_beta.transpose() * tau;
  const Eigen::LLT<CommandMatrix> llt(out.M);
  if (llt.info() != Eigen::Success)
    throw Error("M", "the mass matrix on the commanded speeds is not positive definite: some commanded speed moves no body");
  u_dot = llt.solve(out.Qstar - out.b + out.Q_gravity);
  out.sddot.noalias() += out.T * u_dot;
#endif
}

TorqueTable::TorqueTable(std::vector<double> times, std::vector<TorqueVector> torques)
    : times_(std::move(times)), torques_(std::move(torques)) {
  if (times_.empty() || times_.size() != torques_.size())
    throw Error("torques", fmt::format("a table needs one torque vector per time, at least one: got {} times and {} rows",
                                       times_.size(), torques_.size()));
  for (std::size_t k = 0; k < times_.size(); ++k) {
    if (!std::isfinite(times_[k]) || !torques_[k].allFinite())
      throw Error("torques", fmt::format("row {} (t = {}) is not finite", k, times_[k]));
    if (k > 0 && !(times_[k] > times_[k - 1]))
      throw Error("torques", fmt::format("the times must increase: row {} has t = {} after t = {}", k, times_[k], times_[k - 1]));
  }
}

TorqueVector TorqueTable::at(double t) const {
  // A hair of rounding past either end (t accumulated in steps) is the end itself.
  const double slack = 1e-9 * std::max(1.0, std::abs(times_.back()));
  if (!(t >= times_.front() - slack && t <= times_.back() + slack))
    throw Error("torques", fmt::format("t = {} s is outside the table's times [{}, {}] s", t, times_.front(), times_.back()));
  const auto next = std::upper_bound(times_.begin(), times_.end(), t);
  if (next == times_.begin()) return torques_.front();
  if (next == times_.end()) return torques_.back();
  const std::size_t k = static_cast<std::size_t>(next - times_.begin());
  const double w = (t - times_[k - 1]) / (times_[k] - times_[k - 1]);
  return (1 - w) * torques_[k - 1] + w * torques_[k];
}

TorqueVector TorqueTable::operator()(double t, const Coordinates&, const CommandVector&) const { return at(t); }

void TorqueRun::validate() const {
  validate_time_grid(duration, dt);  // the kinematic runs' grid rules (wlx/simulation.hpp)
  if (!speeds.allFinite()) throw Error("speeds", "must be finite");
  if (!initial.allFinite()) throw Error("initial", "must be finite");
  if (!torques) throw Error("torques", "no torque source given");
}

TorqueTrajectory simulate_torques(const Model& model, const TorqueRun& run) {
  run.validate();
  using Inputs = Eigen::Matrix<double, kInputCount, 1>;
  Data d;
  DynamicsTerms terms;
  TorqueTrajectory out;
  Coordinates s = run.initial;
  TorqueVector tau = TorqueVector::Zero();
  // One evaluation: the dependents at q, u' under the source's torques at (t, s, u), q' = (T u)'s inputs.
  const auto rhs = [&](double t, const Inputs& q, const CommandVector& u, Inputs& dq, CommandVector& du) {
    ++out.evaluations;
    s.head<kInputCount>() = q;
    solve_ik_closed_form(model, s, run.branches);
    tau = run.torques(t, s, u);
    forward_dynamics(model, d, s, u, tau, du, terms, run.nonholonomic);
    dq = terms.sdot.head<kInputCount>();
  };
  const long steps = std::lround(run.duration / run.dt);
  out.samples.reserve(static_cast<std::size_t>(steps + 1));
  Inputs q = run.initial.head<kInputCount>();
  CommandVector u = run.speeds;
  double t = 0;
  try {
    for (long k = 0;; ++k) {
      t = static_cast<double>(k) * run.dt;
      Inputs k1q, k2q, k3q, k4q;
      CommandVector k1u, k2u, k3u, k4u;
      rhs(t, q, u, k1q, k1u);  // leaves s, tau and terms at the step's start: the sample
      TorqueSample& smp = out.samples.emplace_back();
      smp.t = t, smp.s = s, smp.sdot = terms.sdot, smp.u = u, smp.u_dot = k1u, smp.tau = tau;
      smp.kinetic = kinetic_energy(model, d, s, terms.sdot);
      smp.potential = potential_energy(model, d, s);
      smp.power = tau.dot(terms.J_beta * u);
      if (k == steps) break;
      rhs(t + 0.5 * run.dt, q + 0.5 * run.dt * k1q, u + 0.5 * run.dt * k1u, k2q, k2u);
      rhs(t + 0.5 * run.dt, q + 0.5 * run.dt * k2q, u + 0.5 * run.dt * k2u, k3q, k3u);
      rhs(t + run.dt, q + run.dt * k3q, u + run.dt * k3u, k4q, k4u);
      q += run.dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
      u += run.dt / 6 * (k1u + 2 * k2u + 2 * k3u + k4u);
      if (!q.allFinite() || !u.allFinite())
        throw Error("", "the state became non-finite (inf or NaN): torques too large for the step, or a singular pose");
    }
  } catch (const Error& e) {
    out.complete = false;
    out.error = fmt::format("stopped at t = {:.6f} s: {}", t, e.what());
  }
  return out;
}

WLX_MODEL_NAMESPACE_END
