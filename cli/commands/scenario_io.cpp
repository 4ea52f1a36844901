#include "per_model.hpp"
#include "scenario_io.hpp"

#include "bounded_input.hpp"
#include "csv_columns.hpp"
#include "interrupt.hpp"
#include "input.hpp"
#include "limits.hpp"
#include "scenario_folder.hpp"

#include <fmt/format.h>
#include <wlx/support/text.hpp>
#include <wlx/support/bounded_file.hpp>
#include <wlx/error.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

WLX_COMMANDS_BEGIN

// Defined in the build tree's embedded_scenarios.cpp (CMakeLists.txt writes it from scenarios/).
extern const std::vector<std::pair<std::string, std::string>> kEmbeddedScenarios;

namespace {
// The model's runs: those of --scenarios DIR if given (cli/shell/scenario_folder.hpp), else the
// embedded ones.
const std::vector<std::pair<std::string, std::string>>& scenario_set() {
  const ScenarioFolder* folder = scenario_folder();
  return folder != nullptr ? folder->scenarios : kEmbeddedScenarios;
}
}  // namespace

std::vector<std::string> scenario_ids() {
  std::vector<std::string> ids;
  for (const auto& [id, text] : scenario_set()) ids.push_back(id);
  return ids;
}

std::string embedded_scenario(const std::string& id) {
  for (const auto& [i, text] : scenario_set())
    if (i == id) return text;
  return {};
}

nlohmann::json read_scenario_json(const std::string& arg) {
  std::string text;
  std::error_code ec;  // e.g. a name too long for a path: then it is not a file (the message excerpts it)
  if (std::filesystem::is_regular_file(arg, ec)) {
    std::ifstream in(arg, std::ios::binary);
    if (!in) throw Error(arg, "cannot open for reading");
    text = read_all_capped(in, arg, kMaxFileBytes);
    if (in.bad()) throw Error(arg, "reading failed");
  } else {
    text = embedded_scenario(arg);
    if (text.empty()) {
      const std::string hint = nearest(arg, scenario_ids());
      throw Error("SCENARIO", fmt::format("'{}' is neither a file nor a scenario id{}", excerpt(arg),
                                          hint.empty() ? " (wlx simulate --list shows them)" : "; did you mean '" + hint + "'?"));
    }
    return model_scenario_json(arg);
  }
  return parse_json_bounded(text, arg);
}

nlohmann::json model_scenario_json(const std::string& id) {
  const std::string text = embedded_scenario(id);
  if (text.empty()) throw Error("SCENARIO", fmt::format("the model has no scenario '{}'", excerpt(id)));
  // A run of the model's (or of --scenarios DIR) is known by its file's name: its "id", if it
  // has one, must say the same, else the report and the viewer would name it otherwise.
  nlohmann::json j = parse_json_bounded(text, id);
  if (j.is_object()) {
    if (!j.contains("id")) j["id"] = id;
    else if (j.at("id") != id)
      throw Error(id + ": id", fmt::format("is {}, but the run's file is named {}.json: a run's id is its file's name",
                                           excerpt(j.at("id")), id));
  }
  return j;
}

std::string model_scenario_directory() {
  const ScenarioFolder* folder = scenario_folder();
  return folder != nullptr ? folder->dir : std::string();
}

Quantity quantity_of(bool angle, bool rate) {
  if (!angle) return Quantity::other;
  return rate ? Quantity::angular_rate : Quantity::angle;
}

double si_value(const nlohmann::json& v, const std::string& key, Quantity quantity) {
  if (v.is_object()) {
    if (quantity == Quantity::other) throw Error(key, "only angles may be given in degrees; give this value in SI units");
    // One unit per quantity: {"deg/s": x} for an angle (or {"deg": x} for a rate) is a mistake, not a synonym.
    const char* unit = quantity == Quantity::angle ? "deg" : "deg/s";
    if (v.size() != 1 || !v.contains(unit))
      throw Error(key, fmt::format("expected a number or {{\"{}\": x}}, got {}", unit, excerpt(v)));
    return finite_number(v.at(unit), key + "." + unit) * std::numbers::pi / 180;
  }
  return finite_number(v, key);
}

namespace {
// "psi_l2, psi_l3, ...": the actuators in the order of a weighting's entries.
std::string actuator_list() {
  std::string out;
  for (const std::string_view a : kActuatorNames) out += (out.empty() ? "" : ", ") + std::string(a);
  return out;
}
}  // namespace

