// Time integration of a scenario (thesis 4.2, 5; docs/excavator.md sections 5 and 8): the commanded input
// rates and the dependent pair are integrated; the holonomic dependents are re-solved by the
// closed-form IK at every evaluation, so the loop closure cannot drift. A run is driven by rates
// (kinematic, or inverse dynamics with a weighting) or by torques (forward dynamics).
#pragma once

#include "wlx/contacts.hpp"
#include "wlx/error.hpp"
#include "wlx/dynamics.hpp"
#include "wlx/forward_dynamics.hpp"
#include "wlx/ik.hpp"
#include "wlx/integration.hpp"
#include "wlx/model.hpp"
#include "wlx/nonholonomic.hpp"

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

WLX_MODEL_NAMESPACE_BEGIN

// The integrators (Integrator, integrator_name, validate_time_grid) are model-independent and
// compiled once: wlx/integration.hpp.

struct Scenario {
  std::string id;
  std::string description;
  Params params = settings().params;
  Coordinates initial = nominal_inputs();                 // inputs; dependents are solved
  Eigen::Matrix<double, kInputCount, 1> rates = Eigen::Matrix<double, kInputCount, 1>::Zero();  // commanded
  DependentPair pair = default_pair();
  double duration = 0;  // s
  double dt = 1e-3;     // s
  Integrator integrator = Integrator::rk4;
  double tolerance = 1e-10;  // dopri5 only: local error per step, relative to 1 + |q| (m or rad)
  Branches branches;
  NonholonomicOptions nonholonomic;
  // Set: an inverse-dynamics run: the model's dynamics pair dependent, only the commanded speeds u
  // of its dynamics section given (the scenario's rates, constant: u' = 0), torques distributed
  // with this weighting.
  std::optional<Weighting> weighting;
  // Set: a forward-dynamics run. The state is the inputs and the commanded speeds u (their values
  // at t = 0 in `rates`, which may name only the commanded inputs); u' comes from forward_dynamics
  // under these torques, the dependent pair must be the dynamics section's, the other inputs keep
  // their start values. Every integrator applies (dopri5's error control covers u too). The run
  // also stops when the clearance box reaches the ground: the model has no contact there.
  TorqueSource torques;
  // Dynamics runs: stop where a contact would pull on the ground (a negative normal force) or the
  // machine would tip (the force-angle margin reaches zero), naming the contact or the edge: the
  // model's contacts hold both ways, so what follows such a sample is not the machine's motion.
  // false (the scenario's "on_contact_loss": "continue") reports those samples in the columns and
  // the summary and goes on, as the thesis' bilateral contacts do.
  bool stop_on_contact_loss = true;
  // Stop where a joint leaves its range or exceeds its largest speed (settings().lower, upper,
  // velocity_limit), naming the joint, its value and the time; false (the scenario's "on_limit":
  // "continue") goes on and says in Trajectory::limit_warning where it first happened.
  bool stop_on_limit = true;

  bool driven_by_torques() const { return static_cast<bool>(torques); }
  // The commanded speeds u at t = 0: the commanded inputs' rates.
  CommandVector commanded_speeds() const;
  // Number of output samples: duration / dt steps plus t = 0 (the thesis' "2001 integrations" for 2 s).
  long samples() const;
  // Throws wlx::Error naming the field for a bad duration, step, or a commanded dependent rate, and
  // for a run given both a weighting and torques.
  void validate() const;
};

struct Sample {
  double t = 0;
  Coordinates s;                                           // all coordinates
  Coordinates sdot;                                        // their rates
  Eigen::Matrix<double, 2 * kWheelCount, 1> contacts;      // per wheel x, y of its contact point (x_Wl, y_Wl, ...)
  Eigen::Matrix<double, 3, kWheelCount> contact_velocity;  // v_W in K0, one column per wheel
  WheelVector nh_residual;                                 // v_W . n_W per wheel (should be 0)
  WheelVector spin_rate;                                   // wheel spin rates, rad/s
  double cond_J_beta = 0;
  double clearance = 0;  // the clearance box's lowest corner above z = 0, m (+infinity without a box: gen::kHasClearance)
  // Inverse- and forward-dynamics runs only:
  TorqueVector tau = TorqueVector::Zero();      // actuator torques, order of kActuatedJoints
  CommandVector Qstar = CommandVector::Zero();  // generalized forces on u (J_beta^T tau)
  // Forward-dynamics runs only:
  CommandVector u = CommandVector::Zero(), u_dot = CommandVector::Zero();  // commanded speeds and their rates
  double kinetic = 0, potential = 0;  // J
  double power = 0;                   // the actuators' power tau . J_beta u, W
  // Dynamics runs: the ground's forces at the contacts, the margins (contacts.hpp), and the whole
  // machine's momentum balance with them (relative residual: rounding when the forces are right).
  ContactForces forces = {};
  Stability stability = {};
  double momentum_residual = 0;
};

// The integration's outcome (wlx/integration.hpp: complete, or why and when it stopped, with the
// reason apart for a caller that lists stopped runs in a table, its kind, and the accepted and
// rejected steps), and what the run adds to it.
struct Trajectory : integration::Outcome {
  std::vector<Sample> samples;  // its samples end before the step that stopped it
  std::string limit_warning;  // with stop_on_limit false: where a joint first left its limits, else empty
  long evaluations = 0;  // right-hand-side evaluations (each one an IK of every limb plus a dependent-rate solve)
};

// Called after each sample with (samples done, samples in all).
using Progress = std::function<void(long, long)>;

Trajectory simulate(const Scenario& scenario, const Progress& progress = {});

// The same without storing the samples: each one goes to `on_sample` as it is computed, so a
// run of any length needs constant memory. Returns how the run ended (samples left empty).
Trajectory simulate_each(const Scenario& scenario, const std::function<void(const Sample&)>& on_sample,
                         const Progress& progress = {});

// The height above the ground (z = 0 of K0) of the lowest corner of the model file's clearance box;
// +infinity for a model without one.
double lowest_clearance(const Model& model, const Coordinates& s);

WLX_MODEL_NAMESPACE_END
