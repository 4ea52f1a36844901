// Scenario files (scenarios/*.json, embedded in the binary at build time) to wlx::Scenario.
#pragma once

#include "per_model.hpp"
#include <nlohmann/json.hpp>
#include <wlx/simulation.hpp>

#include <string>
#include <vector>

WLX_COMMANDS_BEGIN

// The ids of the embedded scenario files, sorted.
std::vector<std::string> scenario_ids();
// The embedded file's text for an id, or empty.
std::string embedded_scenario(const std::string& id);

// A path to a JSON file, or the id of an embedded scenario; errors suggest the nearest id.
nlohmann::json read_scenario_json(const std::string& path_or_id);
// `base`: the parameters the scenario's "params" override.
Scenario parse_scenario(const nlohmann::json& j, const Params& base = {});

// 1, 2, {"diag": [...]} or {"matrix": [[...]]}.
Weighting parse_weighting(const nlohmann::json& v, const std::string& key);

// A number in SI units, or {"deg": x} / {"deg/s": x} for angle coordinates.
double si_value(const nlohmann::json& v, const std::string& key, bool is_angle);

WLX_COMMANDS_END
