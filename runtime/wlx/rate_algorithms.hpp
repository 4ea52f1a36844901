// The dependent rates' algorithms (wlx/nonholonomic.hpp says what they compute) written once for
// both runtimes: the model's own at its fixed sizes and the one compiled once for every model, at
// run-time sizes (wlx/generic/nonholonomic.hpp). They see the model through a problem P:
//
//   static constexpr int kLimbSize;          the limb blocks' size at compile time (or Eigen::Dynamic)
//   int limb_size() const;                   the largest limb's size: the limb blocks' size
//   static constexpr int kWheels, kClosureRows, kInputs;   the sizes at compile time (or Eigen::Dynamic)
//   int wheel_count() const;  int closure_rows() const;  int input_count() const;
//   void for_each_limb(F f) const;           f(limb, IkLimb) for every limb; the model's own runtime
//                                            passes the limb as a compile-time constant, so that its
//                                            blocks' indices are constants and the copies unroll
//   D& data() const;                         dPhi_ds, C, wheel_adjoint, J_beta, J_beta_lu,
//                                            cond_J_beta, dPhi_ds_dot_sdot, C_dot_sdot
//   limb_inverse(l)                          the limb's block's inverse (a kLimbSize square matrix)
//   std::string_view coordinate_name(int k) const;  std::string_view limb_title(int l) const;
//   std::string raise_a_wheel_hint() const;  what to do about a singular J_beta, from the model
//
// and a dependent pair: `index`, the pair's coordinates, one per wheel.
#pragma once

#include "wlx/error.hpp"
#include "wlx/ik_options.hpp"  // IkLimb, NonholonomicOptions
#include "wlx/small_dense.hpp"

#include <fmt/format.h>

#include <Eigen/Core>
#include <Eigen/LU>  // a limb block's inverse

#include <cmath>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace wlx::rate_algorithms {

template <class P>
using ClosureVector = Eigen::Matrix<double, P::kClosureRows, 1>;
template <class P>
using WheelVector = Eigen::Matrix<double, P::kWheels, 1>;
template <int N>
using LimbMatrix = Eigen::Matrix<double, N, N>;
template <int N>
using LimbVector = Eigen::Matrix<double, N, 1>;

// The 2-norm condition number of J_beta (wlx/nonholonomic.hpp, condition_number): in closed form
// for up to two wheels, by one-sided Jacobi rotations (small_dense.hpp) for more.
template <int W>
double condition_number(const Eigen::Matrix<double, W, W>& J) {
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  const int wheels = static_cast<int>(J.cols());
  if (wheels == 0) return 1;  // no wheels, no rates to solve for: nothing is ill-conditioned
  if (wheels == 1) return std::isfinite(J(0, 0)) && J(0, 0) != 0 ? 1 : kInfinity;
  if (wheels == 2) {
    // sigma_max = (sqrt(p) + sqrt(q)) / 2 with p = (a + d)^2 + (b - c)^2 and q = (a - d)^2 + (b + c)^2
    // (sums of squares: accurate even where the two singular values nearly agree, where the
    // textbook sqrt(E^2 - 4 det^2) loses half the digits), and sigma_max sigma_min = |det|.
    const double a = J(0, 0), b = J(0, 1), c = J(1, 0), d = J(1, 1);
    const double p = (a + d) * (a + d) + (b - c) * (b - c), q = (a - d) * (a - d) + (b + c) * (b + c);
    const double D = std::abs(a * d - b * c);
    if (!std::isfinite(p + q) || !(D > 0)) return kInfinity;
    const double smax = 0.5 * (std::sqrt(p) + std::sqrt(q));
    return smax * smax / D;
  }
  return small::condition_number<W>(J);
}

