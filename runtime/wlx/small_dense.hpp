// Small dense decompositions at a fixed size N, written out as loops on the coefficients: for the
// wheels' square matrix J_beta (one row and column per wheel), an LU factorization with partial
// pivoting and the 2-norm condition number by one-sided Jacobi rotations; for forward dynamics'
// mass matrix on the commanded speeds, a Cholesky solve.
//
// Why not Eigen's PartialPivLU and JacobiSVD: at fixed sizes Eigen unrolls them into code that cost
// 1.5-2 s of CPU per model to compile (the quadruped's four wheels: the LU's factorization, solve
// and transposed solve 1.7 s, the SVD 0.5 s more), for a few dozen multiply-adds a step. The LU does
// Eigen's unblocked partial-pivoting elimination in Eigen's order (the largest entry of the column,
// rows swapped whole, the column below divided by the pivot, the trailing block updated), so it
// keeps its backward stability: the rolling rows hold to rounding where J_beta is badly
// conditioned. The Cholesky solve is Eigen's unblocked LLT likewise (its LLT<4 x 4> and solve cost
// 0.8 s of each model's compile). Nothing here allocates.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace wlx::small {

// P A = L U for a square A of size N (L unit lower triangular, below the diagonal of `lu`; U on
// and above it). A zero column below the diagonal is left as it is, as Eigen does: a singular A
// gets infinite or NaN solutions, which the callers' condition test refuses first. N may be
// Eigen::Dynamic (the runtime compiled once for every model): the size is then A's, and the
// operations are the same, in the same order.
template <int N>
struct PartialPivotLu {
  Eigen::Matrix<double, N, N> lu;
  Eigen::Matrix<int, N, 1> row;  // row(k): A's row at position k of P A

  PartialPivotLu() {
    if constexpr (N != Eigen::Dynamic) row.setZero();
  }

  int size() const { return static_cast<int>(lu.rows()); }

  void compute(const Eigen::Matrix<double, N, N>& A) {
    lu = A;
    const int n = size();
    row.resize(n);
    for (int i = 0; i < n; ++i) row(i) = i;
    for (int k = 0; k < n; ++k) {
      int p = k;
      for (int i = k + 1; i < n; ++i)
        if (std::abs(lu(i, k)) > std::abs(lu(p, k))) p = i;
      if (lu(p, k) == 0) continue;  // nothing to eliminate with (Eigen records it and goes on)
      if (p != k) {
        lu.row(p).swap(lu.row(k));
        std::swap(row(p), row(k));
      }
      for (int i = k + 1; i < n; ++i) lu(i, k) /= lu(k, k);
      for (int j = k + 1; j < n; ++j)
        for (int i = k + 1; i < n; ++i) lu(i, j) -= lu(i, k) * lu(k, j);
    }
  }

  // B := A^-1 B, all columns at once: the permutation, then L and U row by row.
  template <class Matrix>
  void solve_in_place(Matrix& B) const {
    const int n = size();
    typename Matrix::PlainObject permuted(B.rows(), B.cols());
    for (int i = 0; i < n; ++i) permuted.row(i) = B.row(row(i));
    B = permuted;
    for (int i = 1; i < n; ++i)
      for (int j = 0; j < i; ++j) B.row(i) -= lu(i, j) * B.row(j);
    for (int i = n - 1; i >= 0; --i) {
      for (int j = i + 1; j < n; ++j) B.row(i) -= lu(i, j) * B.row(j);
      B.row(i) /= lu(i, i);
    }
  }

  // x = A^-T b: A^T = U^T L^T P, so U^T z = b forwards, L^T w = z backwards, x = P^T w.
  void solve_transposed(const Eigen::Matrix<double, N, 1>& b, Eigen::Matrix<double, N, 1>& x) const {
    const int n = size();
    Eigen::Matrix<double, N, 1> w = b;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < i; ++j) w(i) -= lu(j, i) * w(j);
      w(i) /= lu(i, i);
    }
    for (int i = n - 1; i >= 0; --i)
      for (int j = i + 1; j < n; ++j) w(i) -= lu(j, i) * w(j);
    x.resize(n);
    for (int i = 0; i < n; ++i) x(row(i)) = w(i);
  }
};

