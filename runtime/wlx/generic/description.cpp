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

// model.json is wlx-gen's: a deeper text is not one.
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

// The index `lookup` gives the name at object[key], refused as "<where>.<key> is no <what>"; an
// empty name is -1 where `optional`.
template <class Lookup>
int named_index(const Json& object, const char* key, const std::string& where, const char* what, Lookup lookup,
                bool optional = false) {
  const std::string name = text(object, key, where);
  if (optional && name.empty()) return -1;
  const int k = lookup(name);
  if (k < 0) fail(fmt::format("{}.{} is no {}", where, key, what));
  return k;
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

namespace {

void read_parameters(const Json& d, Description& out) {
  for (const Json& p : list(d, "parameters", "model.json", kMaxParameters)) {
    Parameter parameter;
    parameter.name = text(p, "name", "parameters[]");
    const std::string where = "parameters." + parameter.name;
    parameter.unit = text(p, "unit", where);
    if (!parameter_kind_of(text(p, "kind", where), parameter.kind)) fail(fmt::format("{}.kind is no parameter kind", where));
    parameter.value = number(member(p, "value", where), where + ".value");
    out.parameters.push_back(std::move(parameter));
  }

}

void read_coordinates(const Json& d, Description& out) {
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

}

void read_frames_and_bodies(const Json& d, Description& out) {
  const auto frame_named = [&](const std::string& name) { return out.frame_index(name); };
  const auto parameter_named = [&](const std::string& name) { return out.parameter_index(name); };
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
    body.frame = named_index(b, "frame", where, "frame", frame_named);
    body.mass = named_index(b, "mass", where, "parameter", parameter_named);
    const std::vector<int> inertia =
        indices(member(b, "inertia", where), where + ".inertia", "parameter", parameter_named);
    if (inertia.size() != 3) fail(fmt::format("{}.inertia does not name three parameters", where));
    std::copy(inertia.begin(), inertia.end(), body.inertia.begin());
    out.bodies.push_back(std::move(body));
  }

}

void read_limbs(const Json& d, Description& out) {
  const auto coordinate = [&](const std::string& name) { return out.coordinate_index(name); };
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

}

void read_wheels_and_pairs(const Json& d, Description& out) {
  const auto frame_named = [&](const std::string& name) { return out.frame_index(name); };
  const auto parameter_named = [&](const std::string& name) { return out.parameter_index(name); };
  const auto coordinate = [&](const std::string& name) { return out.coordinate_index(name); };
  const auto axis = [](const std::string& name, const std::string& where) {
    if (name == "x") return 0;
    if (name == "y") return 1;
    if (name == "z") return 2;
    fail(fmt::format("{} is no axis (x, y or z)", where));
  };
  for (const Json& w : list(d, "wheels", "model.json", kMaxWheels)) {
    Wheel wheel;
    wheel.name = text(w, "name", "wheels[]");
    const std::string where = "wheels." + wheel.name;
    wheel.contact_frame = named_index(w, "contact", where, "frame", frame_named);
    wheel.hub_frame = named_index(w, "hub", where, "frame", frame_named, true);
    wheel.radius = named_index(w, "radius", where, "parameter", parameter_named);
    wheel.forward_axis = axis(text(w, "forward", where), where + ".forward");
    wheel.lateral_axis = axis(text(w, "lateral", where), where + ".lateral");
    wheel.axle_axis = axis(text(w, "axle", where), where + ".axle");
    wheel.ground = named_index(w, "ground", where, "coordinate", coordinate, true);
    out.wheels.push_back(std::move(wheel));
  }
  const Json& pairs = member(d, "pairs", "model.json");
  out.pair_candidates = indices(member(pairs, "candidates", "pairs"), "pairs.candidates", "coordinate", coordinate);
  for (const Json& p : list(pairs, "named", "pairs", kMaxCoordinates)) {
    Pair pair;
    pair.name = text(p, "name", "pairs.named[]");
    pair.coordinates = indices(member(p, "rates", "pairs." + pair.name), "pairs." + pair.name + ".rates", "coordinate", coordinate);
    out.pairs.push_back(std::move(pair));
  }
  const Json& default_pair = member(pairs, "default", "pairs");
  if (!default_pair.is_null()) {
    if (!default_pair.is_string()) fail("pairs.default is not a pair's name");
    out.default_pair = -1;
    for (std::size_t k = 0; k < out.pairs.size(); ++k)
      if (out.pairs[k].name == default_pair.get<std::string>()) out.default_pair = static_cast<int>(k);
    if (out.default_pair < 0) fail(fmt::format("pairs.default: no pair '{}'", default_pair.get<std::string>()));
  }

}

void read_settings(const Json& d, Description& out) {
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
}

}  // namespace

