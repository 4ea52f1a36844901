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
    fmt::print("max |v_W . n_W| = {:.2e} m/s, max cond(J_beta) = {:.3g}, min clearance = {:.4f} m\n",
               summary.worst_residual, summary.worst_cond, summary.min_clearance);
    if (sc.weighting) fmt::print("inverse dynamics with {}: largest |tau| = {:.4g} N m\n", sc.weighting->label(), summary.peak_tau);
    if (sc.driven_by_torques())
      fmt::print("driven by torques: largest |tau| = {:.4g} N m; kinetic + potential energy {:.6g} -> {:.6g} J, the "
                 "actuators' work {:.6g} J (trapezoid on the samples): balance off by {:.2e} J\n",
                 summary.peak_tau, summary.energy.first, summary.energy.last, summary.energy.work,
                 summary.energy.residual());
  }
  fmt::print("wrote {}\n", path);
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