// Factorizes each limb's block of dPhi/ds and solves the adjoint Phi_dep^T Lambda = C_dep^T: one
// right-hand side per wheel instead of one per input (Phi_dep^-1 Phi_q). The wheel rows reduced to
// the inputs, C_hat = C_q - Lambda^T Phi_q, are then formed only where needed (reduced_column).
template <class P>
void reduce(const P& p) {
  constexpr int N = P::kLimbSize;
  auto& d = p.data();
  const int wheels = p.wheel_count();
  p.for_each_limb([&](auto limb, const IkLimb& b) {
    const int n = p.limb_size();
    LimbMatrix<N> block = LimbMatrix<N>::Identity(n, n);
    Eigen::Matrix<double, N, P::kWheels> rhs = Eigen::Matrix<double, N, P::kWheels>::Zero(n, wheels);
    for (int j = 0; j < b.size; ++j) {
      const int joint = b.joints[j];
      for (int i = 0; i < b.size; ++i) block(i, j) = d.dPhi_ds(b.rows[i], joint);
      // A row of a matrix with no columns is a block at an offset from a null pointer (undefined
      // behaviour that UBSan reports) for a model without wheels: nothing to copy there.
      if constexpr (P::kWheels != 0)
        if (wheels > 0) rhs.row(j) = d.C.col(joint).transpose();
    }
    auto&& inverse = p.limb_inverse(limb);
    inverse = block.inverse();
    // A singular block means the limb's joint rates are not determined by its target's motion.
    const double rcond = 1.0 / (block.cwiseAbs().colwise().sum().maxCoeff() * inverse.cwiseAbs().colwise().sum().maxCoeff());
    if (!(rcond > 1e-13))
      throw Error(std::string(p.limb_title(limb)),
                  fmt::format("the closure Jacobian of this limb is singular (reciprocal condition {:.2g}): {}; its joint "
                              "rates are undefined here",
                              std::isfinite(rcond) ? rcond : 0.0,  // an exactly singular block inverts to inf/NaN
                              "its joints cannot move its targets in every direction here (a chain stretched straight "
                              "or folded, or two joint axes aligned)"),
                  ErrorKind::singular);
    if constexpr (P::kWheels != 0)  // (fixed-size blocks of a matrix without columns do not compile)
      if (wheels > 0) {
        const Eigen::Matrix<double, N, P::kWheels> lambda = inverse.transpose().lazyProduct(rhs);
        for (int i = 0; i < b.size; ++i) d.wheel_adjoint.row(b.rows[i]) = lambda.row(i);
      }
  });
}

// The dependent joints' part of s'' or s' for a closure right-hand side: Phi_dep x = -v.
template <class P, class Closure, class Vector>
void solve_closure(const P& p, const Closure& v, Vector& out) {
  constexpr int N = P::kLimbSize;
  p.for_each_limb([&](auto limb, const IkLimb& b) {
    LimbVector<N> rhs = LimbVector<N>::Zero(p.limb_size());
    for (int i = 0; i < b.size; ++i) rhs(i) = -v(b.rows[i]);
    const LimbVector<N> x = p.limb_inverse(limb) * rhs;
    for (int j = 0; j < b.size; ++j) out(b.joints[j]) = x(j);
  });
}

// Column k of C_hat = C_q - Lambda^T Phi_q.
template <class P>
WheelVector<P> reduced_column(const P& p, int k) {
  const auto& d = p.data();
  return d.C.col(k) - d.wheel_adjoint.transpose().lazyProduct(d.dPhi_ds.col(k));
}

