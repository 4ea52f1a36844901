#include "per_model.hpp"
#include "input.hpp"

#include "bounded_input.hpp"
#include "limits.hpp"
#include "scenario_io.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <wlx/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

WLX_COMMANDS_BEGIN

namespace {

std::vector<std::string> dependent_names() {
  std::vector<std::string> v;
  for (int k = kInputCount; k < kCoordinateCount; ++k) v.emplace_back(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
  return v;
}

std::string type_name(const nlohmann::json& v) { return v.type_name(); }

bool is_angle_param(const std::string& name) {
  for (const auto& info : gen::kParamInfo)
    if (info.name == name) return info.kind == gen::ParamKind::angle;
  return false;
}

}  // namespace

const char* method_name(IkMethod method) { return method == IkMethod::closed_form ? "closed-form" : "newton"; }

std::array<IkMethod, kLimbCount> limb_methods(IkMethod requested) {
  std::array<IkMethod, kLimbCount> methods{};
  for (Limb limb : kLimbs)
    methods[static_cast<std::size_t>(limb)] =
        requested == IkMethod::closed_form && has_closed_form(limb) ? IkMethod::closed_form : IkMethod::newton;
  return methods;
}

std::string overall_method(const std::array<IkMethod, kLimbCount>& methods, IkMethod requested) {
  if (methods.empty()) return method_name(requested);
  for (IkMethod m : methods)
    if (m != methods.front()) return "mixed";
  return method_name(methods.front());
}

std::string methods_in_words(const std::array<IkMethod, kLimbCount>& methods) {
  std::vector<std::string> by_newton;
  for (Limb limb : kLimbs)
    if (methods[static_cast<std::size_t>(limb)] == IkMethod::newton) by_newton.emplace_back(limb_name(limb));
  if (by_newton.empty()) return "the closed-form IK";
  if (by_newton.size() == methods.size()) {
    for (Limb limb : kLimbs)
      if (has_closed_form(limb)) return "Newton's method";  // asked for: the closed form was there
    return "Newton's method (wlx-gen derived no closed form for any limb)";
  }
  return fmt::format("the closed-form IK, and Newton's method for the limbs without a closed form ({})",
                     fmt::join(by_newton, ", "));
}

Params parse_params(const nlohmann::json& object, Params params) {
  if (!object.is_object()) throw Error("params", fmt::format("must be an object, got {}", type_name(object)));
  std::vector<std::string> names;
  for (const auto& info : gen::kParamInfo) names.emplace_back(info.name);
  reject_unknown_keys(object, names, "params.");
  // The scenario files' grammar here too: an angle parameter may be {"deg": x}, anything else is SI.
  for (const auto& [key, value] : object.items())
    *find_param(params, key) = si_value(value, "params." + key, quantity_of(is_angle_param(key)));
  check_param_bounds(params, "params.");
  try {
    Model check(params);
  } catch (const Error& e) {
    throw Error("params." + e.field(), e.reason());
  }
  return params;
}

IkRequest parse_ik_request(const nlohmann::json& j, const Params& base) {
  if (!j.is_object()) throw Error("", fmt::format("expected a JSON object, got {}", type_name(j)));
  auto valid = input_names();
  for (const char* k : {"params", "method", "branch", "start"}) valid.emplace_back(k);
  reject_unknown_keys(j, valid, "");
  IkRequest r;
  r.params = base;
  r.s = nominal_inputs();
  for (int k = 0; k < kInputCount; ++k) {
    const std::string name(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    if (j.contains(name)) {
      r.s(k) = si_value(j.at(name), name, quantity_of(is_angle(k)));  // the scenario files' grammar: SI or {"deg": x}
      check_input_bound(k, r.s(k), name);
    }
  }
  if (j.contains("params")) r.params = parse_params(j.at("params"), base);
  if (j.contains("method")) {
    const auto& m = j.at("method");
    if (m == "closed-form") r.method = IkMethod::closed_form;
    else if (m == "newton") r.method = IkMethod::newton;
    else throw Error("method", fmt::format("must be \"closed-form\" or \"newton\", got {}", excerpt(m)));
  }
  if (j.contains("branch")) {
    const auto& b = j.at("branch");
    const auto set = [&](Limb limb, const nlohmann::json& v, const std::string& key) {
      if (!v.is_number_integer()) throw Error(key, fmt::format("must be an integer, got {}", excerpt(v)));
      // Compared as 64-bit integers: a conversion to int first would wrap 4294967297 to 1.
      const auto count = static_cast<std::int64_t>(branch_count(limb));
      const bool in_range = v.is_number_unsigned() ? v.get<std::uint64_t>() < static_cast<std::uint64_t>(count)
                                                   : v.get<std::int64_t>() >= 0 && v.get<std::int64_t>() < count;
      if (!in_range)
        throw Error(key, fmt::format("{} has branches 0 to {}, got {}", limb_name(limb), branch_count(limb) - 1, excerpt(v)));
      r.branches.limb[static_cast<std::size_t>(limb)] = static_cast<int>(v.get<std::int64_t>());
    };
    std::vector<std::string> limbs;
    for (const auto& l : gen::kLimbs) limbs.emplace_back(l.name);
    if (b.is_object()) {
      reject_unknown_keys(b, limbs, "branch.");
      for (std::size_t k = 0; k < limbs.size(); ++k)
        if (b.contains(limbs[k])) set(kLimbs[k], b.at(limbs[k]), "branch." + limbs[k]);
    } else {
      for (Limb limb : kLimbs) set(limb, b, "branch");
    }
  }
  if (j.contains("start")) {
    const auto& st = j.at("start");
    if (!st.is_object()) throw Error("start", fmt::format("must be an object of dependent joints, got {}", type_name(st)));
    reject_unknown_keys(st, dependent_names(), "start.");
    for (const auto& [key, value] : st.items()) {
      const int k = coordinate_index(key);
      r.start.emplace_back(k, si_value(value, "start." + key, quantity_of(is_angle(k))));
      // Newton's starting guess: for every limb with "method": "newton", else for the limbs that
      // have no closed form (which Newton's method solves whatever the method asked).
      if (r.method == IkMethod::newton) continue;
      for (Limb limb : kLimbs) {
        const LimbBlock block = limb_block(limb);
        if (has_closed_form(limb) && std::find(block.joints.begin(), block.joints.begin() + block.size, k) != block.joints.begin() + block.size)
          throw Error("start." + key,
                      fmt::format("is Newton's starting guess, and {} is solved by its closed form, which takes none: give "
                                  "\"method\": \"newton\" to solve it by Newton's method from this start",
                                  limb_name(limb)));
      }
    }
  }
  return r;
}

WLX_COMMANDS_END
