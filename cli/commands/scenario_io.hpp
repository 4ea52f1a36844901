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
// One of the model's runs (scenario_ids(): embedded, or of --scenarios DIR) by its id, with its
// "id" checked against the file's name (or set from it); and the folder its relative files (a
// torque table) are found in: --scenarios' DIR, else none.
nlohmann::json model_scenario_json(const std::string& id);
std::string model_scenario_directory();
// The folder of a scenario file (where the files it names are looked for), or empty for an id.
std::string scenario_directory(const std::string& path_or_id);

// `base`: the parameters the scenario's "params" override; `directory`: where a file the scenario
// names (a torque table) is looked for, relative names from the working directory when empty;
// `function`: set, the run is driven by it (a controller in the loop: Python's
// simulate(torques=f)), and the scenario may then have neither "torques" nor a weighting.
Scenario parse_scenario(const nlohmann::json& j, const Params& base = settings().params, const std::string& directory = {},
                        TorqueSource function = {});

// A scenario's "torques": {"file": CSV}, {"run": an inverse-dynamics scenario, run first with
// `params`} or the columns inline ({"t": [...], "tau_<actuator>": [...]}), with "interpolation"
// "linear" or "cubic" (the default for a run's torques); the table must cover [0, duration].
TorqueSource parse_torques(const nlohmann::json& value, const Params& params, double duration, const std::string& directory);

// 1, 2, {"diag": [...]} or {"matrix": [[...]]}.
Weighting parse_weighting(const nlohmann::json& v, const std::string& key);

// What a JSON value measures, which decides the one non-SI form it may take: an angle may be
// {"deg": x}, an angular rate {"deg/s": x}; anything else is a plain number in SI units.
enum class Quantity { other, angle, angular_rate };
// `angle`: the value is an angle coordinate (or angle parameter); `rate`: it is that coordinate's rate.
Quantity quantity_of(bool angle, bool rate = false);
// A number in SI units, or the degree form its quantity allows ({"deg": x}, {"deg/s": x}).
double si_value(const nlohmann::json& v, const std::string& key, Quantity quantity);

WLX_COMMANDS_END