Weighting parse_weighting(const nlohmann::json& v, const std::string& key) {
  // By what they do; 1, 2 and 3 are the thesis' numbers for the same three (docs/excavator.md).
  if (v == "model-weights" || (v.is_number_integer() && v == 1)) return Weighting::model_weights();
  if (v == "contribution" || (v.is_number_integer() && v == 2)) return Weighting::contribution();
  if (v == "contacts" || (v.is_number_integer() && v == 3)) return Weighting::contacts();
  if (v.is_object() && v.size() == 1 && v.contains("diag")) {
    const auto& d = v.at("diag");
    if (!d.is_array() || d.size() != static_cast<std::size_t>(kActuatedCount))
      throw Error(key + ".diag", fmt::format("must be an array of {} weights (one per actuator: {}), got {}", kActuatedCount,
                                             actuator_list(), excerpt(d)));
    TorqueVector w;
    for (int i = 0; i < kActuatedCount; ++i) w(i) = finite_number(d[static_cast<std::size_t>(i)], fmt::format("{}.diag[{}]", key, i));
    // Only ratios of weights matter (a uniform scale leaves the torques unchanged); beyond this span
    // rounding, not the weights, would decide how the torque is split.
    if (w.minCoeff() > 0 && w.maxCoeff() / w.minCoeff() > kMaxWeightRatio)
      throw Error(key + ".diag", fmt::format("the largest weight is {:.3g} times the smallest; at most {:g} is meaningful",
                                             w.maxCoeff() / w.minCoeff(), kMaxWeightRatio));
    try {
      return Weighting::diagonal_of(w);
    } catch (const Error& e) {
      throw Error(key + ".diag", e.reason());
    }
  }
  if (v.is_object() && v.size() == 1 && v.contains("matrix")) {
    const auto& m = v.at("matrix");
    constexpr auto n = static_cast<std::size_t>(kActuatedCount);
    if (!m.is_array() || m.size() != n)
      throw Error(key + ".matrix", fmt::format("must be {} rows of {} numbers (one per actuator: {})", n, n, actuator_list()));
    TorqueMatrix W;
    for (int r = 0; r < kActuatedCount; ++r) {
      const auto& row = m[static_cast<std::size_t>(r)];
      if (!row.is_array() || row.size() != n) throw Error(fmt::format("{}.matrix[{}]", key, r), fmt::format("must be a row of {} numbers", n));
      for (int c = 0; c < kActuatedCount; ++c) W(r, c) = finite_number(row[static_cast<std::size_t>(c)], fmt::format("{}.matrix[{}][{}]", key, r, c));
    }
    try {
      return Weighting::matrix_of(W);
    } catch (const Error& e) {
      throw Error(key + ".matrix", e.reason());
    }
  }
  throw Error(key, fmt::format("must be \"model-weights\" (or 1), \"contribution\" (2), \"contacts\" (3), {{\"diag\": [{0} weights]}} "
                               "or {{\"matrix\": [[{0} x {0}]]}}, got {1}",
                               kActuatedCount, excerpt(v)));
}

std::string scenario_directory(const std::string& path_or_id) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path_or_id, ec))
    return embedded_scenario(path_or_id).empty() ? std::string() : model_scenario_directory();
  return std::filesystem::path(path_or_id).parent_path().string();
}

namespace {

// The CSV columns of a torque table: t, then tau_<actuator> (as `wlx simulate` writes them).
std::vector<std::string> torque_columns() {
  std::vector<std::string> names{"t"};
  for (const std::string_view a : kActuatorNames) names.push_back("tau_" + std::string(a));
  return names;
}

// A table's rows: bounded in number and size, checked against the run it drives.
TorqueTable torque_table(const std::map<std::string, std::vector<double>>& columns, const std::string& key,
                         TorqueTable::Interpolation interpolation, double duration) {
  const std::vector<double>& times = columns.at("t");
  if (times.size() > kMaxTorqueRows)
    throw Error(key, fmt::format("{} rows, more than the limit of {}", times.size(), kMaxTorqueRows));
  // Rows closer than an integrator step can resolve: a cubic's slopes divide by the gap, so two
  // rows 1e-300 s apart made an infinite torque a run stopped on far from the table.
  for (std::size_t r = 1; r < times.size(); ++r) {
    const double gap = times[r] - times[r - 1];
    if (gap > 0 && gap < kMinTorqueRowGap * std::max(1.0, std::abs(times[r])))
      throw Error(key + ".t", fmt::format("rows {} and {} are {:g} s apart: a table's rows must be at least {:g} s apart (relative "
                                          "to t beyond 1 s), which an integrator step can resolve",
                                          r - 1, r, gap, kMinTorqueRowGap));
  }
  std::vector<TorqueVector> rows(times.size());
  for (int a = 0; a < kActuatedCount; ++a) {
    const std::string name = "tau_" + std::string(kActuatorNames[static_cast<std::size_t>(a)]);
    const std::vector<double>& values = columns.at(name);
    if (values.size() != times.size())
      throw Error(key + "." + name, fmt::format("has {} values for {} times", values.size(), times.size()));
    for (std::size_t r = 0; r < times.size(); ++r) {
      if (!(std::abs(values[r]) <= kMaxTorque))
        throw Error(key + "." + name, fmt::format("row {}: |{}| N m (or N) is beyond the limit of {:g}", r, values[r], kMaxTorque));
      rows[r](a) = values[r];
    }
  }
  try {
    TorqueTable table(times, std::move(rows), interpolation);
    // The run asks for every time in [0, duration]: a table that ends early is a mistake now, not
    // a run that stops half-way.
    if (table.start() > 0 || table.end() < duration * (1 - 1e-12))
      throw Error("torques", fmt::format("the table covers t = {} to {} s; the run needs 0 to {} s", table.start(),
                                         table.end(), duration));
    return table;
  } catch (const Error& e) {
    throw Error(key, e.reason());
  }
}

}  // namespace

