// Forward dynamics: the machine moved by its actuators (the converse of wlx/dynamics.hpp's inverse
// dynamics, on the same commanded speeds u, actuated joints and dependent pair), and runs driven
// by torques.
#pragma once

#include "wlx/dynamics.hpp"

#include <functional>
#include <vector>

WLX_MODEL_NAMESPACE_BEGIN

// Forward dynamics: the accelerations u' of the commanded speeds under the actuator torques tau
// (in kActuatedJoints' order), from M u' = J_beta^T tau - b + Q_gravity, the other inputs held
// (as in inverse_dynamics), the closure and the rolling rows kept (s'' = T u' + s''_bias in
// out.sddot). One evaluation of the equations of motion (equations_of_motion: composite rigid bodies) and a
// Cholesky factorisation of M; out.Qstar is J_beta^T tau. Throws wlx::Error if M is not positive definite (a model whose bodies do not move
// with some commanded speed) or for a model without a dynamics section.
void forward_dynamics(const Model& model, Data& data, const Coordinates& s, const CommandVector& u, const TorqueVector& tau,
                      CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options = {});

// The actuator torques of a run at time t in the state (s, u): a table over time, a controller.
// A run driven by torques is a Scenario with its `torques` set (wlx/simulation.hpp).
using TorqueSource = std::function<TorqueVector(double t, const Coordinates& s, const CommandVector& u)>;

// A torque table: the torques at the given times (strictly increasing, finite). Between them,
// linear interpolation (what a table of set points means: a step between two rows is a ramp), or
// cubic: the cubic through the four nearest rows (two on each side; at an end, the four nearest),
// error ~h^4 |tau''''| / 24 for rows h apart against h^2 |tau''| / 8 for linear, so that a smooth
// table sampled at 1 ms (an inverse-dynamics run's torques) is reproduced between its rows to
// ~1e-12 of its scale. Throws wlx::Error (field "torques") for a table that is empty, out of order
// or not finite, and when asked for a time outside it.
class TorqueTable {
 public:
  enum class Interpolation { linear, cubic };
  TorqueTable(std::vector<double> times, std::vector<TorqueVector> torques, Interpolation interpolation = Interpolation::linear);
  TorqueVector operator()(double t, const Coordinates& s, const CommandVector& u) const;
  TorqueVector at(double t) const;
  double start() const { return times_.front(); }
  double end() const { return times_.back(); }

 private:
  std::vector<double> times_;
  std::vector<TorqueVector> torques_;
  Interpolation interpolation_;
};

WLX_MODEL_NAMESPACE_END
