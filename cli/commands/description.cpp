#include "description.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <wlx/error.hpp>

#include <algorithm>
#include <cstdint>
#include <limits>

WLX_COMMANDS_BEGIN

namespace {

using Json = nlohmann::json;

[[noreturn]] void mismatch(const std::string& what) {
  throw Error("model.json", fmt::format("{} (it was written for other code: regenerate the model)", what));
}

const Json& member(const Json& object, const std::string& key, Json::value_t type, const std::string& where) {
  if (!object.is_object() || !object.contains(key)) mismatch(fmt::format("{} has no '{}'", where, key));
  const Json& value = object[key];
  // A number of either kind where a number is asked for.
  const bool ok = type == Json::value_t::number_float ? value.is_number() : value.type() == type;
  if (!ok) mismatch(fmt::format("{}.{} is not a {}", where, key, type == Json::value_t::number_float ? "number" : "value of the expected kind"));
  return value;
}

double number(const Json& object, const std::string& key, const std::string& where) {
  return member(object, key, Json::value_t::number_float, where).get<double>();
}

// One value per named coordinate, from an object keyed by name: every name present, no other.
template <std::size_t N>
void by_name(const Json& object, int first, std::array<double, N>& out, const std::string& where) {
  if (!object.is_object() || object.size() != N) mismatch(fmt::format("{} does not hold exactly {} values", where, N));
  for (std::size_t k = 0; k < N; ++k) out[k] = number(object, std::string(gen::kCoordinateNames[static_cast<std::size_t>(first) + k]), where);
}

template <std::size_t N>
void numbers(const Json& list, std::array<double, N>& out, const std::string& where) {
  if (!list.is_array() || list.size() != N) mismatch(fmt::format("{} does not hold exactly {} numbers", where, N));
  for (std::size_t k = 0; k < N; ++k) {
    if (!list[k].is_number()) mismatch(fmt::format("{}[{}] is not a number", where, k));
    out[k] = list[k].get<double>();
  }
}

}  // namespace

