// The steps of Newton's method on one limb's square block J of dPhi/ds (its rows against its own
// dependent joints) and residual r, at the limb's fixed size N (gen::kMaxLimbSize: smaller limbs
// are padded with a unit diagonal).
//
// Why here and not in ik.cpp: the decompositions they take (a full-pivoting LU with its condition
// estimate, an LDLT, a Householder QR of a 2N x N matrix) were a seventh of each model's runtime
// compile, once per model although they depend on nothing but N. They are defined below for every
// N, and compiled once, into wlx::numerics, for N = 1 to kPrecompiledLimbSize (limb_steps.cpp); the
// extern declarations keep every model's runtime from compiling them again. Each model calls them
// at its own fixed size, so Newton's method keeps its fixed-size speed and allocates nothing (on
// dynamic-size matrices instead it was 40% slower). A limb of more joints compiles them where it
// is used, as before.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/QR>

#include <cmath>

namespace wlx::limb_steps {

template <int N>
using Square = Eigen::Matrix<double, N, N>;
template <int N>
using Column = Eigen::Matrix<double, N, 1>;

// The largest N compiled once: legs of three to six joints, levers of one or two (each size
// costs wlx's own build about 6 s of CPU at -O3, and saves each model's runtime as much).
inline constexpr int kPrecompiledLimbSize = 6;

// The Newton step -J^-1 r into `step` when J has full rank and its reciprocal condition estimate
// is above 1e-12, by a full-pivoting LU; false (step untouched) otherwise.
template <int N>
bool newton_step(const Square<N>& J, const Column<N>& r, Column<N>& step);

// The step of the regularized normal equations (J^T J + mu I) dx = -J^T r, by LDLT: the
// backtracking method's step at a singular pose.
template <int N>
Column<N> regularized_step(const Square<N>& J, const Column<N>& r, double mu);

// Levenberg-Marquardt's step: the least-squares solution of [J; sqrt(mu) I] dx = [-r; 0], by QR
// (the normal equations would square J's condition number, 1e6 at the thesis' worst poses).
template <int N>
Column<N> damped_step(const Square<N>& J, const Column<N>& r, double mu);

template <int N>
bool newton_step(const Square<N>& J, const Column<N>& r, Column<N>& step) {
  const Eigen::FullPivLU<Square<N>> lu(J);
  // Both tests: the condition estimate solves with the LU, which for a J of lower rank leaves the
  // null directions at zero and so estimates a moderate inverse; the rank test sees that J.
  if (!lu.isInvertible() || !(lu.rcond() > 1e-12)) return false;
  step = -lu.solve(r);
  return true;
}

template <int N>
Column<N> regularized_step(const Square<N>& J, const Column<N>& r, double mu) {
  return -(J.transpose() * J + mu * Square<N>::Identity()).ldlt().solve(J.transpose() * r);
}

template <int N>
Column<N> damped_step(const Square<N>& J, const Column<N>& r, double mu) {
  Eigen::Matrix<double, 2 * N, N> stacked;
  stacked << J, std::sqrt(mu) * Square<N>::Identity();
  Eigen::Matrix<double, 2 * N, 1> rhs;
  rhs << -r, Column<N>::Zero();
  return stacked.householderQr().solve(rhs);
}

// Compiled once, in limb_steps.cpp, for N = 1 to kPrecompiledLimbSize; where nothing links
// wlx::numerics (the viewer's WebAssembly module defines WLX_LIMB_STEPS_HERE), where they are used.
#ifndef WLX_LIMB_STEPS_HERE
#define WLX_LIMB_STEPS_EXTERN(N)                                                                      \
  extern template bool newton_step<N>(const Square<N>&, const Column<N>&, Column<N>&);               \
  extern template Column<N> regularized_step<N>(const Square<N>&, const Column<N>&, double);          \
  extern template Column<N> damped_step<N>(const Square<N>&, const Column<N>&, double);
WLX_LIMB_STEPS_EXTERN(1)
WLX_LIMB_STEPS_EXTERN(2)
WLX_LIMB_STEPS_EXTERN(3)
WLX_LIMB_STEPS_EXTERN(4)
WLX_LIMB_STEPS_EXTERN(5)
WLX_LIMB_STEPS_EXTERN(6)
#undef WLX_LIMB_STEPS_EXTERN
#endif

}  // namespace wlx::limb_steps