Description read_description(std::string_view json_text) {
  if (json_text.size() > kMaxDescriptionBytes)
    fail(fmt::format("{} bytes, more than a description's {}", json_text.size(), kMaxDescriptionBytes));
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

  read_parameters(d, out);
  read_coordinates(d, out);
  read_frames_and_bodies(d, out);
  read_limbs(d, out);
  read_wheels_and_pairs(d, out);
  read_settings(d, out);
  validate(out);
  return out;
}

void validate(const Description& d) {
  const auto bounded = [](const char* what, std::size_t n, int most) {
    if (n > static_cast<std::size_t>(most)) fail(fmt::format("{} {}, more than the {} a model may have", n, what, most));
  };
  bounded("coordinates", d.coordinates.size(), kMaxCoordinates);
  bounded("frames", d.frames.size(), kMaxFrames);
  bounded("bodies", d.bodies.size(), kMaxFrames);
  bounded("parameters", d.parameters.size(), kMaxParameters);
  bounded("limbs", d.limbs.size(), kMaxLimbs);
  bounded("closure rows", d.closure_rows.size(), kMaxCoordinates);
  const auto unique = [](const char* what, const auto& items, const auto& name_of) {
    for (std::size_t i = 0; i < items.size(); ++i) {
      if (name_of(items[i]).empty()) fail(fmt::format("{}[{}] has no name", what, i));
      for (std::size_t j = 0; j < i; ++j)
        if (name_of(items[i]) == name_of(items[j])) fail(fmt::format("{}: '{}' twice", what, name_of(items[i])));
    }
  };
  const auto named = [](const auto& item) -> const std::string& { return item.name; };
  unique("coordinates", d.coordinates, named);
  unique("frames", d.frames, named);
  unique("parameters", d.parameters, named);
  unique("bodies", d.bodies, named);
  unique("limbs", d.limbs, named);
  unique("closure", d.closure_rows, [](const std::string& row) -> const std::string& { return row; });
  const int n = d.coordinate_count();
  int inputs = 0;
  for (std::size_t k = 0; k < d.coordinates.size(); ++k) {
    const Coordinate& c = d.coordinates[k];
    if (c.unit != "m" && c.unit != "rad") fail(fmt::format("coordinates.{}: unit '{}', not m or rad", c.name, c.unit));
    if (c.input && static_cast<int>(k) != inputs) fail(fmt::format("coordinates.{}: an input after a dependent coordinate (the inputs come first)", c.name));
    inputs += c.input ? 1 : 0;
  }
  if (inputs != d.input_count) fail(fmt::format("{} inputs flagged, input_count {}", inputs, d.input_count));
  const auto in_range = [](int k, std::size_t size) { return k >= 0 && static_cast<std::size_t>(k) < size; };
  for (std::size_t f = 0; f < d.frames.size(); ++f)
    if (d.frames[f].parent < -1 || d.frames[f].parent >= static_cast<int>(f))
      fail(fmt::format("frames.{}: its parent is not a frame before it", d.frames[f].name));
  for (const Body& b : d.bodies) {
    if (!in_range(b.frame, d.frames.size())) fail(fmt::format("bodies.{}.frame is no frame", b.name));
    if (!in_range(b.mass, d.parameters.size())) fail(fmt::format("bodies.{}.mass is no parameter", b.name));
    for (int i : b.inertia)
      if (!in_range(i, d.parameters.size())) fail(fmt::format("bodies.{}.inertia names no parameter", b.name));
  }
  for (const Limb& l : d.limbs) {
    const std::string where = "limbs." + l.name;
    if (l.joints.size() != l.rows.size())
      fail(fmt::format("{}: {} joints against {} closure rows (a limb's block is square)", where, l.joints.size(), l.rows.size()));
    if (l.joints.empty() || l.joints.size() > static_cast<std::size_t>(kMaxLimbSize))
      fail(fmt::format("{}: {} joints; a limb has 1 to {}", where, l.joints.size(), kMaxLimbSize));
    for (int j : l.joints)
      if (!in_range(j, d.coordinates.size()) || d.coordinates[static_cast<std::size_t>(j)].input)
        fail(fmt::format("{}.joints: not a dependent coordinate", where));
    for (int r : l.rows)
      if (!in_range(r, d.closure_rows.size())) fail(fmt::format("{}.closure: not a closure row", where));
    if (l.inputs.size() > d.coordinates.size()) fail(fmt::format("{}.inputs: more than the model's coordinates", where));
    for (int i : l.inputs)
      if (!in_range(i, d.coordinates.size()) || !d.coordinates[static_cast<std::size_t>(i)].input)
        fail(fmt::format("{}.inputs: not an input", where));
  }
  bounded("wheels", d.wheels.size(), kMaxWheels);
  unique("wheels", d.wheels, named);
  for (const Wheel& w : d.wheels) {
    const std::string where = "wheels." + w.name;
    if (!in_range(w.contact_frame, d.frames.size())) fail(fmt::format("{}.contact is no frame", where));
    if (w.hub_frame != -1 && !in_range(w.hub_frame, d.frames.size())) fail(fmt::format("{}.hub is no frame", where));
    if (!in_range(w.radius, d.parameters.size())) fail(fmt::format("{}.radius is no parameter", where));
    for (int a : {w.forward_axis, w.lateral_axis, w.axle_axis})
      if (a < 0 || a > 2) fail(fmt::format("{}: an axis that is not x, y or z", where));
    if (w.ground != -1 && (!in_range(w.ground, d.coordinates.size()) || !d.coordinates[static_cast<std::size_t>(w.ground)].input))
      fail(fmt::format("{}.ground is no input", where));
  }
  for (int k : d.pair_candidates)
    if (!in_range(k, d.coordinates.size()) || !d.coordinates[static_cast<std::size_t>(k)].input)
      fail("pairs.candidates: not an input");
  if (d.pairs.empty()) fail("pairs.named: no pair (a model without wheels has one, of no rates)");
  for (const Pair& p : d.pairs) {
    if (p.coordinates.size() != d.wheels.size())
      fail(fmt::format("pairs.{}: {} rates for {} wheels", p.name, p.coordinates.size(), d.wheels.size()));
    for (int k : p.coordinates)
      if (!in_range(k, d.coordinates.size()) || !d.coordinates[static_cast<std::size_t>(k)].input)
        fail(fmt::format("pairs.{}: a rate that is not an input's", p.name));
  }
  if (!in_range(d.default_pair, d.pairs.size())) fail("pairs.default is no pair");
  const Settings& s = d.settings;
  const auto sized = [](const char* what, std::size_t size, std::size_t expected) {
    if (size != expected) fail(fmt::format("settings.{}: {} values for {}", what, size, expected));
  };
  sized("nominal", s.nominal_inputs.size(), static_cast<std::size_t>(d.input_count));
  sized("dependent_start", s.dependent_start.size(), static_cast<std::size_t>(n));
  sized("limits (lower)", s.lower.size(), static_cast<std::size_t>(n));
  sized("limits (upper)", s.upper.size(), static_cast<std::size_t>(n));
  sized("limits (velocity)", s.velocity_limit.size(), static_cast<std::size_t>(n));
  sized("branches", s.default_branch.size(), d.limbs.size());
  for (std::size_t k = 0; k < s.nominal_inputs.size(); ++k)
    if (!std::isfinite(s.nominal_inputs[k])) fail(fmt::format("settings.nominal.{} is not finite", d.coordinates[k].name));
  for (std::size_t k = 0; k < s.dependent_start.size(); ++k)
    if (!std::isfinite(s.dependent_start[k])) fail(fmt::format("settings.dependent_start.{} is not finite", d.coordinates[k].name));
  for (std::size_t k = 0; k < s.lower.size(); ++k)
    if (!(s.lower[k] <= s.upper[k]) || std::isnan(s.velocity_limit[k]) || s.velocity_limit[k] < 0)
      fail(fmt::format("settings.limits.{}: not a range (lower {}, upper {}, velocity {})", d.coordinates[k].name, s.lower[k],
                       s.upper[k], s.velocity_limit[k]));
  for (std::size_t l = 0; l < s.default_branch.size(); ++l)
    if (s.default_branch[l] < -1) fail(fmt::format("settings.branches.{} is not a branch", d.limbs[l].name));
}

}  // namespace wlx::generic
