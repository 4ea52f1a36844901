// The wlx command line: every subcommand and option, defined in one place for main.cpp and for
// the fuzz target of the command-line parser (tests/fuzz/fuzz_command_line.cpp).
#pragma once

#include "commands.hpp"

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace wlx::cli {

// `wlx sweep`: a parameter sweep, run by the Python package on Dask (python3 -m wlx sweep ...).
struct SweepOptions {
  std::string spec;
  std::string out, scheduler;  // empty: the spec's folder, a local cluster
  std::optional<long> workers, batch_size;
};

// What a parsed command line asks for: the option values, and the subcommands (parsed() tells
// which was given).
struct Invocation {
  std::string model_name;
  std::string model_file;  // --model-file: a model file of the user's (cli/shell/model_plugin.hpp)
  std::string scenarios_dir;  // --scenarios: a folder of runs replacing the model's (cli/shell/scenario_folder.hpp)
  ModelOptions model_options;
  CLI::App* list_models = nullptr;
  CLI::App* fk = nullptr;
  bool fk_json = false;
  CLI::App* ik = nullptr;
  bool batch = false;
  CLI::App* verify_ik = nullptr;
  std::string ik_out = "out/verify-ik";
  std::vector<std::string> sweep_ids;
  CLI::App* verify_nh = nullptr;
  std::string nh_out = "out/verify-nonholonomic";
  CLI::App* simulate = nullptr;
  SimulateOptions sim;
  CLI::App* report = nullptr;
  ReportOptions report_options;
  CLI::App* viewer = nullptr;
  ViewerOptions viewer_options;
  CLI::App* export_mjcf = nullptr;
  std::string export_out;  // empty: out/mjcf/<model>.xml
  CLI::App* sweep = nullptr;
  SweepOptions sweep_options;
};

// Adds wlx's subcommands and options to `app` (model_names: the built-in models, the default
// first); then parse with parse_command_line (command_line.hpp).
void define_command_line(CLI::App& app, Invocation& inv, const std::vector<std::string>& model_names,
                         const std::string& version);

}  // namespace wlx::cli
