// A second-order univariate Taylor number: f(t) = v + d t + dd t^2 / 2 around t = 0.
// Evaluating a function of s(t) = s + t u with jets gives the function, its directional
// derivative J u, and the second derivative u^T H u = (d/dt J) u exactly (to rounding), which is
// how the tests check Jacobians and convective terms without finite differences.
#pragma once

#include <cmath>

namespace wlx::test {

struct Jet {
  double v = 0, d = 0, dd = 0;
  Jet() = default;
  Jet(double value) : v(value) {}  // NOLINT: constants convert implicitly
  Jet(double value, double first, double second) : v(value), d(first), dd(second) {}
};

inline Jet operator+(Jet a, Jet b) { return {a.v + b.v, a.d + b.d, a.dd + b.dd}; }
inline Jet operator-(Jet a, Jet b) { return {a.v - b.v, a.d - b.d, a.dd - b.dd}; }
inline Jet operator-(Jet a) { return {-a.v, -a.d, -a.dd}; }
inline Jet operator*(Jet a, Jet b) { return {a.v * b.v, a.d * b.v + a.v * b.d, a.dd * b.v + 2 * a.d * b.d + a.v * b.dd}; }
inline Jet operator/(Jet a, double k) { return {a.v / k, a.d / k, a.dd / k}; }
inline Jet operator/(Jet a, Jet b) {  // a * (1 / b), with (1/b)' = -b'/b^2, (1/b)'' = 2 b'^2/b^3 - b''/b^2
  const double r = 1 / b.v;
  return a * Jet{r, -b.d * r * r, (2 * b.d * b.d * r - b.dd) * r * r};
}
inline Jet& operator+=(Jet& a, Jet b) { return a = a + b; }
inline Jet& operator-=(Jet& a, Jet b) { return a = a - b; }
inline Jet& operator*=(Jet& a, Jet b) { return a = a * b; }
inline Jet& operator/=(Jet& a, Jet b) { return a = a / b; }
inline bool operator<(Jet a, Jet b) { return a.v < b.v; }
inline bool operator>(Jet a, Jet b) { return a.v > b.v; }
inline bool operator==(Jet a, Jet b) { return a.v == b.v && a.d == b.d && a.dd == b.dd; }
inline bool operator!=(Jet a, Jet b) { return !(a == b); }
inline Jet abs(Jet a) { return a.v < 0 ? -a : a; }  // away from 0, where |x| has derivatives
inline Jet sqrt(Jet a) {
  const double r = std::sqrt(a.v);
  return {r, a.d / (2 * r), a.dd / (2 * r) - a.d * a.d / (4 * r * r * r)};
}
inline Jet sin(Jet a) {
  const double s = std::sin(a.v), c = std::cos(a.v);
  return {s, c * a.d, c * a.dd - s * a.d * a.d};
}
inline Jet cos(Jet a) {
  const double s = std::sin(a.v), c = std::cos(a.v);
  return {c, -s * a.d, -s * a.dd - c * a.d * a.d};
}

}  // namespace wlx::test
