#include "wlx/generic/description.hpp"

#include "wlx/error.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace wlx::generic {

namespace {

using Json = nlohmann::json;

// model.json is wlx-gen's: a bigger or deeper text is not one (the largest models' are under 1 MB).
constexpr std::size_t kMaxTextBytes = 64u << 20;
constexpr int kMaxDepth = 16;

[[noreturn]] void fail(const std::string& what) { throw Error("model.json", what); }

const Json& member(const Json& object, const char* key, const std::string& where) {
  if (!object.is_object() || !object.contains(key)) fail(fmt::format("{} has no '{}'", where, key));
  return object[key];
}

std::string text(const Json& object, const char* key, const std::string& where) {
  const Json& v = member(object, key, where);
  if (!v.is_string()) fail(fmt::format("{}.{} is not a string", where, key));
  return v.get<std::string>();
}

double number(const Json& v, const std::string& where) {
  if (!v.is_number()) fail(fmt::format("{} is not a number", where));
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(fmt::format("{} is not finite", where));
  return x;
}

// A number, or null for `absent`.
double number_or(const Json& object, const char* key, double absent, const std::string& where) {
  const Json& v = member(object, key, where);
  return v.is_null() ? absent : number(v, where + "." + key);
}

const Json& list(const Json& object, const char* key, const std::string& where, std::size_t most) {
  const Json& v = member(object, key, where);
  if (!v.is_array()) fail(fmt::format("{}.{} is not a list", where, key));
  if (v.size() > most) fail(fmt::format("{}.{} has {} entries, more than the {} a model may have", where, key, v.size(), most));
  return v;
}

// The index of each name in `names`, as `what` (an error names the unknown one).
template <class Lookup>
std::vector<int> indices(const Json& names, const std::string& where, const char* what, Lookup lookup) {
  if (!names.is_array()) fail(fmt::format("{} is not a list", where));
  std::vector<int> out;
  for (const Json& n : names) {
    if (!n.is_string()) fail(fmt::format("{} holds a value that is not a name", where));
    const int k = lookup(n.get<std::string>());
    if (k < 0) fail(fmt::format("{}: no {} '{}'", where, what, n.get<std::string>()));
    out.push_back(k);
  }
  return out;
}

template <class T>
int index_by_name(const std::vector<T>& items, std::string_view name) noexcept {
  for (std::size_t k = 0; k < items.size(); ++k)
    if (items[k].name == name) return static_cast<int>(k);
  return -1;
}

}  // namespace

int Description::max_limb_size() const noexcept {
  std::size_t n = 1;
  for (const Limb& l : limbs) n = std::max(n, l.joints.size());
  return static_cast<int>(n);
}
int Description::coordinate_index(std::string_view name) const noexcept { return index_by_name(coordinates, name); }
int Description::frame_index(std::string_view name) const noexcept { return index_by_name(frames, name); }
int Description::parameter_index(std::string_view name) const noexcept { return index_by_name(parameters, name); }
int Description::limb_index(std::string_view name) const noexcept { return index_by_name(limbs, name); }

