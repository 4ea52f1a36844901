// `wlx simulate`'s run, streamed: each sample becomes a CSV row as soon as it is computed, so
// memory does not grow with the number of steps, and the summary is accumulated on the way.
#include "per_model.hpp"
#include "bounded_input.hpp"
#include "interrupt.hpp"
#include "outputs.hpp"
#include "run_summary.hpp"

#include <fmt/format.h>
#include <wlx/support/diagnostics.hpp>
#include <wlx/support/csv.hpp>
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

}  // namespace

int stream_simulation(const Scenario& sc, const std::string& label, const std::string& out_dir) {
  const std::string path = (std::filesystem::path(out_dir) / "trajectory.csv").string();
  CsvWriter csv(path, trajectory_header(sc));
  RunSummary summary;  // over the samples written
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
      summary.add(smp, sc.weighting || sc.driven_by_torques());
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
    fmt::print("max |v_W . n_W| = {:.2e} m/s, max cond(J_beta) = {:.3g}, {}\n", summary.worst_rolling_residual(), summary.worst_cond,
               gen::kHasClearance ? fmt::format("min clearance = {:.4f} m", summary.min_clearance) : std::string("no clearance box"));
    if (sc.weighting) fmt::print("inverse dynamics with {}: largest |tau| = {:.4g} N m\n", sc.weighting->label(), summary.largest_tau());
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
                 summary.largest_tau(), summary.energy.first, summary.energy.last, summary.energy.work,
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
