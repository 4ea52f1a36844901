// Forward dynamics: the machine moved by its actuators (the converse of wlx/dynamics.hpp's inverse
// dynamics, on the same commanded speeds u, actuated joints and dependent pair), and runs driven
// by torques.
#pragma once

#include "wlx/dynamics.hpp"
#include "wlx/ik.hpp"

#include <functional>
#include <string>
#include <vector>

WLX_MODEL_NAMESPACE_BEGIN

// Forward dynamics: the accelerations u' of the commanded speeds under the actuator torques tau
// (in kActuatedJoints' order), from M u' = J_beta^T tau - b + Q_gravity, the other inputs held
// (as in inverse_dynamics), the closure and the rolling rows kept (s'' = T u' + s''_bias in
// out.sddot). One evaluation of the equations of motion (equations_of_motion: Kane's sums) and a
// Cholesky factorisation of M; out.Qstar is J_beta^T tau. Throws wlx::Error if M is not positive definite (a model whose bodies do not move
// with some commanded speed) or for a model without a dynamics section.
void forward_dynamics(const Model& model, Data& data, const Coordinates& s, const CommandVector& u, const TorqueVector& tau,
                      CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options = {});

// The actuator torques of a run at time t in the state (s, u): a table over time, a controller.
using TorqueSource = std::function<TorqueVector(double t, const Coordinates& s, const CommandVector& u)>;

// A torque table: the torques at the given times (strictly increasing, finite), linear in between.
// Throws wlx::Error (field "torques") for a table that is empty, out of order or not finite, and
// when asked for a time outside it.
class TorqueTable {
 public:
  TorqueTable(std::vector<double> times, std::vector<TorqueVector> torques);
  TorqueVector operator()(double t, const Coordinates& s, const CommandVector& u) const;
  TorqueVector at(double t) const;

 private:
  std::vector<double> times_;
  std::vector<TorqueVector> torques_;
};

// A run driven by torques. The state is the inputs q and the commanded speeds u: each evaluation
// solves the dependent joints by the closed-form IK (the closure cannot drift), the dependent
// rates (the rolling rows hold exactly, at velocity level) and u' by forward_dynamics; the inputs
// that are neither commanded nor in the dynamics pair keep their start values. RK4 with step dt.
struct TorqueRun {
  Coordinates initial = nominal_inputs();        // inputs; the dependents are solved
  CommandVector speeds = CommandVector::Zero();  // u at t = 0
  double duration = 0;                           // s
  double dt = 1e-3;                              // s
  Branches branches;
  NonholonomicOptions nonholonomic;
  TorqueSource torques;
  // Throws wlx::Error naming the field for a bad duration or step (validate_time_grid), start
  // state or speed, or a missing source.
  void validate() const;
};

struct TorqueSample {
  double t = 0;
  Coordinates s, sdot;
  CommandVector u, u_dot;
  TorqueVector tau;
  double kinetic = 0, potential = 0;  // J
  double power = 0;                   // the actuators' power tau . J_beta u, W
};

struct TorqueTrajectory {
  std::vector<TorqueSample> samples;  // t = 0, dt, ..., duration
  bool complete = true;
  std::string error;  // why the run stopped early (with its time), when !complete
  long evaluations = 0;
};

TorqueTrajectory simulate_torques(const Model& model, const TorqueRun& run);

WLX_MODEL_NAMESPACE_END