TorqueSource parse_torques(const nlohmann::json& v, const Params& params, double duration, const std::string& directory) {
  const std::string key = "torques";
  if (!v.is_object())
    throw Error(key, fmt::format("must be {{\"file\": CSV}}, {{\"run\": an inverse-dynamics scenario}} or {{\"t\": [...], "
                                 "\"tau_<actuator>\": [...]}}, got {}",
                                 excerpt(v)));
  const std::vector<std::string> columns = torque_columns();
  const int sources = static_cast<int>(v.contains("file")) + static_cast<int>(v.contains("run")) + static_cast<int>(v.contains("t"));
  if (sources != 1) throw Error(key, "give exactly one of \"file\", \"run\" or the columns \"t\", \"tau_<actuator>\"");
  std::vector<std::string> valid{"interpolation"};
  if (v.contains("t")) valid.insert(valid.end(), columns.begin(), columns.end());
  else valid.emplace_back(v.contains("file") ? "file" : "run");
  reject_unknown_keys(v, valid, key + ".");
  // A run's torques are samples of a smooth function (cubic); a table of set points means what
  // it says between its rows (linear).
  auto interpolation = v.contains("run") ? TorqueTable::Interpolation::cubic : TorqueTable::Interpolation::linear;
  if (v.contains("interpolation")) {
    const auto& i = v.at("interpolation");
    if (i == "linear") interpolation = TorqueTable::Interpolation::linear;
    else if (i == "cubic") interpolation = TorqueTable::Interpolation::cubic;
    else throw Error(key + ".interpolation", fmt::format("must be \"linear\" or \"cubic\", got {}", excerpt(i)));
  }
  const auto text_of = [&](const char* field) {
    const auto& value = v.at(field);
    if (!value.is_string() || value.get<std::string>().empty())
      throw Error(key + "." + field, fmt::format("must be a file name, got {}", excerpt(value)));
    return value.get<std::string>();
  };
  if (v.contains("file")) {
    const std::string name = text_of("file");
    const std::filesystem::path path = std::filesystem::path(name).is_absolute() || directory.empty()
                                           ? std::filesystem::path(name)
                                           : std::filesystem::path(directory) / name;
    const BoundedRead file = read_bounded_file(path.string(), kMaxFileBytes);
    if (!file.ok()) throw Error(key + ".file", fmt::format("{}: {}", excerpt(path.string()), file.error));
    return torque_table(read_csv_columns(file.text, key + ".file", "the torque table " + excerpt(path.string()), columns),
                        key + ".file", interpolation, duration);
  }
  if (v.contains("run")) {
    const std::string id = text_of("run");
    // A file beside the scenario, else a file or an embedded id as `wlx simulate` takes them.
    std::error_code ec;
    const std::filesystem::path beside = std::filesystem::path(directory) / id;
    const std::string source = !directory.empty() && std::filesystem::is_regular_file(beside, ec) ? beside.string() : id;
    const nlohmann::json referenced = read_scenario_json(source);
    if (referenced.is_object() && referenced.contains("torques"))
      throw Error(key + ".run", fmt::format("'{}' is driven by torques itself: name an inverse-dynamics run", excerpt(id)));
    Scenario inverse = parse_scenario(referenced, params, scenario_directory(source));
    if (!inverse.weighting)
      throw Error(key + ".run", fmt::format("'{}' has no weighting: it is a kinematic run, and only an inverse-dynamics run "
                                            "computes torques",
                                            excerpt(id)));
    if (inverse.samples() > static_cast<long>(kMaxTorqueRows))
      throw Error(key + ".run", fmt::format("'{}' has {} samples, more than the limit of {} rows", excerpt(id),
                                            inverse.samples(), kMaxTorqueRows));
    std::map<std::string, std::vector<double>> table;
    for (const auto& name : columns) table[name].reserve(static_cast<std::size_t>(inverse.samples()));
    const Trajectory run = simulate_each(inverse, [&](const Sample& smp) {
      throw_if_interrupted();
      table["t"].push_back(smp.t);
      for (int a = 0; a < kActuatedCount; ++a) table[columns[static_cast<std::size_t>(a) + 1]].push_back(smp.tau(a));
    });
    if (!run.complete) throw Error(key + ".run", fmt::format("the inverse-dynamics run '{}' {}", excerpt(id), run.error));
    return torque_table(table, key + ".run", interpolation, duration);
  }
  std::map<std::string, std::vector<double>> table;
  for (const auto& name : columns) {
    if (!v.contains(name))
      throw Error(key, fmt::format("has \"t\" but no column \"{}\": a table gives every actuator's torque", name));
    const auto& column = v.at(name);
    if (!column.is_array()) throw Error(key + "." + name, fmt::format("must be an array of numbers, got {}", excerpt(column)));
    if (column.size() > kMaxTorqueRows)
      throw Error(key + "." + name, fmt::format("{} rows, more than the limit of {}", column.size(), kMaxTorqueRows));
    std::vector<double>& values = table[name];
    for (std::size_t r = 0; r < column.size(); ++r) values.push_back(finite_number(column[r], fmt::format("{}.{}[{}]", key, name, r)));
  }
  return torque_table(table, key, interpolation, duration);
}

