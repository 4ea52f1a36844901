#include "wlx/parameter_checks.hpp"

#include "wlx/error.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string>

namespace wlx {

bool parameter_kind_of(std::string_view name, ParameterKind& kind) noexcept {
  constexpr std::array<std::pair<std::string_view, ParameterKind>, 7> kKinds{{{"length", ParameterKind::length},
                                                                                {"mass", ParameterKind::mass},
                                                                                {"inertia", ParameterKind::inertia},
                                                                                {"gravity", ParameterKind::gravity},
                                                                                {"offset", ParameterKind::offset},
                                                                                {"angle", ParameterKind::angle},
                                                                                {"other", ParameterKind::other}}};
  for (const auto& [text, k] : kKinds)
    if (text == name) {
      kind = k;
      return true;
    }
  return false;
}

void check_parameter(std::string_view name_view, ParameterKind kind, double v) {
  const std::string name(name_view);
  if (!std::isfinite(v)) throw Error(name, fmt::format("must be a finite number, got {}", v));
  switch (kind) {
    case ParameterKind::length:
      if (!(v > 0)) throw Error(name, fmt::format("a length must be positive, got {} m", v));
      break;
    case ParameterKind::mass:
      if (!(v > 0)) throw Error(name, fmt::format("a mass must be positive, got {} kg", v));
      break;
    case ParameterKind::inertia:
      if (!(v > 0)) throw Error(name, fmt::format("a principal inertia must be positive, got {} kg*m^2", v));
      break;
    case ParameterKind::gravity:
      if (!(v >= 0)) throw Error(name, fmt::format("gravity must be non-negative, got {} m/s^2", v));
      break;
    case ParameterKind::offset:
    case ParameterKind::angle:
    case ParameterKind::other: break;
  }
}

void check_principal_inertias(const std::array<double, 3>& I, const std::array<std::string_view, 3>& names) {
  // A rigid body's principal moments obey the triangle inequality (each at most the sum of the others).
  for (std::size_t k = 0; k < 3; ++k)
    if (I[k] > I[(k + 1) % 3] + I[(k + 2) % 3] * (1 + 1e-12))
      throw Error(std::string(names[k]),
                  fmt::format("{} kg*m^2 exceeds the sum of the other two principal inertias ({} + {}): no rigid body "
                              "has such an inertia",
                              I[k], I[(k + 1) % 3], I[(k + 2) % 3]));
}

}  // namespace wlx
