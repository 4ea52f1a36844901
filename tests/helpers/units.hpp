// Unit factors the tests write their angles and rates with.
#pragma once

#include <numbers>

namespace wlx::test {

inline constexpr double kDeg = std::numbers::pi / 180;  // one degree in radians

}  // namespace wlx::test
