// Reproducible random configurations for the tests.
#pragma once

#include <wlx/gen/types.hpp>

#include <numbers>
#include <random>
#include <string_view>

namespace wlx::test {

// Every angle uniform in [-pi, pi], every length coordinate uniform in [-5, 5] m.
inline gen::Coordinates random_coordinates(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi), length(-5.0, 5.0);
  gen::Coordinates s;
  for (int i = 0; i < gen::kCoordinateCount; ++i)
    s(i) = gen::kCoordinateUnits[static_cast<std::size_t>(i)] == std::string_view("rad") ? angle(rng) : length(rng);
  return s;
}

inline gen::Coordinates random_rates(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> rate(-2.0, 2.0);
  gen::Coordinates u;
  for (int i = 0; i < gen::kCoordinateCount; ++i) u(i) = rate(rng);
  return u;
}

}  // namespace wlx::test
