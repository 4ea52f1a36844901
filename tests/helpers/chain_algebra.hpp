// 3-vectors, rotation matrices and poses generic in the scalar (double or Jet), for the tests'
// independent reference chains.
#pragma once

#include "jet.hpp"

#include <wlx/gen/params.hpp>
#include <wlx/gen/types.hpp>

#include <array>
#include <cmath>

namespace wlx::test {

template <class T> using V3 = std::array<T, 3>;
template <class T> using M3 = std::array<std::array<T, 3>, 3>;

template <class T> M3<T> mul(const M3<T>& a, const M3<T>& b) {
  M3<T> m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
  return m;
}
template <class T> V3<T> mul(const M3<T>& a, const V3<T>& x) {
  return {a[0][0] * x[0] + a[0][1] * x[1] + a[0][2] * x[2], a[1][0] * x[0] + a[1][1] * x[1] + a[1][2] * x[2],
          a[2][0] * x[0] + a[2][1] * x[1] + a[2][2] * x[2]};
}
template <class T> V3<T> add(const V3<T>& a, const V3<T>& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
template <class T> T dot(const V3<T>& a, const V3<T>& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

using std::cos;
using std::sin;
template <class T> M3<T> Rx(T a) { return {{{T(1), T(0), T(0)}, {T(0), cos(a), -sin(a)}, {T(0), sin(a), cos(a)}}}; }
template <class T> M3<T> Ry(T a) { return {{{cos(a), T(0), sin(a)}, {T(0), T(1), T(0)}, {-sin(a), T(0), cos(a)}}}; }
template <class T> M3<T> Rz(T a) { return {{{cos(a), -sin(a), T(0)}, {sin(a), cos(a), T(0)}, {T(0), T(0), T(1)}}}; }

template <class T> struct Pose {
  M3<T> R;
  V3<T> r;
};

// Coordinates moving along s + t u, as jets.
inline std::array<Jet, gen::kCoordinateCount> along(const gen::Coordinates& s, const gen::Coordinates& u) {
  std::array<Jet, gen::kCoordinateCount> out;
  for (int i = 0; i < gen::kCoordinateCount; ++i) out[static_cast<std::size_t>(i)] = Jet(s(i), u(i), 0);
  return out;
}

// The angular velocity and acceleration of a rotation moving as a jet: omega^ = Rdot R^T and
// alpha^ = d/dt omega^ = Rddot R^T + Rdot Rdot^T, read off the skew-symmetric matrices.
struct AngularRates {
  V3<double> omega, alpha;
};
inline AngularRates angular_rates(const M3<Jet>& R) {
  M3<double> W{}, Wdot{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        W[i][j] += R[i][k].d * R[j][k].v;
        Wdot[i][j] += R[i][k].dd * R[j][k].v + R[i][k].d * R[j][k].d;
      }
  return {{W[2][1], W[0][2], W[1][0]}, {Wdot[2][1], Wdot[0][2], Wdot[1][0]}};
}

}  // namespace wlx::test
