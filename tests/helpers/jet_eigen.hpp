// Jet as an Eigen scalar (Eigen::Matrix<Jet, ...>), for the generated functions' Scalar template.
#pragma once

#include "jet.hpp"

#include <Eigen/Core>

#include <limits>

namespace Eigen {
template <>
struct NumTraits<wlx::test::Jet> : GenericNumTraits<double> {
  using Real = wlx::test::Jet;
  using NonInteger = wlx::test::Jet;
  using Literal = wlx::test::Jet;
  using Nested = wlx::test::Jet;
  enum { IsComplex = 0, IsInteger = 0, IsSigned = 1, RequireInitialization = 1, ReadCost = 3, AddCost = 3, MulCost = 9 };
};
}  // namespace Eigen

namespace wlx::test {
inline bool isfinite(Jet a) { return std::isfinite(a.v) && std::isfinite(a.d) && std::isfinite(a.dd); }
}  // namespace wlx::test
