// One run's summary, accumulated sample by sample: what `wlx simulate` prints after a run, what
// `wlx verify nonholonomic` checks, what the report's tables show and what a sweep's metrics are
// (through Python's m.simulate). One definition, so that the four agree on what "the largest
// torque" or "the smallest clearance" of a run is.
#pragma once

#include "outputs.hpp"
#include "per_model.hpp"
#include "run_extremes.hpp"

#include <wlx/simulation.hpp>

#include <algorithm>
#include <cmath>

WLX_COMMANDS_BEGIN

// The model-independent extremes (cli/shell/run_extremes.hpp), and per wheel and actuator:
struct RunSummary : cli::RunExtremes {
  WheelVector worst_residual = WheelVector::Zero();  // max |v_W . n_W| per wheel, m/s
  TorqueVector peak_tau = TorqueVector::Zero();      // max |tau| per actuator
  TorqueVector sum_tau_squared = TorqueVector::Zero();
  EnergyBalance energy;  // runs driven by torques

  // `dynamics`: the sample has torques and (for a model with contacts) contact forces.
  void add(const Sample& smp, bool dynamics) {
    energy.add(smp);
    const WheelVector residual = smp.nh_residual.cwiseAbs();
    const TorqueVector tau = smp.tau.cwiseAbs();
    if (samples == 0) {
      worst_residual = residual, worst_cond = smp.cond_J_beta, min_clearance = smp.clearance, peak_tau = tau;
    } else {
      worst_residual = worst_residual.cwiseMax(residual);
      worst_cond = std::max(worst_cond, smp.cond_J_beta);
      min_clearance = std::min(min_clearance, smp.clearance);
      peak_tau = peak_tau.cwiseMax(tau);
    }
    sum_tau_squared += smp.tau.cwiseAbs2();
    last_t = smp.t;
    ++samples;
    if (dynamics) add_contacts(smp);
  }

  // The largest over the wheels (0 for a model without wheels).
  double worst_rolling_residual() const { return kWheelCount > 0 ? worst_residual.maxCoeff() : 0.0; }
  // The largest over the actuators (0 for a model without actuators).
  double largest_tau() const { return kActuatedCount > 0 ? peak_tau.maxCoeff() : 0.0; }
  // The root mean square of actuator k's torque over the samples.
  double rms_tau(int k) const { return samples > 0 ? std::sqrt(sum_tau_squared(k) / static_cast<double>(samples)) : 0.0; }

 private:
  void add_contacts(const Sample& smp) {
    if constexpr (kContactCount > 0) {
      for (int c = 0; c < kContactCount; ++c) {
        if (!gen::kContacts[static_cast<std::size_t>(c)].supports) continue;
        normal.add(smp.forces.normal(c), c, smp.t);
        friction.add(smp.forces.friction_margin(c), c, smp.t);
        if (first_slip < 0 && smp.forces.friction_margin(c) < 0) first_slip = c, slip_t = smp.t;
        if (first_pull < 0 && smp.forces.normal(c) < 0) first_pull = c, pull_t = smp.t;
      }
      tip.add(smp.stability.tip_angle, smp.stability.tip_edge[0], smp.t, smp.stability.tip_edge[1]);
      worst_momentum = std::max(worst_momentum, smp.momentum_residual);
    } else {
      static_cast<void>(smp);
    }
  }
};

// A finished run's summary; `dynamics` as RunSummary::add's.
inline RunSummary summarize(const Trajectory& trajectory, bool dynamics) {
  RunSummary summary;
  for (const Sample& smp : trajectory.samples) summary.add(smp, dynamics);
  return summary;
}

WLX_COMMANDS_END
