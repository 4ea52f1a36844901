// wlx: the command-line tool over the runtime. This file knows no model: it parses the command
// line and runs the chosen built-in model's command (commands.hpp, models()).
#include "bounded_input.hpp"
#include "app.hpp"
#include "command_line.hpp"
#include "commands.hpp"
#include "interrupt.hpp"
#include "mjcf_export.hpp"
#include "model_plugin.hpp"
#include "output_checks.hpp"
#include "scenario_folder.hpp"
#include "viewer_export.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <wlx/support/diagnostics.hpp>
#include <wlx/support/atomic_file.hpp>
#include <wlx/error.hpp>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

// `wlx sweep`: the sweep engine is the Python package's (python/wlx/_sweep.py, on Dask). This
// process becomes `python3 -m wlx sweep ...` (exec, no shell): its exit code and its signals are
// the sweep's. The package is the build tree's, or the one installed beside this bin/.
int run_sweep(const wlx::cli::SweepOptions& o, bool model_options_given) {
  namespace fs = std::filesystem;
  if (model_options_given)
    throw wlx::Error("sweep", "the model and its runs are the spec's (model, runs): --model, --model-file, --scenarios and --params do not apply");
  if (o.spec.empty()) throw wlx::Error("SPEC", "missing: give the sweep's spec file (YAML)");
#ifdef WLX_PYTHON_EXECUTABLE
  // An installed wlx's own package first (<prefix>/bin/wlx: <prefix>/lib/python3/dist-packages),
  // so that it never runs a build tree's that is still there; else the build tree's.
  std::error_code ec;
  fs::path package;
  if (const fs::path executable = fs::read_symlink("/proc/self/exe", ec); !ec)
    package = (executable.parent_path() / WLX_PYTHON_FROM_BINDIR).lexically_normal();
  if (package.empty() || !fs::is_regular_file(package / "wlx" / "_sweep.py", ec)) package = WLX_PYTHON_BUILD_DIR;
  if (!fs::is_regular_file(package / "wlx" / "_sweep.py", ec))
    throw wlx::Error("sweep", "the Python package wlx was not found (" + package.string() + "): build it (pybind11-dev)");
  const char* old_path = std::getenv("PYTHONPATH");
  const std::string python_path = package.string() + (old_path != nullptr && *old_path != '\0' ? ":" + std::string(old_path) : "");
  setenv("PYTHONPATH", python_path.c_str(), 1);
  std::vector<std::string> args{WLX_PYTHON_EXECUTABLE, "-m", "wlx", "sweep", o.spec};
  if (!o.out.empty()) args.insert(args.end(), {"--out", o.out});
  if (!o.scheduler.empty()) args.insert(args.end(), {"--scheduler", o.scheduler});
  if (o.workers) args.insert(args.end(), {"--workers", std::to_string(*o.workers)});
  if (o.batch_size) args.insert(args.end(), {"--batch-size", std::to_string(*o.batch_size)});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  execv(argv[0], argv.data());
  throw wlx::Error("sweep", std::string("cannot run ") + WLX_PYTHON_EXECUTABLE + ": " + std::strerror(errno));
#else
  throw wlx::Error("sweep", "wlx was built without its Python package (pybind11-dev), which runs sweeps");
#endif
}

