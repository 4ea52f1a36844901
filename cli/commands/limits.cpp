#include "per_model.hpp"
#include "limits.hpp"

#include <fmt/format.h>
#include <wlx/error.hpp>

#include <cmath>
#include <string_view>

WLX_COMMANDS_BEGIN

bool is_angle(int coordinate) { return gen::kCoordinateUnits[static_cast<std::size_t>(coordinate)] == std::string_view("rad"); }

std::vector<std::string> input_names() {
  std::vector<std::string> v;
  for (int k = 0; k < kInputCount; ++k) v.emplace_back(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
  return v;
}

void check_param_bounds(const Params& params, const std::string& prefix) {
  for (const auto& info : gen::kParamInfo) {
    const double v = params.*info.member;
    const std::string_view unit = info.unit;
    double bound = 0;
    const char* what = "";
    if (unit == "m") bound = kMaxLength, what = "a length";
    else if (unit == "kg") bound = kMaxMass, what = "a mass";
    else if (unit == "kg*m^2") bound = kMaxInertia, what = "an inertia";
    else if (info.name == "g") bound = kMaxGravity, what = "gravity";
    else continue;
    if (v > bound)
      throw Error(prefix + std::string(info.name),
                  fmt::format("{} of {:g} {} is beyond the bound of {:g} {} for a machine", what, v, unit, bound, unit));
  }
}

void check_input_bound(int coordinate, double value, const std::string& field) {
  const bool angle = is_angle(coordinate);
  const double bound = angle ? kMaxAngle : kMaxPosition;
  if (std::abs(value) > bound)
    throw Error(field, fmt::format("|{:g}| {} is beyond the bound of {:g} {}", value, angle ? "rad" : "m", bound,
                                   angle ? "rad" : "m"));
}

void check_rate_bound(int coordinate, double rate, const std::string& field) {
  const bool angle = is_angle(coordinate);
  const double bound = angle ? kMaxAngularRate : kMaxLinearRate;
  if (std::abs(rate) > bound)
    throw Error(field, fmt::format("a rate of |{:g}| {} is beyond the bound of {:g} {}", rate, angle ? "rad/s" : "m/s",
                                   bound, angle ? "rad/s" : "m/s"));
}

WLX_COMMANDS_END
