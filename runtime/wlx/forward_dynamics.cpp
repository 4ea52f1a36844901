#include "wlx/forward_dynamics.hpp"

#include "wlx/error.hpp"
#include "wlx/small_dense.hpp"

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
  // Coefficient-based products (lazyProduct): at these fixed sizes Eigen's general
  // matrix-vector kernel costs more in set-up than in arithmetic.
  out.Qstar.noalias() = out.J_beta.transpose().lazyProduct(tau);
  // M and the forces are checked for finiteness only when the solve's answer is not finite (a NaN
  // anywhere in them reaches it): checked first, M's 100 entries cost the quadruped's step 2%.
  const bool solved = small::cholesky_solve<kCommandedCount>(out.M, out.Qstar - out.b + out.Q_gravity, u_dot);
  if (!solved || !u_dot.allFinite()) {
    if (!out.M.allFinite())
      throw Error("M", "the mass matrix on the commanded speeds is not finite in this state (the pose or the parameters are "
                       "outside the model's domain)");
    if (!solved)
      throw Error("M", "the mass matrix on the commanded speeds is not positive definite: some commanded speed moves no body");
    throw Error("u_dot", "the forces on the commanded speeds (b, Q_gravity) are not finite in this state (the pose, the rates or "
                         "the parameters are outside the model's domain)");
  }
  out.sddot.noalias() += out.T.lazyProduct(u_dot);
#endif
}

TorqueTable::TorqueTable(std::vector<double> times, std::vector<TorqueVector> torques, Interpolation interpolation)
    : times_(std::move(times)), torques_(std::move(torques)), interpolation_(interpolation) {
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
  const std::size_t k = static_cast<std::size_t>(next - times_.begin());  // t in [times_[k-1], times_[k])
  if (interpolation_ == Interpolation::linear || times_.size() < 3) {
    const double w = (t - times_[k - 1]) / (times_[k] - times_[k - 1]);
    return (1 - w) * torques_[k - 1] + w * torques_[k];
  }
  // Lagrange's form on the (up to) four rows nearest the interval: exact for cubics, on any spacing.
  const std::size_t n = std::min<std::size_t>(4, times_.size());
  const std::size_t first = std::min(k >= 2 ? k - 2 : 0, times_.size() - n);
  TorqueVector out = TorqueVector::Zero();
  for (std::size_t i = first; i < first + n; ++i) {
    double weight = 1;
    for (std::size_t j = first; j < first + n; ++j)
      if (j != i) weight *= (t - times_[j]) / (times_[i] - times_[j]);
    out += weight * torques_[i];
  }
  return out;
}

TorqueVector TorqueTable::operator()(double t, const Coordinates&, const CommandVector&) const { return at(t); }

WLX_MODEL_NAMESPACE_END
