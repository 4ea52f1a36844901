// The CLI's subcommands: their options (model-independent) and the table of one model's command
// functions. Each built-in model compiles its own functions (cli/commands/model_commands.hpp); main.cpp
// finds them by name in models() (the registry CMake writes from the list of built-in models).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace wlx::cli {

struct ModelApi;  // model_api.hpp

struct SimulateOptions {
  std::string scenario;
  std::string out_dir = "out/simulate";
  std::string integrator;    // empty: the scenario's
  std::optional<double> dt;  // empty: the scenario's
  std::optional<double> tolerance;  // dopri5 only; empty: the scenario's
  std::string weighting;     // "1" or "2" overrides the scenario's (and makes it a dynamics run)
  bool list = false;
};

struct ReportOptions {
  std::string out_dir = "report";
  bool quick = false;        // a reduced set of runs (for tests)
  std::string claims_file;   // a report file to use instead of the model's embedded one
  std::string command_line;  // as invoked, and wlx's version: recorded in the report
  std::string version;
};

struct ViewerOptions {
  std::string out_dir = "out/viewer";
  std::vector<std::string> runs;  // scenario files or ids, simulated and written as runs/<id>.js
};

// Options every command takes.
struct ModelOptions {
  std::string params_file;  // JSON {"name": value, ...} overriding the model's parameters; empty: defaults
};

// One model's commands. A null function: the model has no such command (yet).
struct ModelCommands {
  std::string_view name;
  std::string_view description;
  int (*fk)(const ModelOptions& model, bool as_json);
  int (*ik)(const ModelOptions& model, bool batch);
  int (*verify_ik)(const ModelOptions& model, const std::string& out_dir, const std::vector<std::string>& sweep_ids);
  int (*verify_nonholonomic)(const ModelOptions& model, const std::string& out_dir);
  int (*simulate)(const ModelOptions& model, const SimulateOptions& options);
  int (*report)(const ModelOptions& model, const ReportOptions& options);
  int (*viewer)(const ModelOptions& model, const ViewerOptions& options);
  const ModelApi* api;  // its computations for a binding that names no model (Python)
  // Its description (model.json's text), embedded by CMake for a model built into wlx; empty for a
  // model file's plugin, whose description wlx-gen gives at each load.
  const char* description_json;
};

// The built-in models, the default first.
const std::vector<ModelCommands>& models();

}  // namespace wlx::cli
