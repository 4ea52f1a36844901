#include "wlx/settings.hpp"

#include "wlx/error.hpp"

#include <fmt/format.h>

#include <cmath>
#include <optional>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

#if __has_include(<wlx/gen/settings.hpp>)
// Compiled in: the generated tables, copied once.
Settings compiled_settings() {
  Settings s;
  s.nominal_inputs = gen::kNominalInputs;
  s.dependent_start = gen::kDependentStart;
  s.sweep_start = gen::kSweepStart;
  for (const auto& sw : gen::kIkSweeps)
    s.ik_sweeps.push_back({std::string(sw.id), std::string(gen::kCoordinateNames[static_cast<std::size_t>(sw.input)]), sw.from, sw.to,
                           sw.step, sw.degrees, sw.limb, sw.branch});
  s.weights = gen::kDefaultWeights;
  s.has_torque_limits = gen::kHasTorqueLimits;
  s.torque_limits = gen::kTorqueLimits;
  s.friction = gen::kContactFriction;
  s.lower = gen::kJointLower;
  s.upper = gen::kJointUpper;
  s.velocity_limit = gen::kJointVelocityLimit;
  s.default_branch = gen::kDefaultBranches;
  return s;
}
std::optional<Settings>& current() {
  static std::optional<Settings> s = compiled_settings();
  return s;
}
#else
// A plugin's: none until its loader hands over model.json's.
std::optional<Settings>& current() {
  static std::optional<Settings> s;
  return s;
}
#endif

void check_finite(const std::string& field, double v) {
  if (!std::isfinite(v)) throw Error(field, fmt::format("must be a finite number, got {}", v));
}

}  // namespace

const Settings& settings() {
  const auto& s = current();
  if (!s) throw Error("model", "this model's settings (its model.json) were not loaded: a plugin's loader sets them before any use");
  return *s;
}

bool has_settings() noexcept { return current().has_value(); }

void set_settings(const Settings& s) {
  for (const auto& info : gen::kParamInfo) check_finite(std::string(info.name), s.params.*info.member);
  for (int k = 0; k < gen::kInputCount; ++k) {
    check_finite(fmt::format("nominal.{}", gen::kCoordinateNames[static_cast<std::size_t>(k)]), s.nominal_inputs[static_cast<std::size_t>(k)]);
    check_finite(fmt::format("ik_sweeps.start.{}", gen::kCoordinateNames[static_cast<std::size_t>(k)]), s.sweep_start[static_cast<std::size_t>(k)]);
  }
  for (int k = 0; k < gen::kDependentCount; ++k)
    check_finite(fmt::format("start.{}", gen::kCoordinateNames[static_cast<std::size_t>(gen::kInputCount + k)]),
                 s.dependent_start[static_cast<std::size_t>(k)]);
  for (const auto& sw : s.ik_sweeps) {
    const std::string field = "ik_sweeps." + sw.id;
    bool input = false;
    for (int k = 0; k < gen::kInputCount; ++k) input = input || gen::kCoordinateNames[static_cast<std::size_t>(k)] == sw.input;
    if (!input) throw Error(field, fmt::format("its input '{}' is not one of the model's inputs", sw.input));
    if (sw.limb < 0 || sw.limb >= gen::kLimbCount) throw Error(field, "its limb is not one of the model's limbs");
    {
      const gen::ClosedFormInfo& cf = gen::kClosedForm[static_cast<std::size_t>(sw.limb)];
      const int count = cf.solve == nullptr ? 1 : cf.branches;
      if (sw.branch < -1 || sw.branch >= count)
        throw Error(field + ".branch", fmt::format("limb {} has branches 0 to {}, got {}", gen::kLimbs[static_cast<std::size_t>(sw.limb)].name,
                                                   count - 1, sw.branch));
    }
    check_finite(field + ".from", sw.from);
    check_finite(field + ".to", sw.to);
    if (!(std::isfinite(sw.step) && sw.step > 0)) throw Error(field + ".step", fmt::format("must be positive, got {}", sw.step));
  }
  for (std::size_t a = 0; a < s.weights.size(); ++a) {
    const std::string actuator(gen::kActuatorNames[a]);
    if (!(std::isfinite(s.weights[a]) && s.weights[a] > 0))
      throw Error("dynamics.weights." + actuator, fmt::format("must be positive, got {}", s.weights[a]));
    if (s.has_torque_limits && !(std::isfinite(s.torque_limits[a]) && s.torque_limits[a] > 0))
      throw Error("dynamics.torque_limits." + actuator, fmt::format("must be positive, got {}", s.torque_limits[a]));
  }
  for (std::size_t c = 0; c < s.friction.size(); ++c)
    if (!(std::isfinite(s.friction[c]) && s.friction[c] >= 0))
      throw Error(fmt::format("contacts.friction ({})", gen::kContacts[c].name), fmt::format("must be non-negative, got {}", s.friction[c]));
  for (int k = 0; k < gen::kCoordinateCount; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    const std::string field = fmt::format("limits.{}", gen::kCoordinateNames[kk]);
    if (std::isnan(s.lower[kk]) || std::isnan(s.upper[kk]) || !(s.lower[kk] < s.upper[kk]))
      throw Error(field, fmt::format("lower ({}) must be below upper ({})", s.lower[kk], s.upper[kk]));
    if (!(std::isfinite(s.velocity_limit[kk]) && s.velocity_limit[kk] >= 0))
      throw Error(field + ".velocity", fmt::format("must be positive (0: none), got {}", s.velocity_limit[kk]));
  }
  for (int l = 0; l < gen::kLimbCount; ++l) {
    const int b = s.default_branch[static_cast<std::size_t>(l)];
    const gen::ClosedFormInfo& cf = gen::kClosedForm[static_cast<std::size_t>(l)];
    const int count = cf.solve == nullptr ? 1 : cf.branches;
    if (b < -1 || b >= count)
      throw Error(fmt::format("limbs.{}.branch", gen::kLimbs[static_cast<std::size_t>(l)].name),
                  fmt::format("the limb has branches 0 to {}, got {}", count - 1, b));
  }
#if !__has_include(<wlx/gen/settings.hpp>)
  // The generated Params' defaults read these (params.hpp, --data-at-run-time): Params{} is the file's.
  for (std::size_t k = 0; k < gen::kParamInfo.size(); ++k) gen::detail::param_defaults()[k] = s.params.*gen::kParamInfo[k].member;
#endif
  current() = s;
}

WLX_MODEL_NAMESPACE_END
