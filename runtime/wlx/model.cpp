#include "wlx/model.hpp"

#include "wlx/error.hpp"

#include <fmt/format.h>

#include <cmath>

#include <Eigen/Core>

WLX_MODEL_NAMESPACE_BEGIN

Model::Model(const Params& params) : params_(params) {
  // Each parameter's kind (from the model file) says which values make sense.
  for (const auto& info : gen::kParamInfo) {
    const double v = params_.*info.member;
    const std::string name(info.name);
    if (!std::isfinite(v)) throw Error(name, fmt::format("must be a finite number, got {}", v));
    switch (info.kind) {
      case gen::ParamKind::length:
        if (!(v > 0)) throw Error(name, fmt::format("a length must be positive, got {} m", v));
        break;
      case gen::ParamKind::mass:
        if (!(v > 0)) throw Error(name, fmt::format("a mass must be positive, got {} kg", v));
        break;
      case gen::ParamKind::inertia:
        if (!(v > 0)) throw Error(name, fmt::format("a principal inertia must be positive, got {} kg*m^2", v));
        break;
      case gen::ParamKind::gravity:
        if (!(v >= 0)) throw Error(name, fmt::format("gravity must be non-negative, got {} m/s^2", v));
        break;
      case gen::ParamKind::offset:
      case gen::ParamKind::angle:
      case gen::ParamKind::other: break;
    }
  }
  const auto name_of = [](double Params::*member) {
    for (const auto& info : gen::kParamInfo)
      if (info.member == member) return std::string(info.name);
    return std::string("?");
  };
  for (int b = 0; b < gen::kBodyCount; ++b) {
    const auto& mass = gen::kBodyMass[static_cast<std::size_t>(b)];
    const double I[3] = {params_.*mass.inertia[0], params_.*mass.inertia[1], params_.*mass.inertia[2]};
    // A rigid body's principal moments obey the triangle inequality (each at most the sum of the others).
    for (int k = 0; k < 3; ++k)
      if (I[k] > I[(k + 1) % 3] + I[(k + 2) % 3] * (1 + 1e-12))
        throw Error(name_of(mass.inertia[static_cast<std::size_t>(k)]),
                    fmt::format("{} kg*m^2 exceeds the sum of the other two principal inertias ({} + {}): no rigid body "
                                "has such an inertia",
                                I[k], I[(k + 1) % 3], I[(k + 2) % 3]));
    total_mass_ += params_.*mass.mass;
  }
}

int coordinate_index(std::string_view name) noexcept {
  for (int k = 0; k < gen::kCoordinateCount; ++k)
    if (gen::kCoordinateNames[static_cast<std::size_t>(k)] == name) return k;
  return -1;
}

int frame_index(std::string_view name) noexcept {
  for (int k = 0; k < gen::kFrameCount; ++k)
    if (gen::kFrameNames[static_cast<std::size_t>(k)] == name) return k;
  return -1;
}

double* find_param(Params& params, std::string_view name) noexcept {
  for (const auto& info : gen::kParamInfo)
    if (info.name == name) return &(params.*info.member);
  return nullptr;
}

Coordinates nominal_inputs() {
  Coordinates s;
  const Settings& settings_in_use = settings();
  for (int k = 0; k < kInputCount; ++k) s(k) = settings_in_use.nominal_inputs[static_cast<std::size_t>(k)];
  for (int k = kInputCount; k < kCoordinateCount; ++k) s(k) = settings_in_use.dependent_start[static_cast<std::size_t>(k - kInputCount)];
  return s;
}

WLX_MODEL_NAMESPACE_END
