// The steps of Newton's method on one limb's square block J of dPhi/ds (its rows against its own
// dependent joints) and residual r, at the limb's fixed size N (gen::kMaxLimbSize: smaller limbs
// are padded with a unit diagonal).
//
// Written out as loops on the coefficients, not as Eigen's decompositions: at sizes of one to six
// Eigen unrolls its FullPivLU, LDLT and Householder QR into code that cost about 6 s of CPU per
// size to compile (36 s for sizes 1 to 6 at -O3, 73 s under the sanitizers), for a few dozen
// multiply-adds. These loops compile in a fraction of a second for any N, so every model's
// runtime compiles its own size where it calls them; nothing is precompiled. The steps keep their
// fixed size and allocate nothing.
#pragma once

#include "wlx/small_dense.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace wlx::limb_steps {

template <int N>
using Square = Eigen::Matrix<double, N, N>;
template <int N>
using Column = Eigen::Matrix<double, N, 1>;

// An LU factorization with complete pivoting, P J Q = L U (L unit lower triangular), in place.
template <int N>
struct FullPivotLu {
  double lu[N][N];
  int row[N];     // row[k]: J's row at position k
  int column[N];  // column[k]: J's column at position k
  bool full_rank = true;

  // Full rank as Eigen's FullPivLU::isInvertible() decides it: every pivot above N machine
  // epsilons of the largest pivot, judged once all are known (a later pivot may be the largest).
  explicit FullPivotLu(const Square<N>& J) {
    for (int i = 0; i < N; ++i) {
      row[i] = column[i] = i;
      for (int j = 0; j < N; ++j) lu[i][j] = J(i, j);
    }
    for (int k = 0; k < N; ++k) {
      int p = k, q = k;
      for (int i = k; i < N; ++i)
        for (int j = k; j < N; ++j)
          if (std::abs(lu[i][j]) > std::abs(lu[p][q])) p = i, q = j;
      // A zero pivot ends the elimination (nothing to divide by); so does a NaN (`!(x > 0)`).
      if (!(std::abs(lu[p][q]) > 0) || !std::isfinite(lu[p][q])) {
        full_rank = false;
        return;
      }
      if (p != k) {
        std::swap(row[p], row[k]);
        for (int j = 0; j < N; ++j) std::swap(lu[p][j], lu[k][j]);
      }
      if (q != k) {
        std::swap(column[q], column[k]);
        for (int i = 0; i < N; ++i) std::swap(lu[i][q], lu[i][k]);
      }
      for (int i = k + 1; i < N; ++i) {
        lu[i][k] /= lu[k][k];
        for (int j = k + 1; j < N; ++j) lu[i][j] -= lu[i][k] * lu[k][j];
      }
    }
    double largest = 0;
    for (int k = 0; k < N; ++k) largest = std::max(largest, std::abs(lu[k][k]));
    for (int k = 0; k < N; ++k)
      if (!(std::abs(lu[k][k]) > N * std::numeric_limits<double>::epsilon() * largest)) full_rank = false;
  }

  // x = J^-1 b (full rank only).
  void solve(const double (&b)[N], double (&x)[N]) const {
    double y[N];
    for (int i = 0; i < N; ++i) {
      y[i] = b[row[i]];
      for (int j = 0; j < i; ++j) y[i] -= lu[i][j] * y[j];
    }
    for (int i = N - 1; i >= 0; --i) {
      for (int j = i + 1; j < N; ++j) y[i] -= lu[i][j] * y[j];
      y[i] /= lu[i][i];
    }
    for (int k = 0; k < N; ++k) x[column[k]] = y[k];
  }
};