// The wheels' rows and the closure for input rates (or accelerations) `q` whose pair entries are
// zero, plus the convective terms: the pair's rates from J_beta pair' = -(C_q q + conv_C - Lambda^T
// (Phi_q q + conv_Phi)), then the dependent joints from Phi_dep x = -(Phi_q q' + conv_Phi) with q'
// = q and the pair's rates. Phi_q q is formed once; not at all when the input rates are all zero
// (kInputsZero: the bias accelerations of the inverse dynamics).
template <bool kInputsZero, class P, class Pair, class Closure, class Wheels, class Vector>
void solve_pair_and_closure(const P& p, const Pair& pair, const Closure& conv_Phi, const Wheels& conv_C, Vector& out) {
  const auto& d = p.data();
  const int wheels = p.wheel_count();
  ClosureVector<P> closure = conv_Phi;
  WheelVector<P> rolling = conv_C;
  if constexpr (!kInputsZero) {
    if constexpr (P::kInputs != Eigen::Dynamic) {
      closure.noalias() += d.dPhi_ds.template leftCols<P::kInputs>().lazyProduct(out.template head<P::kInputs>());
      rolling.noalias() += d.C.template leftCols<P::kInputs>().lazyProduct(out.template head<P::kInputs>());
    } else {
      closure.noalias() += d.dPhi_ds.leftCols(p.input_count()).lazyProduct(out.head(p.input_count()));
      rolling.noalias() += d.C.leftCols(p.input_count()).lazyProduct(out.head(p.input_count()));
    }
  }
  if constexpr (P::kWheels != 0)
    if (wheels > 0) {
      WheelVector<P> pair_rate = d.wheel_adjoint.transpose().lazyProduct(closure) - rolling;
      d.J_beta_lu.solve_in_place(pair_rate);
      for (int w = 0; w < wheels; ++w) {
        const int k = pair.index[static_cast<std::size_t>(w)];
        out(k) = pair_rate(w);
        closure.noalias() += d.dPhi_ds.col(k) * pair_rate(w);
      }
    }
  solve_closure(p, closure, out);
}

// The pair as the messages name it: "(y_C', yaw')".
template <class P, class Pair>
std::string pair_label(const P& p, const Pair& pair) {
  std::string names;
  for (int w = 0; w < p.wheel_count(); ++w)
    names += fmt::format("{}{}'", names.empty() ? "" : ", ", p.coordinate_name(pair.index[static_cast<std::size_t>(w)]));
  return "(" + names + ")";
}

// The coordinates of a pair given by the names of its rates (wlx/nonholonomic.hpp,
// dependent_pair): one per wheel, each a candidate (p.pair_candidates()), all different; wlx::Error
// naming `field` otherwise. P also gives coordinate_index(name) (-1: none).
template <class P>
std::vector<int> pair_coordinates(const P& p, const std::vector<std::string>& names, const std::string& field) {
  std::string valid;
  for (int k : p.pair_candidates()) valid += fmt::format("{}{}", valid.empty() ? "" : ", ", p.coordinate_name(k));
  if (names.size() != static_cast<std::size_t>(p.wheel_count()))
    throw Error(field, fmt::format("needs {} names, one dependent rate per wheel, got {}: choose from {}", p.wheel_count(),
                                   names.size(), valid));
  std::vector<int> index;
  for (const std::string& name : names) {
    const int k = p.coordinate_index(name);
    bool candidate = false;
    for (int c : p.pair_candidates()) candidate = candidate || (k >= 0 && c == k);
    if (!candidate) throw Error(field, fmt::format("'{}' cannot be a dependent rate: choose {} of {}", name, p.wheel_count(), valid));
    for (int j : index)
      if (j == k) throw Error(field, fmt::format("the dependent rates must differ, got '{}' twice", name));
    index.push_back(k);
  }
  return index;
}

// The pair the model names `name` (p.pairs(): each with a name and its coordinates); wlx::Error
// naming `field` when there is none.
template <class P>
const auto& named_pair(const P& p, std::string_view name, const std::string& field) {
  std::string valid;
  for (const auto& pair : p.pairs()) {
    if (pair.name == name) return pair;
    valid += fmt::format("{}{}", valid.empty() ? "" : ", ", pair.name);
  }
  throw Error(field, fmt::format("the model names no dependent pair '{}'; its pairs are {}", name, valid));
}

