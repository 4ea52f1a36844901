// `wlx simulate`'s run, streamed: each sample becomes a CSV row as soon as it is computed, so
// memory does not grow with the number of steps, and the summary is accumulated on the way.
#include "per_model.hpp"
#include "bounded_input.hpp"
#include "interrupt.hpp"
#include "outputs.hpp"

#include <fmt/format.h>
#include <wlx/diagnostics.hpp>
#include <wlx/csv.hpp>
#include <wlx/error.hpp>

#include <algorithm>
#include <exception>
#include <filesystem>
#include <optional>

WLX_COMMANDS_BEGIN

namespace {

// Carries a failure of the output (or an interruption) out of simulate_each, which turns every
// wlx::Error raised inside a step into "the run stopped here": a lost file is not a model limit.
struct StopRun {
  std::exception_ptr cause;
};

// Maxima and minima over the samples written; printed only when at least one sample exists, so a
// run that fails at step 0 prints no initial values such as 1e300 or 0.
struct Summary {
  long samples = 0;
  double last_t = 0;
  double worst_residual = 0, worst_cond = 0, min_clearance = 0, peak_tau = 0;
  EnergyBalance energy;  // runs driven by torques
  // Dynamics runs of a model with contacts: the lowest normal force, friction margin and tip
  // angle with their contact (or edge) and time, the first sample where a contact slips or pulls.
  struct Lowest {
    double value = 0, t = 0;
    int contact = -1, other = -1;
    void add(double v, int c, double time, int d = -1) {
      if (contact < 0 || v < value) value = v, contact = c, other = d, t = time;
    }
  } normal, friction, tip;
  int first_slip = -1, first_pull = -1;
  double slip_t = 0, pull_t = 0, worst_momentum = 0;

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

  void add(const Sample& smp) {
    energy.add(smp);
    const double residual = smp.nh_residual.cwiseAbs().maxCoeff(), tau = smp.tau.cwiseAbs().maxCoeff();
    if (samples == 0) {
      worst_residual = residual, worst_cond = smp.cond_J_beta, min_clearance = smp.clearance, peak_tau = tau;
    } else {
      worst_residual = std::max(worst_residual, residual);
      worst_cond = std::max(worst_cond, smp.cond_J_beta);
      min_clearance = std::min(min_clearance, smp.clearance);
      peak_tau = std::max(peak_tau, tau);
    }
    last_t = smp.t;
    ++samples;
  }
};

}  // namespace

int stream_simulation(const Scenario& sc, const std::string& label, const std::string& out_dir) {
  const std::string path = (std::filesystem::path(out_dir) / "trajectory.csv").string();
  CsvWriter csv(path, trajectory_header(sc));
  Summary summary;
  std::optional<Interrupted> interrupted;
  Trajectory tr;
  try {
    tr = simulate_each(sc, [&](const Sample& smp) {
      try {
        throw_if_interrupted();
        csv.row(trajectory_row(smp, sc));
      } catch (...) {
        throw StopRun{std::current_exception()};
      }
      summary.add(smp);
      if (sc.weighting || sc.driven_by_torques()) summary.add_contacts(smp);
    });
  } catch (const StopRun& stop) {
    try {
      std::rethrow_exception(stop.cause);
    } catch (const Interrupted& e) {
      interrupted = e;
    }  // anything else (an OutputError) propagates: the CsvWriter's destructor removes the temporary
  }
  // The samples computed so far are complete rows: keep them, also after an interruption.
  csv.commit();

  fmt::print("{}: {} samples ({} s, dt {} s, {}), dependent pair {}\n", excerpt(label), summary.samples, sc.duration, sc.dt,
             integrator_name(sc.integrator), sc.pair.label());
  if (!interrupted)
    fmt::print("integration: {} steps{}, {} evaluations of the right-hand side\n", tr.steps,
               sc.integrator == Integrator::dopri5
                   ? fmt::format(" ({} rejected; tolerance {:.1e})", tr.rejected_steps, sc.tolerance)
                   : std::string(),
               tr.evaluations);
  if (summary.samples == 0) {
    fmt::print("no sample was computed\n");
  } else {
    fmt::print("max |v_W . n_W| = {:.2e} m/s, max cond(J_beta) = {:.3g}, {}\n", summary.worst_residual, summary.worst_cond,
               gen::kHasClearance ? fmt::format("min clearance = {:.4f} m", summary.min_clearance) : std::string("no clearance box"));
    if (sc.weighting) fmt::print("inverse dynamics with {}: largest |tau| = {:.4g} N m\n", sc.weighting->label(), summary.peak_tau);
    if ((sc.weighting || sc.driven_by_torques()) && summary.normal.contact >= 0) {
      const auto& st = summary;
      fmt::print("contacts: smallest normal force {:.6g} N ({} at t = {:.4f} s), smallest friction margin {:.6g} N ({} at t = "
                 "{:.4f} s), smallest tip-over margin {:.4g} deg (edge {}-{} at t = {:.4f} s); momentum balance to {:.1e}\n",
                 st.normal.value, contact_name(st.normal.contact), st.normal.t, st.friction.value,
                 contact_name(st.friction.contact), st.friction.t, st.tip.value * 180 / 3.14159265358979323846,
                 st.tip.contact >= 0 ? contact_name(st.tip.contact) : "-", st.tip.other >= 0 ? contact_name(st.tip.other) : "-",
                 st.tip.t, st.worst_momentum);
      if (st.first_slip >= 0)
        fmt::print("contacts: {} slips first, at t = {:.4f} s (its friction margin turns negative)\n",
                   contact_name(st.first_slip), st.slip_t);
      if (st.first_pull >= 0)
        wlx::diagnose("wlx: warning: contact {} pulls on the ground from t = {:.4f} s (the run goes on, as its "
                      "\"on_contact_loss\" asks: the model's contacts hold both ways)\n",
                      contact_name(st.first_pull), st.pull_t);
    }
    if (sc.driven_by_torques())
      fmt::print("driven by torques: largest |tau| = {:.4g} N m; kinetic + potential energy {:.6g} -> {:.6g} J, the "
                 "actuators' work {:.6g} J (trapezoid on the samples): balance off by {:.2e} J\n",
                 summary.peak_tau, summary.energy.first, summary.energy.last, summary.energy.work,
                 summary.energy.residual());
  }
  fmt::print("wrote {}\n", path);
  if (!tr.limit_warning.empty()) wlx::diagnose("wlx: warning: a joint left its limits {} (\"on_limit\": \"continue\")\n", tr.limit_warning);
  if (interrupted) {
    wlx::diagnose("wlx: {} at t = {:.4f} s: the run is partial; {} holds the {} samples computed before\n",
               interrupted->what(), summary.last_t, path, summary.samples);
    return interrupted->exit_code();
  }
  if (!tr.complete) {
    wlx::diagnose("wlx: error: {}; {} wrote the {} samples computed before\n", tr.error, path, summary.samples);
    return 2;
  }
  return 0;
}

WLX_COMMANDS_END
