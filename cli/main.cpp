// wlx: the command-line tool over the runtime. This file knows no model: it parses the command
// line and runs the chosen built-in model's command (commands.hpp, models()).
#include "bounded_input.hpp"
#include "command_line.hpp"
#include "commands.hpp"
#include "interrupt.hpp"
#include "output_checks.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <wlx/atomic_file.hpp>
#include <wlx/error.hpp>

#include <cmath>
#include <iostream>

int main(int argc, char** argv) {
  using namespace wlx::cli;
  CLI::App app{"wlx: kinematics and dynamics of wheeled-legged machines, from generated closed-form code"};
  wlx::cli::prepare_command_line(app, WLX_VERSION);
  std::string model_name(models().front().name);
  ModelOptions model_options;
  std::string model_names;
  for (const auto& m : models()) model_names += (model_names.empty() ? "" : ", ") + std::string(m.name);
  // --model and --params before the subcommand or after it (each subcommand has them too, so that
  // an unknown option of a subcommand is reported there, with its own did-you-mean).
  const auto add_model_options = [&](CLI::App* a) {
    a->add_option("--model", model_name, "the built-in model (" + model_names + "; wlx models lists them)")
        ->capture_default_str();
    a->add_option("--params", model_options.params_file,
                  "JSON file {\"name\": value, ...} overriding the model's parameters (SI units)");
  };
  add_model_options(&app);
  auto* list_models = app.add_subcommand("models", "list the built-in models");
  bool fk_json = false;
  auto* fk = app.add_subcommand("fk", "forward kinematics of a pose on stdin (JSON; {} for the nominal pose)");
  fk->add_flag("--json", fk_json, "print JSON instead of a table");

  bool batch = false;
  auto* ik = app.add_subcommand("ik", "inverse kinematics: one JSON object of inputs on stdin, one JSON object out");
  ik->add_flag("--batch", batch, "NDJSON: one object per line in, one per line out (Newton warm-starts along the lines)");

  auto* verify = app.add_subcommand("verify", "the thesis' verifications");
  verify->require_subcommand(1);
  std::string ik_out = "out/verify-ik";
  std::vector<std::string> sweep_ids;
  auto* verify_ik = verify->add_subcommand("ik", "the 12 IK sweeps of docs/excavator.md section 8, closed form and Newton");
  verify_ik->add_option("--out", ik_out, "folder for one CSV per sweep")->capture_default_str();
  verify_ik->add_option("--sweep", sweep_ids, "only these sweeps (IK-L1, ..., IK-WR2)");

  std::string nh_out = "out/verify-nonholonomic";
  auto* verify_nh = verify->add_subcommand("nonholonomic", "NH-1 to NH-4: the wheels' sideways-velocity residual");
  verify_nh->add_option("--out", nh_out, "folder for one trajectory CSV per run")->capture_default_str();

  wlx::cli::SimulateOptions sim;
  auto* simulate = app.add_subcommand("simulate", "integrate a scenario (a file, or an id of docs/excavator.md section 8)");
  simulate->add_option("SCENARIO", sim.scenario, "scenario file or id (NH-1, ST-A1+, ...)");
  simulate->add_option("--out", sim.out_dir, "output folder for trajectory.csv")->capture_default_str();
  simulate->add_option("--integrator", sim.integrator,
                       "rk4, euler or dopri5 (adaptive Dormand-Prince 5(4)); default: the scenario's");
  simulate->add_option("--dt", sim.dt, "step in seconds, or with dopri5 the output interval (default: the scenario's)");
  simulate->add_option("--tolerance", sim.tolerance, "dopri5's local error bound per step, relative to 1 + |q| (default 1e-10)");
  simulate->add_option("--weighting", sim.weighting, "torque weighting 1 or 2 (inverse dynamics, docs/excavator.md section 7)");
  simulate->add_flag("--list", sim.list, "list the built-in scenarios");

  wlx::cli::ReportOptions report_options;
  auto* report = app.add_subcommand("report", "run everything of docs/excavator.md section 8 and write an HTML report with figures");
  report->add_option("--out", report_options.out_dir, "output folder (index.html, fig/, data/, plots/)")->capture_default_str();
  report->add_flag("--quick", report_options.quick, "a reduced set of runs, for a fast look");

  for (CLI::App* a : {fk, ik, verify_ik, verify_nh, simulate, report}) add_model_options(a);
  install_interrupt_handlers();
  if (const auto code = parse_command_line(app, argc, argv)) return finish(*code);
  try {
    const ModelCommands* model = nullptr;
    std::vector<std::string> names;
    for (const auto& m : models()) {
      names.emplace_back(m.name);
      if (m.name == model_name) model = &m;
    }
    if (model == nullptr) {
      const std::string hint = nearest(model_name, names);
      throw wlx::Error("--model", fmt::format("no built-in model '{}'{}; the models are {}", excerpt(model_name),
                                              hint.empty() ? "" : " (did you mean '" + hint + "'?)", model_names));
    }
    if (list_models->parsed()) {
      for (const auto& m : models()) fmt::print("{:<12} {}\n", m.name, m.description);
      return finish(0);
    }
    const auto require = [&](auto function, const char* command) {
      if (function == nullptr)
        throw wlx::Error(command, fmt::format("not available for model '{}' yet", model->name));
      return function;
    };
    if (fk->parsed()) return finish(model->fk(model_options, fk_json));
    if (ik->parsed()) return finish(model->ik(model_options, batch));
    if (verify_ik->parsed()) return finish(model->verify_ik(model_options, ik_out, sweep_ids));
    if (verify_nh->parsed()) return finish(model->verify_nonholonomic(model_options, nh_out));
    if (report->parsed()) return finish(require(model->report, "report")(model_options, report_options));
    if (simulate->parsed()) {
      if (!sim.list && sim.scenario.empty()) throw wlx::Error("SCENARIO", "missing: give a scenario file or id (--list shows the ids)");
      return finish(model->simulate(model_options, sim));
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