// The limb blocks' factorizations, J_beta and its condition (wlx/nonholonomic.hpp,
// factorize_dependent_rates): data's dPhi/ds and C must be current.
template <class P, class Pair>
void factorize(const P& p, const Pair& pair, const NonholonomicOptions& options) {
  auto& d = p.data();
  reduce(p);
  for (int k = 0; k < p.wheel_count(); ++k) d.J_beta.col(k) = reduced_column(p, pair.index[static_cast<std::size_t>(k)]);
  d.cond_J_beta = condition_number(d.J_beta);
  d.J_beta_lu.compute(d.J_beta);  // once: the rate basis and the accelerations use it
  if (!(d.cond_J_beta <= options.max_condition))
    throw Error(
        "dependent",
        fmt::format("J_beta for the dependent pair {} is singular: condition number {:.3g} exceeds the threshold "
                    "{:.3g}. The wheels' sideways constraint lines coincide (collinear wheel axes), "
                    "e.g. wheels on the same level under a level body. {}",
                    pair_label(p, pair), d.cond_J_beta, options.max_condition, p.raise_a_wheel_hint()),
        ErrorKind::singular);
}

// After factorize: s' = T u for unit rates of the `commanded` inputs (wlx/nonholonomic.hpp, rate_basis).
template <class P, class Commanded, class Pair, class Basis>
void rate_basis(const P& p, const Commanded& commanded, const Pair& pair, Basis& T) {
  constexpr int N = P::kLimbSize;
  constexpr int kU = Basis::ColsAtCompileTime;
  const auto& d = p.data();
  const int wheels = p.wheel_count();
  const int u_count = static_cast<int>(commanded.size());
  for (int c : commanded)
    for (int w = 0; w < wheels; ++w)
      if (c == pair.index[static_cast<std::size_t>(w)])
        throw Error("commanded", fmt::format("{}' is a commanded rate and one of the dependent pair", p.coordinate_name(c)));
  // Input-rate columns: a unit commanded rate, and the pair's answer to it.
  Eigen::Matrix<double, P::kWheels, kU> ch(wheels, u_count);
  for (int k = 0; k < u_count; ++k) ch.col(k) = reduced_column(p, commanded[static_cast<std::size_t>(k)]);
  Eigen::Matrix<double, P::kWheels, kU> pair_rates(wheels, u_count);
  if constexpr (P::kWheels != 0)
    if (wheels > 0) {
      pair_rates = -ch;
      d.J_beta_lu.solve_in_place(pair_rates);
    }
  T.setZero();
  for (int k = 0; k < u_count; ++k) {
    T(commanded[static_cast<std::size_t>(k)], k) = 1;
    for (int w = 0; w < wheels; ++w) T(pair.index[static_cast<std::size_t>(w)], k) = pair_rates(w, k);
  }
  // Dependent joints: Phi_dep T_dep = -Phi_q T_q, all columns per limb block at once. T's input
  // rows are zero except the commanded (unit rows) and the pair's: rhs = those columns of dPhi/ds
  // times them.
  Eigen::Matrix<double, P::kClosureRows, kU> rhs(p.closure_rows(), u_count);
  for (int k = 0; k < u_count; ++k) rhs.col(k) = d.dPhi_ds.col(commanded[static_cast<std::size_t>(k)]);
  if constexpr (P::kWheels != 0)  // (fixed-size blocks of a matrix without rows do not compile)
    for (int w = 0; w < wheels; ++w)
      rhs.noalias() += d.dPhi_ds.col(pair.index[static_cast<std::size_t>(w)]).lazyProduct(pair_rates.row(w));
  p.for_each_limb([&](auto limb, const IkLimb& b) {
    Eigen::Matrix<double, N, kU> block_rhs = Eigen::Matrix<double, N, kU>::Zero(p.limb_size(), u_count);
    for (int i = 0; i < b.size; ++i) block_rhs.row(i) = -rhs.row(b.rows[i]);
    const Eigen::Matrix<double, N, kU> x = p.limb_inverse(limb).lazyProduct(block_rhs);
    for (int j = 0; j < b.size; ++j) T.row(b.joints[j]) = x.row(j);
  });
}

}  // namespace wlx::rate_algorithms
