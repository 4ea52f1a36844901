#include "wlx/model.hpp"

#include "wlx/error.hpp"

#include <fmt/format.h>

#include <cmath>

#include <Eigen/Core>

namespace wlx {

namespace {

bool is_length(std::string_view name) {
  for (std::string_view n : {"cxd", "cyd", "thighD", "legD", "wl", "w", "cabin_height"})
    if (n == name) return true;
  return false;
}

}  // namespace

Model::Model(const Params& params) : params_(params) {
  for (const auto& info : gen::kParamInfo) {
    const double v = params_.*info.member;
    if (!std::isfinite(v)) throw Error(std::string(info.name), fmt::format("must be a finite number, got {}", v));
    if (is_length(info.name) && !(v > 0))
      throw Error(std::string(info.name), fmt::format("a length must be positive, got {} m", v));
  }
  if (!(params_.g >= 0)) throw Error("g", fmt::format("gravity must be non-negative, got {} m/s^2", params_.g));
  for (int b = 0; b < gen::kBodyCount; ++b) {
    const auto& mass = gen::kBodyMass[static_cast<std::size_t>(b)];
    const std::string body(gen::kBodyNames[static_cast<std::size_t>(b)]);
    const double m = params_.*mass.mass;
    if (!(m > 0)) throw Error("m_" + body, fmt::format("a mass must be positive, got {} kg", m));
    const double I[3] = {params_.*mass.inertia[0], params_.*mass.inertia[1], params_.*mass.inertia[2]};
    const char* axes[3] = {"Ixx_", "Iyy_", "Izz_"};
    for (int k = 0; k < 3; ++k)
      if (!(I[k] > 0))
        throw Error(axes[k] + body, fmt::format("a principal inertia must be positive, got {} kg*m^2", I[k]));
    // A rigid body's principal moments obey the triangle inequality (each at most the sum of the others).
    for (int k = 0; k < 3; ++k)
      if (I[k] > I[(k + 1) % 3] + I[(k + 2) % 3] * (1 + 1e-12))
        throw Error(axes[k] + body, fmt::format("{} kg*m^2 exceeds the sum of the other two principal inertias "
                                                "({} + {}): no rigid body has such an inertia",
                                                I[k], I[(k + 1) % 3], I[(k + 2) % 3]));
    total_mass_ += m;
  }
  // Structural zeros: a column that is zero at a generic configuration is zero everywhere (the
  // generated code writes only its non-zero entries). Generic: irrational-looking values.
  Coordinates s, sdot;
  for (int k = 0; k < gen::kCoordinateCount; ++k) {
    s(k) = 0.1 + 0.7071067811865476 * std::sin(1.0 + 3.0 * k);
    sdot(k) = 0.3 + 0.5 * std::cos(2.0 + 5.0 * k);
  }
  gen::BodyJacobians Jv, Jw;
  gen::bodies(s, sdot, params_, nullptr, nullptr, &Jv, &Jw, nullptr, nullptr);
  for (int b = 0; b < gen::kBodyCount; ++b)
    for (int j = 0; j < gen::kCoordinateCount; ++j)
      if (Jv[static_cast<std::size_t>(b)].col(j).any() || Jw[static_cast<std::size_t>(b)].col(j).any())
        body_columns_[static_cast<std::size_t>(b)].push_back(j);
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
  Coordinates s = Coordinates::Zero();
  namespace c = gen::coord;
  s(c::z_C) = 2.0;
  s(c::x_Fl) = 3.5;
  s(c::y_Fl) = 1.5;
  s(c::x_Fr) = 3.5;
  s(c::y_Fr) = -1.5;
  s(c::z_Wr) = 0.05;
  return s;
}

}  // namespace wlx