Description read_description(std::string_view json_text) {
  if (json_text.size() > kMaxTextBytes) fail(fmt::format("{} bytes, more than a description's {}", json_text.size(), kMaxTextBytes));
  Json d;
  try {
    d = Json::parse(json_text, [](int depth, Json::parse_event_t, Json&) {
      if (depth > kMaxDepth) throw Error("model.json", fmt::format("nested deeper than {} levels", kMaxDepth));
      return true;
    });
  } catch (const Json::exception& e) {
    fail(fmt::format("not JSON ({})", e.what()));
  }
  if (!d.is_object() || !d.contains("format") || d["format"] != "wlx model description 1")
    fail("it is not a wlx model description of format 1 (regenerate the model with this wlx-gen)");
  Description out;
  out.model = text(d, "model", "model.json");
  out.code_key = text(d, "code_key", "model.json");

  for (const Json& p : list(d, "parameters", "model.json", kMaxParameters)) {
    Parameter parameter;
    parameter.name = text(p, "name", "parameters[]");
    const std::string where = "parameters." + parameter.name;
    parameter.unit = text(p, "unit", where);
    if (!parameter_kind_of(text(p, "kind", where), parameter.kind)) fail(fmt::format("{}.kind is no parameter kind", where));
    parameter.value = number(member(p, "value", where), where + ".value");
    out.parameters.push_back(std::move(parameter));
  }

  bool inputs_done = false;
  for (const Json& c : list(d, "coordinates", "model.json", kMaxCoordinates)) {
    Coordinate coordinate;
    coordinate.name = text(c, "name", "coordinates[]");
    const std::string where = "coordinates." + coordinate.name;
    coordinate.unit = text(c, "unit", where);
    const Json& input = member(c, "input", where);
    if (!input.is_boolean()) fail(fmt::format("{}.input is not true or false", where));
    coordinate.input = input.get<bool>();
    if (coordinate.input && inputs_done) fail(fmt::format("{}: an input after a dependent coordinate (the inputs come first)", where));
    inputs_done = inputs_done || !coordinate.input;
    out.input_count += coordinate.input ? 1 : 0;
    out.coordinates.push_back(std::move(coordinate));
  }
  const auto coordinate = [&](const std::string& name) { return out.coordinate_index(name); };

  for (const Json& f : list(d, "frames", "model.json", kMaxFrames)) {
    Frame frame;
    frame.name = text(f, "name", "frames[]");
    const std::string parent = text(f, "parent", "frames." + frame.name);
    if (parent != "K0") {
      frame.parent = out.frame_index(parent);
      // A frame's parent comes before it: the chains are written from the ground up.
      if (frame.parent < 0) fail(fmt::format("frames.{}: its parent '{}' is not a frame before it", frame.name, parent));
    }
    out.frames.push_back(std::move(frame));
  }

  for (const Json& b : list(d, "bodies", "model.json", kMaxFrames)) {
    Body body;
    body.name = text(b, "name", "bodies[]");
    const std::string where = "bodies." + body.name;
    body.frame = out.frame_index(text(b, "frame", where));
    if (body.frame < 0) fail(fmt::format("{}.frame is no frame", where));
    body.mass = out.parameter_index(text(b, "mass", where));
    if (body.mass < 0) fail(fmt::format("{}.mass is no parameter", where));
    const std::vector<int> inertia =
        indices(member(b, "inertia", where), where + ".inertia", "parameter", [&](const std::string& n) { return out.parameter_index(n); });
    if (inertia.size() != 3) fail(fmt::format("{}.inertia does not name three parameters", where));
    std::copy(inertia.begin(), inertia.end(), body.inertia.begin());
    out.bodies.push_back(std::move(body));
  }

  for (const Json& r : list(d, "closure", "model.json", kMaxCoordinates)) out.closure_rows.push_back(text(r, "name", "closure[]"));
  const auto row = [&](const std::string& name) {
    for (std::size_t k = 0; k < out.closure_rows.size(); ++k)
      if (out.closure_rows[k] == name) return static_cast<int>(k);
    return -1;
  };

  for (const Json& l : list(d, "limbs", "model.json", kMaxLimbs)) {
    Limb limb;
    limb.name = text(l, "name", "limbs[]");
    const std::string where = "limbs." + limb.name;
    limb.title = text(l, "title", where);
    limb.joints = indices(member(l, "joints", where), where + ".joints", "coordinate", coordinate);
    limb.rows = indices(member(l, "closure", where), where + ".closure", "closure row", row);
    limb.inputs = indices(member(l, "inputs", where), where + ".inputs", "coordinate", coordinate);
    if (limb.joints.size() != limb.rows.size())
      fail(fmt::format("{}: {} joints against {} closure rows (a limb's block is square)", where, limb.joints.size(), limb.rows.size()));
    if (limb.joints.empty() || limb.joints.size() > static_cast<std::size_t>(kMaxLimbSize))
      fail(fmt::format("{}: {} joints; a limb has 1 to {}", where, limb.joints.size(), kMaxLimbSize));
    for (int j : limb.joints)
      if (out.coordinates[static_cast<std::size_t>(j)].input) fail(fmt::format("{}.joints: {} is an input", where, out.coordinates[static_cast<std::size_t>(j)].name));
    for (int i : limb.inputs)
      if (!out.coordinates[static_cast<std::size_t>(i)].input) fail(fmt::format("{}.inputs: {} is not an input", where, out.coordinates[static_cast<std::size_t>(i)].name));
    out.limbs.push_back(std::move(limb));
  }

  const Json& settings = member(d, "settings", "model.json");
  const auto n = static_cast<std::size_t>(out.coordinate_count());
  Settings& s = out.settings;
  s.nominal_inputs.assign(static_cast<std::size_t>(out.input_count), 0.0);
  s.dependent_start.assign(n, 0.0);
  s.lower.assign(n, -std::numeric_limits<double>::infinity());
  s.upper.assign(n, std::numeric_limits<double>::infinity());
  s.velocity_limit.assign(n, 0.0);
  s.default_branch.assign(out.limbs.size(), -1);
  // One value per coordinate of [first, last), from an object keyed by name: each present, no other.
  const auto by_name = [&](const char* key, int first, int last, std::vector<double>& values, int offset) {
    const Json& object = member(settings, key, "settings");
    const std::string where = std::string("settings.") + key;
    if (!object.is_object() || object.size() != static_cast<std::size_t>(last - first))
      fail(fmt::format("{} does not hold exactly {} values", where, last - first));
    for (int k = first; k < last; ++k) {
      const std::string& name = out.coordinates[static_cast<std::size_t>(k)].name;
      if (!object.contains(name)) fail(fmt::format("{} has no '{}'", where, name));
      values[static_cast<std::size_t>(k - offset)] = number(object[name], where + "." + name);
    }
  };
  by_name("nominal", 0, out.input_count, s.nominal_inputs, 0);
  by_name("dependent_start", out.input_count, out.coordinate_count(), s.dependent_start, 0);
  for (const Json& l : list(settings, "limits", "settings", kMaxCoordinates)) {
    const std::string name = text(l, "coordinate", "settings.limits[]");
    const std::string where = "settings.limits." + name;
    const int k = out.coordinate_index(name);
    if (k < 0) fail(fmt::format("{}: no coordinate '{}'", where, name));
    const auto kk = static_cast<std::size_t>(k);
    s.lower[kk] = number_or(l, "lower", -std::numeric_limits<double>::infinity(), where);
    s.upper[kk] = number_or(l, "upper", std::numeric_limits<double>::infinity(), where);
    s.velocity_limit[kk] = number_or(l, "velocity", 0, where);
    if (!(s.lower[kk] <= s.upper[kk])) fail(fmt::format("{}: lower {} above upper {}", where, s.lower[kk], s.upper[kk]));
    if (!(s.velocity_limit[kk] >= 0)) fail(fmt::format("{}.velocity is negative", where));
  }
  const Json& branches = member(settings, "branches", "settings");
  if (!branches.is_object()) fail("settings.branches is not an object");
  for (const auto& [name, value] : branches.items()) {
    const int l = out.limb_index(name);
    if (l < 0) fail(fmt::format("settings.branches: no limb '{}'", name));
    if (!value.is_number_integer() || value.get<std::int64_t>() < 0 || value.get<std::int64_t>() > 1024)
      fail(fmt::format("settings.branches.{} is not a branch (a whole number from 0)", name));
    s.default_branch[static_cast<std::size_t>(l)] = static_cast<int>(value.get<std::int64_t>());
  }
  return out;
}

}  // namespace wlx::generic
