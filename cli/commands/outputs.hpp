// The CSV files the CLI writes (their column names are a public interface).
#pragma once

#include "per_model.hpp"
#include <wlx/ik_verification.hpp>
#include <wlx/simulation.hpp>

#include <string>
#include <vector>

WLX_COMMANDS_BEGIN

// One row per sweep point: the swept input, the 14 dependents, contacts, check errors, Newton.
void write_ik_sweep_csv(const std::string& path, const IkSweepResult& result);

// t, the coordinates, per wheel x_/y_<contact> (x_Wl, y_Wl, ...), nh_residual_<wheel>, spin_rate_<wheel>,
// the input rates (<name>_dot), cond_J_beta, clearance (only for a model with a clearance box:
// gen::kHasClearance), the contact velocities vx_/vy_/vz_<contact>, and for
// dynamics runs tau_<joint> and Qstar_<speed>, and for runs driven by torques the commanded speeds'
// accelerations <name>_ddot, the kinetic and potential energy (J) and the actuators' power (W); for
// dynamics runs of a model with contacts, per contact (gen::kContacts' names) the ground's force
// f_x_/f_y_ (K0), f_n_ (normal), f_t_ (tangential), for a wheel f_lat_/f_long_, for a contact with
// level rows moment_ (|moment|), for a supporting one friction_margin_ (mu f_n - f_t, N), then the
// CoM com_x/y/z, the zero-moment point zmp_x/y, margin_static and margin_zmp (m, positive inside
// the support polygon), margin_tip (the force-angle margin, rad) and momentum_residual.
std::vector<std::string> trajectory_header(const Scenario& scenario);
std::vector<double> trajectory_row(const Sample& sample, const Scenario& scenario);
void write_trajectory(const std::string& path, const Trajectory& trajectory, const Scenario& scenario);

// The energy balance of a run driven by torques, sample by sample: the kinetic + potential
// energy against the actuators' work since the first sample (the trapezoid rule on the samples'
// power, error ~dt^2 per unit time). residual() is E - E(first sample) - W, 0 for exact motion.
struct EnergyBalance {
  long samples = 0;
  double first = 0, last = 0, work = 0;
  void add(const Sample& smp) {
    const double energy = smp.kinetic + smp.potential;
    if (samples++ == 0) first = energy;
    else work += 0.5 * (smp.t - last_t_) * (smp.power + last_power_);
    last = energy;
    last_t_ = smp.t;
    last_power_ = smp.power;
  }
  double residual() const { return last - first - work; }

 private:
  double last_t_ = 0, last_power_ = 0;
};

// `wlx simulate`'s run: samples streamed to <out_dir>/trajectory.csv as they are computed
// (constant memory), the file put in place when the run ends, also when it stops early or is
// interrupted (then marked partial by the message and the exit code). Returns the exit code.
int stream_simulation(const Scenario& scenario, const std::string& label, const std::string& out_dir);

WLX_COMMANDS_END