// sigma_max / sigma_min of a square A, infinite for a singular or non-finite A (1 for no wheels, as
// for a model without them). One-sided Jacobi (Hestenes): plane rotations of column pairs until
// every pair is orthogonal to working precision; the singular values are then the columns' norms.
// Backward stable, so sigma_min is found to about eps sigma_max: the condition number to a relative
// eps cond, without the squaring of the condition that A^T A's eigenvalues would bring. A is first
// scaled to a largest entry of 1 (as Eigen's SVD does), so that no squared norm over- or underflows.
template <int N>
double condition_number(Eigen::Matrix<double, N, N> A) {
  if constexpr (N == 0) {
    return 1;  // no wheels (the one-sided rotations of a matrix without columns do not compile)
  } else {
    constexpr double kInfinity = std::numeric_limits<double>::infinity();
    const int n = static_cast<int>(A.cols());  // N, or the size of A where N is Eigen::Dynamic
    if (n == 0) return 1;
    if (!A.allFinite()) return kInfinity;
    const double largest_entry = A.cwiseAbs().maxCoeff();
    if (!(largest_entry > 0)) return kInfinity;
    A /= largest_entry;
    constexpr double eps = std::numeric_limits<double>::epsilon();
    // Each sweep squares the off-diagonal mass once it is small; 30 sweeps is far beyond what sizes
    // like these need (3-8 in practice), and bounds the loop for any input.
    for (int sweep = 0; sweep < 30; ++sweep) {
      bool rotated = false;
      for (int p = 0; p < n - 1; ++p)
        for (int q = p + 1; q < n; ++q) {
          const double alpha = A.col(p).squaredNorm(), beta = A.col(q).squaredNorm(), gamma = A.col(p).dot(A.col(q));
          if (!(std::abs(gamma) > eps * std::sqrt(alpha * beta))) continue;  // orthogonal already (or a zero column)
          rotated = true;
          const double zeta = (beta - alpha) / (2 * gamma);
          // t = sign(zeta) / (|zeta| + sqrt(1 + zeta^2)), the smaller root; 1 / (2 zeta) where zeta^2
          // would overflow (the same to rounding there).
          const double t = std::abs(zeta) > 1e150 ? 1 / (2 * zeta)
                                                  : (zeta >= 0 ? 1.0 : -1.0) / (std::abs(zeta) + std::sqrt(1 + zeta * zeta));
          const double c = 1 / std::sqrt(1 + t * t), s = c * t;
          const Eigen::Matrix<double, N, 1> a_p = A.col(p);
          A.col(p) = c * a_p - s * A.col(q);
          A.col(q) = s * a_p + c * A.col(q);
        }
      if (!rotated) break;
    }
    double largest = 0, smallest = kInfinity;
    for (int k = 0; k < n; ++k) {
      const double sigma = A.col(k).norm();
      largest = std::max(largest, sigma);
      smallest = std::min(smallest, sigma);
    }
    return smallest > 0 ? largest / smallest : kInfinity;

  }
}

// x = A^-1 b for a symmetric positive definite A, from A = L L^T (A's lower triangle is read), as
// Eigen's LLT computes it: false, x untouched, where a pivot is not positive, A not positive
// definite to working precision. Unlike Eigen's LLT, a NaN pivot is refused too (Eigen's test,
// x <= 0, lets it through into NaN results); a NaN off the diagonal gives a NaN in x, which
// callers check. At these sizes the time is the chain of dependent operations, not their count:
// the diagonal's reciprocals are computed once, off the chain, and the triangular solves multiply
// by them and sum each row in a register (10x10 with clang: 253 -> 194 ns; Eigen's LLT 418 ns;
// GCC 289 ns either way; a right-looking, column-by-column form, which vectorizes, took 320 ns).
template <int N>
bool cholesky_solve(const Eigen::Matrix<double, N, N>& A, const Eigen::Matrix<double, N, 1>& b, Eigen::Matrix<double, N, 1>& x) {
  Eigen::Matrix<double, N, N> L = A;
  Eigen::Matrix<double, N, 1> inverse_diagonal;
  for (int k = 0; k < N; ++k) {
    double pivot = L(k, k);
    for (int j = 0; j < k; ++j) pivot -= L(k, j) * L(k, j);
    if (!(pivot > 0)) return false;
    inverse_diagonal(k) = 1 / std::sqrt(pivot);
    for (int i = k + 1; i < N; ++i) {
      double sum = L(i, k);
      for (int j = 0; j < k; ++j) sum -= L(i, j) * L(k, j);
      L(i, k) = sum * inverse_diagonal(k);
    }
  }
  Eigen::Matrix<double, N, 1> y = b;
  for (int i = 0; i < N; ++i) {  // L y = b
    double sum = y(i);
    for (int j = 0; j < i; ++j) sum -= L(i, j) * y(j);
    y(i) = sum * inverse_diagonal(i);
  }
  for (int i = N - 1; i >= 0; --i) {  // L^T x = y
    double sum = y(i);
    for (int j = i + 1; j < N; ++j) sum -= L(j, i) * y(j);
    y(i) = sum * inverse_diagonal(i);
  }
  x = y;
  return true;
}

}  // namespace wlx::small
