#include "wlx/model.hpp"

#include "wlx/error.hpp"
#include "wlx/parameter_checks.hpp"

#include <fmt/format.h>

#include <cmath>

#include <Eigen/Core>

WLX_MODEL_NAMESPACE_BEGIN

namespace {
ParameterKind kind_of(gen::ParamKind kind) noexcept {
  switch (kind) {
    case gen::ParamKind::length: return ParameterKind::length;
    case gen::ParamKind::offset: return ParameterKind::offset;
    case gen::ParamKind::angle: return ParameterKind::angle;
    case gen::ParamKind::mass: return ParameterKind::mass;
    case gen::ParamKind::inertia: return ParameterKind::inertia;
    case gen::ParamKind::gravity: return ParameterKind::gravity;
    case gen::ParamKind::other: break;
  }
  return ParameterKind::other;
}

std::string_view parameter_name(double Params::*member) {
  for (const auto& info : gen::kParamInfo)
    if (info.member == member) return info.name;
  return "?";
}
}  // namespace

Model::Model(const Params& params) : params_(params) {
  // Each parameter's kind (from the model file) says which values make sense.
  for (const auto& info : gen::kParamInfo) check_parameter(info.name, kind_of(info.kind), params_.*info.member);
  for (int b = 0; b < gen::kBodyCount; ++b) {
    const auto& mass = gen::kBodyMass[static_cast<std::size_t>(b)];
    check_principal_inertias({params_.*mass.inertia[0], params_.*mass.inertia[1], params_.*mass.inertia[2]},
                             {parameter_name(mass.inertia[0]), parameter_name(mass.inertia[1]), parameter_name(mass.inertia[2])});
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
