// One model's command functions (compiled per model: cli/commands/per_model.hpp).
#pragma once

#include "commands.hpp"
#include "per_model.hpp"

#include <wlx/model.hpp>
#include <wlx/simulation.hpp>

#include <filesystem>
#include <string>

WLX_COMMANDS_BEGIN

// The model's parameters: defaults, overridden by the JSON file (an error names the file, the key
// and the reason).
Params load_params(const ModelOptions& model);

int run_fk(const ModelOptions& model, bool as_json);
int run_ik(const ModelOptions& model, bool batch);
int run_verify_ik(const ModelOptions& model, const std::string& out_dir, const std::vector<std::string>& sweep_ids);
int run_verify_nonholonomic(const ModelOptions& model, const std::string& out_dir);
int run_simulate(const ModelOptions& model, const SimulateOptions& options);
int run_report(const ModelOptions& model, const ReportOptions& options);
int run_viewer(const ModelOptions& model, const ViewerOptions& options);

// The text of a trajectory CSV (`wlx simulate`'s columns), for write_viewer_run (viewer_export.hpp).
std::string trajectory_csv_text(const Trajectory& trajectory, const Scenario& scenario);
// Writes DIR/runs/<scenario.id>.js for the viewer: the run's coordinates and, beside them, its
// dependent pair's rates (or, for an inverse-dynamics run, its joint torques). Throws wlx::Error
// for a scenario with parameters other than the model's defaults (the viewer draws those).
// `id` and `description` replace the scenario's when given (the report runs one scenario twice,
// once per weighting, as <id>-w1 and <id>-w2).
void write_viewer_run(const std::filesystem::path& dir, const Scenario& scenario, const Trajectory& trajectory,
                      const std::string& id = {}, const std::string& description = {});

// This model's entry in the registry.
const ModelCommands& entry();
// Its computations for a binding that names no model (model_api.cpp).
const ModelApi& api();

WLX_COMMANDS_END
