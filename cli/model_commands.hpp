// One model's command functions (compiled per model: cli/per_model.hpp).
#pragma once

#include "commands.hpp"
#include "per_model.hpp"

#include <wlx/model.hpp>

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

// This model's entry in the registry.
const ModelCommands& entry();

WLX_COMMANDS_END