// The Newton step -J^-1 r into `step` when J has full rank and its reciprocal condition number in
// the 1-norm is above 1e-12, by an LU with complete pivoting; false (step untouched) otherwise.
// The condition number is exact (||J||_1 ||J^-1||_1 from J's inverse, N solves), where Eigen's
// rcond() estimates it from below: the test is, if anything, the stricter.
template <int N>
bool newton_step(const Square<N>& J, const Column<N>& r, Column<N>& step) {
  const FullPivotLu<N> lu(J);
  if (!lu.full_rank) return false;
  double norm = 0, inverse_norm = 0;
  for (int j = 0; j < N; ++j) {
    double e[N] = {}, column[N];
    e[j] = 1;
    lu.solve(e, column);
    double sum = 0, inverse_sum = 0;
    for (int i = 0; i < N; ++i) {
      sum += std::abs(J(i, j));
      inverse_sum += std::abs(column[i]);
    }
    norm = std::max(norm, sum);
    inverse_norm = std::max(inverse_norm, inverse_sum);
  }
  if (!(1.0 / (norm * inverse_norm) > 1e-12)) return false;
  double b[N], x[N];
  for (int i = 0; i < N; ++i) b[i] = -r(i);
  lu.solve(b, x);
  for (int i = 0; i < N; ++i) step(i) = x[i];
  return true;
}

// The step of the regularized normal equations (J^T J + mu I) dx = -J^T r by Cholesky's
// factorization: the backtracking method's step at a singular pose. The matrix must be positive
// definite in floating point, so mu well above N eps ||J||_F^2 (ik.cpp passes 1e-8 max(1, ||J||_F^2),
// about 1e7 times that): at a mu lost in rounding a pivot of a singular J^T J may come out negative.
template <int N>
Column<N> regularized_step(const Square<N>& J, const Column<N>& r, double mu) {
  Square<N> A;
  Column<N> b, x;
  for (int i = 0; i < N; ++i) {
    b(i) = 0;
    for (int k = 0; k < N; ++k) b(i) -= J(k, i) * r(k);
    for (int j = 0; j <= i; ++j) {  // the lower triangle, which the Cholesky solve reads
      double a = i == j ? mu : 0;
      for (int k = 0; k < N; ++k) a += J(k, i) * J(k, j);
      A(i, j) = a;
    }
  }
  // A pivot that is not positive (a mu lost in rounding): no step, as NaN (the square root of a
  // negative pivot gave NaN before; Newton's damping then takes no step either).
  if (!small::cholesky_solve<N>(A, b, x)) x.setConstant(std::numeric_limits<double>::quiet_NaN());
  return x;
}

// Levenberg-Marquardt's step: the least-squares solution of [J; sqrt(mu) I] dx = [-r; 0], mu > 0,
// by Householder's QR of the 2N x N stack (the normal equations would square J's condition
// number, 1e6 at the excavator's worst poses). Row N + k keeps its sqrt(mu) until column k is
// reduced, so every column's norm is at least sqrt(mu) and R's diagonal has no zero.
template <int N>
Column<N> damped_step(const Square<N>& J, const Column<N>& r, double mu) {
  constexpr int M = 2 * N;
  double a[M][N] = {}, b[M] = {};
  const double root_mu = std::sqrt(mu);
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) a[i][j] = J(i, j);
    a[N + i][i] = root_mu;
    b[i] = -r(i);
  }
  for (int k = 0; k < N; ++k) {
    // The reflection I - 2 v v^T / (v^T v) that maps column k below the diagonal onto its first entry.
    double norm = 0;
    for (int i = k; i < M; ++i) norm += a[i][k] * a[i][k];
    norm = std::sqrt(norm);
    const double alpha = a[k][k] > 0 ? -norm : norm;
    double v[M];
    for (int i = k; i < M; ++i) v[i] = a[i][k];
    v[k] -= alpha;
    double vv = 0;
    for (int i = k; i < M; ++i) vv += v[i] * v[i];
    for (int j = k; j < N; ++j) {
      double dot = 0;
      for (int i = k; i < M; ++i) dot += v[i] * a[i][j];
      const double f = 2 * dot / vv;
      for (int i = k; i < M; ++i) a[i][j] -= f * v[i];
    }
    double dot = 0;
    for (int i = k; i < M; ++i) dot += v[i] * b[i];
    const double f = 2 * dot / vv;
    for (int i = k; i < M; ++i) b[i] -= f * v[i];
  }
  Column<N> x;
  for (int i = N - 1; i >= 0; --i) {
    for (int j = i + 1; j < N; ++j) b[i] -= a[i][j] * b[j];
    b[i] /= a[i][i];
    x(i) = b[i];
  }
  return x;
}

}  // namespace wlx::limb_steps