Scenario parse_scenario(const nlohmann::json& j, const Params& base, const std::string& directory, TorqueSource function) {
  if (!j.is_object()) throw Error("", fmt::format("a scenario is a JSON object, got {}", j.type_name()));
  reject_unknown_keys(j, {"id", "model", "description", "observation", "verify", "initial", "params", "rates", "dependent", "duration",
                          "dt", "integrator", "tolerance", "branch", "max_condition", "weighting", "torques",
                          "on_contact_loss", "on_limit"},
                      "");
  // "model": the model the run was written for. Names alone may match another machine's (two
  // models with an x_C), so a run says whose it is, and running it on another is an error.
  if (j.contains("model")) {
    const nlohmann::json& m = j.at("model");
    if (!m.is_string()) throw Error("model", fmt::format("must be the model's name (a string), got {}", excerpt(m)));
    if (m.get<std::string>() != gen::kModelName)
      throw Error("model", fmt::format("the scenario is for model '{}', not for '{}', the model it would run on "
                                       "(--model or --model-file chooses the model)",
                                       excerpt(m.get<std::string>()), gen::kModelName));
  }
  // "verify": "nonholonomic" puts the scenario into `wlx verify nonholonomic`.
  if (j.contains("verify") && j.at("verify") != "nonholonomic")
    throw Error("verify", fmt::format("the only verification a scenario joins is \"nonholonomic\", got {}", excerpt(j.at("verify"))));
  Scenario sc;
  const auto text = [&](const char* key) {
    if (!j.contains(key)) return std::string();
    if (!j.at(key).is_string()) throw Error(key, fmt::format("must be a string, got {}", excerpt(j.at(key))));
    // Ids and descriptions reach the report's scripts and page and the viewer's files: one line of
    // printable UTF-8 (and quoted again for each language where they are written).
    std::string value = j.at(key).get<std::string>();
    if (const std::string why = text::check_one_line(value); !why.empty()) throw Error(key, why);
    return value;
  };
  sc.id = text("id");
  sc.description = text("description");
  sc.params = base;
  if (j.contains("params")) sc.params = parse_params(j.at("params"), base);
  for (const char* group : {"initial", "rates"}) {
    if (!j.contains(group)) continue;
    const auto& obj = j.at(group);
    if (!obj.is_object()) throw Error(group, fmt::format("must be an object of input names, got {}", obj.type_name()));
    reject_unknown_keys(obj, input_names(), std::string(group) + ".");
    for (const auto& [key, value] : obj.items()) {
      const int k = coordinate_index(key);
      const double v = si_value(value, std::string(group) + "." + key, quantity_of(is_angle(k), std::string(group) == "rates"));
      if (std::string(group) == "initial") check_input_bound(k, v, std::string(group) + "." + key);
      else check_rate_bound(k, v, std::string(group) + "." + key);
      if (std::string(group) == "initial") sc.initial(k) = v;
      else sc.rates(k) = v;
    }
  }
  const bool by_torques = j.contains("torques") || static_cast<bool>(function);
  if (!j.contains("dependent") && by_torques) {
    sc.pair = dynamics_pair();  // the only pair a forward-dynamics run can have
  } else if (!j.contains("dependent")) {
    std::string example;
    for (int k : default_pair().index)
      example += fmt::format("{}\"{}\"", example.empty() ? "" : ", ", gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    throw Error("dependent",
                fmt::format("missing: name the {} dependent rates (one per wheel), e.g. [{}]", kWheelCount, example));
  } else {
    const auto& dep = j.at("dependent");
    if (!dep.is_array() || dep.size() != static_cast<std::size_t>(kWheelCount) ||
        !std::all_of(dep.begin(), dep.end(), [](const auto& name) { return name.is_string(); }))
      throw Error("dependent", fmt::format("must be an array of {} names, got {}", kWheelCount, excerpt(dep)));
    std::vector<std::string> names;
    for (const auto& name : dep) {  // the pair's own messages quote the names in full
      if (excerpt(name.get<std::string>()) != name.get<std::string>())
        throw Error("dependent", fmt::format("'{}' cannot be a dependent rate", excerpt(name.get<std::string>())));
      names.push_back(name.get<std::string>());
    }
    sc.pair = dependent_pair(names);
  }
  if (!j.contains("duration")) throw Error("duration", "missing: the run's length in seconds");
  sc.duration = finite_number(j.at("duration"), "duration");
  if (j.contains("dt")) sc.dt = finite_number(j.at("dt"), "dt");
  if (j.contains("integrator")) {
    const auto& in = j.at("integrator");
    const auto integrator = in.is_string() ? integrator_from_name(in.get<std::string>()) : std::nullopt;
    if (!integrator) throw Error("integrator", fmt::format("must be \"rk4\", \"euler\" or \"dopri5\", got {}", excerpt(in)));
    sc.integrator = *integrator;
  }
  if (j.contains("tolerance")) {
    // Only the adaptive integrator has a tolerance: on rk4 or euler it would be ignored without a
    // word, and the writer would believe the run accurate to it.
    if (sc.integrator != Integrator::dopri5)
      throw Error("tolerance", fmt::format("applies to the adaptive integrator only; this run integrates with {} at a fixed "
                                           "dt (the file's \"integrator\" or `wlx simulate --integrator`: choose dopri5, or "
                                           "remove the tolerance)",
                                           sc.integrator == Integrator::rk4 ? "rk4" : "euler"));
    sc.tolerance = finite_number(j.at("tolerance"), "tolerance");
  }
  if (j.contains("branch")) sc.branches = parse_ik_request(nlohmann::json{{"branch", j.at("branch")}}).branches;
  if (j.contains("max_condition")) {
    sc.nonholonomic.max_condition = finite_number(j.at("max_condition"), "max_condition");
    if (!(sc.nonholonomic.max_condition > 1))
      throw Error("max_condition", fmt::format("must be above 1, got {}", sc.nonholonomic.max_condition));
  }
  if (j.contains("weighting")) sc.weighting = parse_weighting(j.at("weighting"), "weighting");
  if (j.contains("on_limit")) {
    const nlohmann::json& v = j.at("on_limit");
    if (!(v == "stop" || v == "continue"))
      throw Error("on_limit", fmt::format("must be \"stop\" or \"continue\", got {}", excerpt(v)));
    sc.stop_on_limit = v == "stop";
  }
  if (j.contains("on_contact_loss")) {
    const nlohmann::json& v = j.at("on_contact_loss");
    if (!(v == "stop" || v == "continue"))
      throw Error("on_contact_loss", fmt::format("must be \"stop\" or \"continue\", got {}", excerpt(v)));
    sc.stop_on_contact_loss = v == "stop";
  }
  if (j.contains("torques")) {
    if (sc.weighting)
      throw Error("torques", "a run is driven by its rates (the weighting then splits their torques) or by torques, not both");
    sc.validate();  // the time grid first: the table is checked against it
    sc.torques = parse_torques(j.at("torques"), sc.params, sc.duration, directory);
  }
  if (function) {
    if (j.contains("torques"))
      throw Error("torques", "given twice: in the scenario and as a function; keep one");
    if (sc.weighting)
      throw Error("torques", "a run is driven by its rates (the weighting then splits their torques) or by torques, not both");
    sc.torques = std::move(function);
  }
  sc.validate();
  return sc;
}

WLX_COMMANDS_END
