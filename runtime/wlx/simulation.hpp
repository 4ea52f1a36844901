// Time integration of a scenario (thesis 4.2, 5; docs/excavator.md sections 5 and 8): the commanded input
// rates and the dependent pair are integrated; the holonomic dependents are re-solved by the
// closed-form IK at every evaluation, so the loop closure cannot drift.
#pragma once

#include "wlx/dynamics.hpp"
#include "wlx/ik.hpp"
#include "wlx/model.hpp"
#include "wlx/nonholonomic.hpp"

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

WLX_MODEL_NAMESPACE_BEGIN

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

struct Scenario {
  std::string id;
  std::string description;
  Params params;
  Coordinates initial = nominal_inputs();                 // inputs; dependents are solved
  Eigen::Matrix<double, kInputCount, 1> rates = Eigen::Matrix<double, kInputCount, 1>::Zero();  // commanded
  DependentPair pair = default_pair();
  double duration = 0;  // s
  double dt = 1e-3;     // s
  Integrator integrator = Integrator::rk4;
  double tolerance = 1e-10;  // dopri5 only: local error per step, relative to 1 + |q| (m or rad)
  Branches branches;
  NonholonomicOptions nonholonomic;
  // Set: an inverse-dynamics run (docs/excavator.md section 7): pair A, only u = [z_C', x_C', roll',
  // pitch'] commanded (constant, so u' = 0), torques distributed with this weighting.
  std::optional<Weighting> weighting;

  // Number of output samples: duration / dt steps plus t = 0 (the thesis' "2001 integrations" for 2 s).
  long samples() const;
  // Throws wlx::Error naming the field for a bad duration, step, or a commanded dependent rate.
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
  double clearance = 0;  // the clearance box's lowest corner above z = 0, m (+infinity without a box)
  // Inverse-dynamics runs only:
  TorqueVector tau = TorqueVector::Zero();      // actuator torques, order of kActuatedJoints
  CommandVector Qstar = CommandVector::Zero();  // generalized forces on u
};

struct Trajectory {
  std::vector<Sample> samples;
  bool complete = true;
  std::string error;  // why the run stopped early (with its time), when !complete
  // Integration work: accepted steps, rejected steps (dopri5 only), right-hand-side evaluations
  // (each one an IK of every limb plus a dependent-rate solve).
  long steps = 0, rejected_steps = 0, evaluations = 0;
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
double lowest_clearance(const Params& p, const Coordinates& s);

WLX_MODEL_NAMESPACE_END
