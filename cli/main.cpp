// wlx: the command-line tool over the runtime.
#include "command_line.hpp"
#include "commands.hpp"
#include "interrupt.hpp"
#include "output_checks.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <wlx/atomic_file.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/model.hpp>

#include <cmath>
#include <iostream>

namespace wlx::cli {

namespace {

// Rounding residue such as -1e-17 would print as "-0.0000" in a table.
double tidy(double v) { return std::abs(v) < 5e-13 ? 0.0 : v; }

}  // namespace

// `wlx fk`: the nominal pose of MODEL.md section 8, dependent joints by closed-form IK, and the
// forward kinematics of every frame of interest.
int run_fk(bool as_json) {
  const Model model;
  Data data;
  Coordinates s = nominal_inputs();
  solve_ik_closed_form(model, s, {});
  forward_kinematics(model, s, data);
  closure(model, s, data, false);
  const double residual = data.Phi.cwiseAbs().maxCoeff();
  if (as_json) {
    nlohmann::ordered_json out;
    for (int k = 0; k < kCoordinateCount; ++k) out["coordinates"][std::string(gen::kCoordinateNames[k])] = s(k);
    for (int f = 0; f < gen::kFrameCount; ++f) {
      auto& fr = out["frames"][std::string(gen::kFrameNames[f])];
      fr["position"] = {data.frame_positions(0, f), data.frame_positions(1, f), data.frame_positions(2, f)};
      const auto& R = data.frame_rotations[f];
      fr["rotation"] = {{R(0, 0), R(0, 1), R(0, 2)}, {R(1, 0), R(1, 1), R(1, 2)}, {R(2, 0), R(2, 1), R(2, 2)}};
    }
    out["closure_residual"] = residual;
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  fmt::print("Nominal pose (MODEL.md section 8), dependent joints by closed-form IK:\n");
  for (int k = kInputCount; k < kCoordinateCount; ++k)
    fmt::print("  {:<9} {:>10.4f} deg\n", gen::kCoordinateNames[k], tidy(s(k)) * 180 / M_PI);
  fmt::print("\nForward kinematics, frame origins in K0 (m):\n  {:<12} {:>9} {:>9} {:>9}\n", "frame", "x", "y", "z");
  for (int f = 0; f < gen::kFrameCount; ++f)
    fmt::print("  {:<12} {:>9.4f} {:>9.4f} {:>9.4f}\n", gen::kFrameNames[f], tidy(data.frame_positions(0, f)),
               tidy(data.frame_positions(1, f)), tidy(data.frame_positions(2, f)));
  fmt::print("\nclosure residual max|Phi| = {:.2e}; total mass {:.2f} kg\n", residual, model.total_mass());
  return 0;
}

}  // namespace wlx::cli

int main(int argc, char** argv) {
  CLI::App app{"wlx: kinematics and dynamics of the walking excavator, from generated closed-form code"};
  wlx::cli::prepare_command_line(app, WLX_VERSION);
  bool fk_json = false;
  auto* fk = app.add_subcommand("fk", "forward kinematics of the nominal pose (MODEL.md section 8)");
  fk->add_flag("--json", fk_json, "print JSON instead of a table");

  bool batch = false;
  auto* ik = app.add_subcommand("ik", "inverse kinematics: one JSON object of inputs on stdin, one JSON object out");
  ik->add_flag("--batch", batch, "NDJSON: one object per line in, one per line out (Newton warm-starts along the lines)");

  auto* verify = app.add_subcommand("verify", "the thesis' verifications");
  verify->require_subcommand(1);
  std::string ik_out = "out/verify-ik";
  std::vector<std::string> sweep_ids;
  auto* verify_ik = verify->add_subcommand("ik", "the 12 IK sweeps of MODEL.md section 8, closed form and Newton");
  verify_ik->add_option("--out", ik_out, "folder for one CSV per sweep")->capture_default_str();
  verify_ik->add_option("--sweep", sweep_ids, "only these sweeps (IK-L1, ..., IK-WR2)");

  std::string nh_out = "out/verify-nonholonomic";
  auto* verify_nh = verify->add_subcommand("nonholonomic", "NH-1 to NH-4: the wheels' sideways-velocity residual");
  verify_nh->add_option("--out", nh_out, "folder for one trajectory CSV per run")->capture_default_str();

  wlx::cli::SimulateOptions sim;
  auto* simulate = app.add_subcommand("simulate", "integrate a scenario (a file, or an id of MODEL.md section 8)");
  simulate->add_option("SCENARIO", sim.scenario, "scenario file or id (NH-1, ST-A1+, ...)");
  simulate->add_option("--out", sim.out_dir, "output folder for trajectory.csv")->capture_default_str();
  simulate->add_option("--integrator", sim.integrator,
                       "rk4, euler or dopri5 (adaptive Dormand-Prince 5(4)); default: the scenario's");
  simulate->add_option("--dt", sim.dt, "step in seconds, or with dopri5 the output interval (default: the scenario's)");
  simulate->add_option("--tolerance", sim.tolerance, "dopri5's local error bound per step, relative to 1 + |q| (default 1e-10)");
  simulate->add_option("--weighting", sim.weighting, "torque weighting 1 or 2 (inverse dynamics, MODEL.md section 7)");
  simulate->add_flag("--list", sim.list, "list the built-in scenarios");

  wlx::cli::ReportOptions report_options;
  auto* report = app.add_subcommand("report", "run everything of MODEL.md section 8 and write an HTML report with figures");
  report->add_option("--out", report_options.out_dir, "output folder (index.html, fig/, data/, plots/)")->capture_default_str();
  report->add_flag("--quick", report_options.quick, "a reduced set of runs, for a fast look");

  using namespace wlx::cli;
  install_interrupt_handlers();
  if (const auto code = parse_command_line(app, argc, argv)) return finish(*code);
  try {
    if (fk->parsed()) return finish(run_fk(fk_json));
    if (ik->parsed()) return finish(run_ik(batch));
    if (verify_ik->parsed()) return finish(run_verify_ik(ik_out, sweep_ids));
    if (verify_nh->parsed()) return finish(run_verify_nonholonomic(nh_out));
    if (report->parsed()) return finish(run_report(report_options));
    if (simulate->parsed()) {
      if (!sim.list && sim.scenario.empty()) throw wlx::Error("SCENARIO", "missing: give a scenario file or id (--list shows the ids)");
      return finish(run_simulate(sim));
    }
  } catch (const Interrupted& e) {
    finish(0);
    fmt::print(stderr, "wlx: {}: stopped before the end; the files finished before are complete, none was left cut\n",
               e.what());
    return e.exit_code();
  } catch (const wlx::OutputError& e) {
    fmt::print(stderr, "wlx: error: {}\n", e.what());
    return kExitOutputError;
  } catch (const wlx::Error& e) {
    fmt::print(stderr, "wlx: error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    // Library messages (std::filesystem's) quote whole arguments: bound them like wlx's own.
    const std::string message = e.what();
    fmt::print(stderr, "wlx: error: {}\n", message.size() > 500 ? message.substr(0, 500) + "..." : message);
    return 2;
  }
  return 0;
}