// `wlx export mjcf`: the model's MJCF, written atomically (cli/shell/mjcf_export.hpp).
int run_export_mjcf(const std::string& description, std::string out, const wlx::cli::ModelOptions& options, const std::string& scenarios) {
  if (!options.params_file.empty())
    throw wlx::Error("--params", "the export writes the model at its description's parameter values: change them in the model file");
  if (!scenarios.empty()) throw wlx::Error("--scenarios", "the export writes the model, not its runs");
  if (description.empty()) throw wlx::Error("export", "this model has no description to export (rebuild wlx)");
  const wlx::cli::MjcfExport mjcf = wlx::cli::mjcf_of_description(description);
  if (out.empty()) out = "out/mjcf/" + mjcf.model + ".xml";
  std::error_code ec;
  const std::filesystem::path parent = std::filesystem::path(out).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  wlx::write_file_atomically(out, mjcf.xml);
  if (!mjcf.placeholders.empty()) wlx::diagnose("wlx: export mjcf: {}", mjcf.placeholders);
  wlx::diagnose("wlx: wrote {}\n", out);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace wlx::cli;
  CLI::App app{"wlx: kinematics and dynamics of wheeled-legged machines, from generated closed-form code"};
  std::vector<std::string> names;
  for (const auto& m : models()) names.emplace_back(m.name);
  Invocation inv;
  define_command_line(app, inv, names, WLX_VERSION);
  auto& [model_name, model_file, scenarios_dir, model_options, list_models, fk, fk_json, ik, batch, verify_ik, ik_out, sweep_ids, verify_nh, nh_out,
         simulate, sim, report, report_options, viewer, viewer_options, export_mjcf, export_out, sweep, sweep_options] = inv;
  std::string model_names;
  for (const auto& n : names) model_names += (model_names.empty() ? "" : ", ") + n;
  install_interrupt_handlers();
  if (const auto code = parse_command_line(app, argc, argv)) return finish(*code);
  report_options.version = WLX_VERSION;
  for (int k = 0; k < argc; ++k) {
    const std::string arg = argv[k];
    const bool plain = !arg.empty() && arg.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789+-_./=:,") == std::string::npos;
    report_options.command_line += (k ? " " : "") + (plain ? arg : "'" + arg + "'");
  }
  try {
    if (sweep->parsed()) return run_sweep(sweep_options, !model_file.empty() || !scenarios_dir.empty() || !model_options.params_file.empty() ||
                                                            model_name != names.front());
    const ModelCommands* model = nullptr;
    std::vector<std::string> names;
    for (const auto& m : models()) {
      names.emplace_back(m.name);
      if (m.name == model_name) model = &m;
    }
    // The folder first: a mistake in it is said before a model file's first compile.
    if (!scenarios_dir.empty() && !list_models->parsed()) load_scenario_folder(scenarios_dir);
    if (!model_file.empty()) {
      if (model_name != names.front())
        throw wlx::Error("--model-file", "give --model (a built-in model) or --model-file (your own), not both");
      // An export reads the model as data: its description, and no compile.
      if (export_mjcf->parsed()) return finish(run_export_mjcf(describe_model_file(model_file), export_out, model_options, scenarios_dir));
      if (!list_models->parsed()) model = &load_model_file(model_file, WLX_VERSION);
    }
    if (model == nullptr) {
      const std::string hint = nearest(model_name, names);
      throw wlx::Error("--model", fmt::format("no built-in model '{}'{}; the models are {}", excerpt(model_name),
                                              hint.empty() ? "" : " (did you mean '" + hint + "'?)", model_names));
    }
    if (list_models->parsed()) {
      std::size_t width = 0;
      for (const auto& m : models()) width = std::max(width, std::string_view(m.name).size());
      for (const auto& m : models()) fmt::print("{:<{}}  {}\n", m.name, width, m.description);
      return finish(0);
    }
    const auto require = [&](auto function, const char* command) {
      if (function == nullptr)
        throw wlx::Error(command, fmt::format("not available for model '{}' yet", model->name));
      return function;
    };
    if (export_mjcf->parsed()) return finish(run_export_mjcf(model->description_json, export_out, model_options, scenarios_dir));
    if (fk->parsed()) return finish(model->fk(model_options, fk_json));
    if (ik->parsed()) return finish(model->ik(model_options, batch));
    if (verify_ik->parsed()) return finish(model->verify_ik(model_options, ik_out, sweep_ids));
    if (verify_nh->parsed()) return finish(model->verify_nonholonomic(model_options, nh_out));
    // A model file's viewer module is its own (a built-in module of the same name would draw
    // another machine): built when a viewer is written (`viewer`, `report`), on first use; the
    // report stands without it, the viewer does not.
    if (!model_file.empty()) use_viewer_module(std::string(model->name), &model_file_viewer_module);
    if (viewer->parsed()) return finish(require(model->viewer, "viewer")(model_options, viewer_options));
    if (report->parsed()) return finish(require(model->report, "report")(model_options, report_options));
    if (simulate->parsed()) {
      if (!sim.list && sim.scenario.empty()) throw wlx::Error("SCENARIO", "missing: give a scenario file or id (--list shows the ids)");
      return finish(model->simulate(model_options, sim));
    }
  } catch (const Interrupted& e) {
    finish(0);
    wlx::diagnose("wlx: {}: stopped before the end; the files finished before are complete, none was left cut\n",
               e.what());
    return e.exit_code();
  } catch (const wlx::OutputError& e) {
    wlx::diagnose("wlx: error: {}\n", e.what());
    return kExitOutputError;
  } catch (const PluginBuildError& e) {  // a correct model file that did not compile
    wlx::diagnose("wlx: error: {}\n", e.what());
    return 1;
  } catch (const wlx::Error& e) {
    wlx::diagnose("wlx: error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    // Library messages (std::filesystem's) quote whole arguments: bound them like wlx's own.
    const std::string message = e.what();
    wlx::diagnose("wlx: error: {}\n", message.size() > 500 ? message.substr(0, 500) + "..." : message);
    return 2;
  }
  return 0;
}