Settings settings_of_description(const std::string& json_text) {
  Json d;
  try {
    d = Json::parse(json_text);
  } catch (const Json::exception& e) {
    throw Error("model.json", fmt::format("not JSON ({})", e.what()));
  }
  if (!d.is_object() || d.value("format", "") != "wlx model description 1") mismatch("it is not a wlx model description of format 1");
  if (d.value("model", "") != gen::kModelName) mismatch(fmt::format("it describes model '{}', not '{}'", d.value("model", ""), gen::kModelName));
  Settings s;
  const Json& params = member(d, "parameters", Json::value_t::array, "model.json");
  if (params.size() != gen::kParamInfo.size()) mismatch(fmt::format("it has {} parameters, the code {}", params.size(), gen::kParamInfo.size()));
  for (std::size_t k = 0; k < params.size(); ++k) {
    const auto& info = gen::kParamInfo[k];
    if (!params[k].is_object() || params[k].value("name", "") != info.name)
      mismatch(fmt::format("parameter {} is not '{}'", k + 1, info.name));
    s.params.*info.member = number(params[k], "value", "parameters." + std::string(info.name));
  }
  const Json& section = member(d, "settings", Json::value_t::object, "model.json");
  by_name(member(section, "nominal", Json::value_t::object, "settings"), 0, s.nominal_inputs, "settings.nominal");
  by_name(member(section, "dependent_start", Json::value_t::object, "settings"), gen::kInputCount, s.dependent_start,
          "settings.dependent_start");
  by_name(member(section, "sweep_start", Json::value_t::object, "settings"), 0, s.sweep_start, "settings.sweep_start");
  for (const Json& sw : member(section, "ik_sweeps", Json::value_t::array, "settings")) {
    IkSweep sweep;
    sweep.id = member(sw, "id", Json::value_t::string, "settings.ik_sweeps[]").get<std::string>();
    const std::string where = "settings.ik_sweeps." + sweep.id;
    sweep.input = member(sw, "input", Json::value_t::string, where).get<std::string>();
    sweep.from = number(sw, "from", where);
    sweep.to = number(sw, "to", where);
    sweep.step = number(sw, "step", where);
    sweep.degrees = member(sw, "degrees", Json::value_t::boolean, where).get<bool>();
    const std::string limb = member(sw, "limb", Json::value_t::string, where).get<std::string>();
    sweep.limb = -1;
    for (std::size_t l = 0; l < gen::kLimbs.size(); ++l)
      if (gen::kLimbs[l].name == limb) sweep.limb = static_cast<int>(l);
    if (sweep.limb < 0) mismatch(fmt::format("{}: the code has no limb '{}'", where, limb));
    if (!sw.contains("branch")) mismatch(fmt::format("{} has no 'branch'", where));
    if (!sw["branch"].is_null()) {
      if (!sw["branch"].is_number_integer()) mismatch(fmt::format("{}.branch is not a whole number", where));
      sweep.branch = static_cast<int>(std::clamp<std::int64_t>(sw["branch"].get<std::int64_t>(), -2, 1 << 20));
    }
    s.ik_sweeps.push_back(sweep);
  }
  numbers(member(section, "weights", Json::value_t::array, "settings"), s.weights, "settings.weights");
  if (!section.contains("torque_limits")) mismatch("settings has no 'torque_limits'");
  s.has_torque_limits = !section["torque_limits"].is_null();
  if (s.has_torque_limits) numbers(section["torque_limits"], s.torque_limits, "settings.torque_limits");
  numbers(member(section, "friction", Json::value_t::array, "settings"), s.friction, "settings.friction");
  for (const Json& l : member(section, "limits", Json::value_t::array, "settings")) {
    const std::string name = member(l, "coordinate", Json::value_t::string, "settings.limits[]").get<std::string>();
    const std::string where = "settings.limits." + name;
    std::size_t k = 0;
    while (k < gen::kCoordinateNames.size() && gen::kCoordinateNames[k] != name) ++k;
    if (k == gen::kCoordinateNames.size()) mismatch(fmt::format("{}: the code has no coordinate '{}'", where, name));
    const auto optional_number = [&](const char* key, double absent) {
      if (!l.contains(key)) mismatch(fmt::format("{} has no '{}'", where, key));
      return l[key].is_null() ? absent : number(l, key, where);
    };
    s.lower[k] = optional_number("lower", -std::numeric_limits<double>::infinity());
    s.upper[k] = optional_number("upper", std::numeric_limits<double>::infinity());
    s.velocity_limit[k] = optional_number("velocity", 0);
  }
  const Json& branches = member(section, "branches", Json::value_t::object, "settings");
  for (const auto& [limb, value] : branches.items()) {
    std::size_t l = 0;
    while (l < gen::kLimbs.size() && gen::kLimbs[l].name != limb) ++l;
    if (l == gen::kLimbs.size()) mismatch(fmt::format("settings.branches: the code has no limb '{}'", limb));
    if (!value.is_number_integer()) mismatch(fmt::format("settings.branches.{} is not a whole number", limb));
    s.default_branch[l] = static_cast<int>(std::clamp<std::int64_t>(value.get<std::int64_t>(), -2, 1 << 20));
  }
  return s;
}

namespace {
std::string& loaded_description() {
  static std::string text;
  return text;
}
}  // namespace

extern const char* const kEmbeddedDescription;  // the model's model.json, embedded by CMake ("" in a plugin)

const std::string& description_text() {
  static const std::string embedded = kEmbeddedDescription;
  return embedded.empty() ? loaded_description() : embedded;
}

std::string load_description(const std::string& json_text) noexcept {
  try {
    set_settings(settings_of_description(json_text));
    loaded_description() = json_text;
    return {};
  } catch (const Error& e) {
    return e.field() == "model.json" ? fmt::format("model.json: {}", e.reason()) : fmt::format("model.json: {}: {}", e.field(), e.reason());
  } catch (const std::exception& e) {
    return fmt::format("model.json: {}", e.what());
  }
}

WLX_COMMANDS_END
