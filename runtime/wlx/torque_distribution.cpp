// How the actuators share the generalized forces on the commanded speeds: the weightings, and the
// weighted minimum-norm torques tau with J_beta^T tau = Q* (a fixed-size QR on J_beta's
// structure; the pivoted QR where that declines) (dynamics.hpp).
#include "wlx/dynamics.hpp"

#include "wlx/error.hpp"
#include "wlx/numerics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <tuple>
#include <utility>

WLX_MODEL_NAMESPACE_BEGIN

std::string Weighting::label() const {
  switch (kind) {
    case Kind::model_weights: return "the model file's weights";
    case Kind::contribution: return "weights by contribution";
    case Kind::diagonal: return "diagonal weights";
    case Kind::matrix: return "weight matrix";
    case Kind::contacts: return "the weights that keep the contacts";
  }
  return {};
}

Weighting Weighting::diagonal_of(const TorqueVector& w) {
  for (int i = 0; i < kActuatedCount; ++i)
    if (!(std::isfinite(w(i)) && w(i) > 0))
      throw Error(fmt::format("weighting[{}]", i), fmt::format("a weight must be positive and finite, got {}", w(i)));
  Weighting out;
  out.kind = Kind::diagonal;
  out.diagonal = w;
  return out;
}

Weighting Weighting::matrix_of(const TorqueMatrix& W) {
  if (!W.allFinite()) throw Error("weighting", "the weight matrix has a non-finite entry");
  if ((W - W.transpose()).cwiseAbs().maxCoeff() > 1e-12 * W.cwiseAbs().maxCoeff())
    throw Error("weighting", "the weight matrix must be symmetric");
  // S = L^-T of W = L L^T, once here rather than at every step. W is scaled to a largest entry of 1
  // first: entries near 1e308 would overflow in the factorization, and a uniform scale of W leaves
  // the minimum-norm torques as they are.
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(kActuatedCount, kActuatedCount);
#if __has_include(<wlx/gen/reduced_dynamics.hpp>)  // (no actuated joints without: nothing to factorize)
  // (Scaled into a fixed-size matrix first: a product or quotient bound to numerics' dynamic-size
  // Ref would compile Eigen's general kernels into every model.)
  const TorqueMatrix scaled = W / W.cwiseAbs().maxCoeff();
  if (!numerics::inverse_cholesky_factor(scaled, S))
    throw Error("weighting", "the weight matrix must be positive definite");
#endif
  Weighting out;
  out.kind = Kind::matrix;
  out.matrix = std::make_shared<const TorqueMatrix>(S);
  return out;
}

// The torque split, for a model with commanded speeds (a dynamics section: wlx-gen writes
// reduced_dynamics.hpp then); fixed-size blocks of empty matrices would not compile.
#if __has_include(<wlx/gen/reduced_dynamics.hpp>)
namespace {

// An upper bound on the infinity-norm condition number of the upper triangular R: ||R||_inf times
// ||M(R)^-1 e||_inf, M(R) R's comparison matrix (|r_ii| on the diagonal, -|r_ij| above it) and e =
// (1, ..., 1). |R^-1| <= M(R)^-1 entrywise (Higham, Accuracy and Stability of Numerical
// Algorithms, 2nd ed., Theorem 8.12), and M(R)^-1 e >= 0 comes from one back substitution without
// cancellation: a tenth of forming R^-1, and an upper bound, which is what the fast paths' guarantee
// needs (it can overstate the condition, up to 2^(n-1) for R far from diagonally dominant: then the
// pivoted QR answers, to the same rounding).
double condition_bound(const CommandMatrix& R) {
  constexpr int kU = kCommandedCount;
  CommandVector z;
  double norm_R = 0, norm_inverse = 0;
  for (int i = kU - 1; i >= 0; --i) {
    double sum = 1, row = std::abs(R(i, i));
    for (int j = i + 1; j < kU; ++j) {
      sum += std::abs(R(i, j)) * z(j);
      row += std::abs(R(i, j));
    }
    z(i) = sum / std::abs(R(i, i));
    norm_R = std::max(norm_R, row);
    norm_inverse = std::max(norm_inverse, z(i));
  }
  return norm_R * norm_inverse;
}

// The bound on condition_bound() that keeps n cond_inf below the pivoted QR's 1e13 (cond_2 <= n
// cond_inf): 1e12 up to 9 speeds, 0.9e13 / n beyond. Then sigma_min / sigma_max > 1e-13, so the
// pivoted QR's rank test would pass too, and both paths are backward stable: the same torques to
// rounding (tests/runtime/test_dynamics.cpp and tests/models/test_any_model.cpp check the paths
// against a long-double solution).
constexpr double kConditionLimit = kCommandedCount <= 9 ? 1e12 : 0.9e13 / kCommandedCount;

// The part of the dense QR's minimum-norm solve after the reflectors (qr's top rows hold R): the
// condition test, then R^T y = Q* by forward substitution into x's head, the rest zero. False,
// leaving the answer to the pivoted QR, unless condition_bound(R) <= kConditionLimit.
bool solve_transposed_R(const ActuatorJacobian& qr, const CommandVector& Qstar, TorqueVector& x) {
  const CommandMatrix R = qr.template topRows<kCommandedCount>().template triangularView<Eigen::Upper>();
  if (!(condition_bound(R) <= kConditionLimit)) return false;
  x.setZero();
  for (int i = 0; i < kCommandedCount; ++i) {
    double sum = Qstar(i);
    for (int l = 0; l < i; ++l) sum -= R(l, i) * x(l);
    x(i) = sum / R(i, i);
  }
  return true;
}

// Which entries of J_beta can be nonzero, from the generated structure: a joint's row is its
// coordinate's row of T (kRateBasisPattern), a drive's row its drive row times T (the rows of T
// that kDriveColumns names). A machine of several legs has many structural zeros: a speed that
// moves one foot moves only that leg's actuators.
using ActuatorPattern = std::array<std::array<bool, kCommandedCount>, kActuatedCount>;
constexpr ActuatorPattern actuator_pattern() {
  ActuatorPattern p{};
  for (int r = 0; r < kActuatedCount; ++r) {
    const int joint = kActuatedJoints[static_cast<std::size_t>(r)];
    if (joint >= 0) {
      for (int k = 0; k < kCommandedCount; ++k)
        p[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)] = gen::kRateBasisPattern[static_cast<std::size_t>(joint)][static_cast<std::size_t>(k)];
      continue;
    }
    const auto& columns = gen::kDriveColumns[static_cast<std::size_t>(kActuatedWheels[static_cast<std::size_t>(r)])];
    for (int i = 0; i < columns.count; ++i)
      for (int k = 0; k < kCommandedCount; ++k)
        p[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)] =
            p[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)] ||
            gen::kRateBasisPattern[static_cast<std::size_t>(columns.index[static_cast<std::size_t>(i)])][static_cast<std::size_t>(k)];
  }
  return p;
}
inline constexpr ActuatorPattern kActuatorPattern = actuator_pattern();

// The Householder QR of a J_beta with that structure, planned at compile time as a sparse QR
// would be: the column with the fewest nonzero rows goes next (a foot's speed before the body's),
// its reflector acts on those rows only, the first of them keeps R's row (the others' order does
// not matter: a row permutation, and Householder QR is backward stable in any row order), and the
// columns it meets fill in on those rows. For the wheeled quadruped the four feet's speeds go
// first, on their legs' four rows each, and leave a 12 x 6 dense QR for the body's speeds.
struct SparseQrPlan {
  std::array<int, kCommandedCount> column{};  // the column step k reduces
  std::array<int, kCommandedCount> count{};   // the rows its reflector acts on
  std::array<std::array<int, kActuatedCount>, kCommandedCount> rows{};      // those rows, R's row first
  std::array<std::array<bool, kCommandedCount>, kCommandedCount> meets{};  // step k's reflector meets column c
  bool feasible = true;  // every step has a row left (else the structure alone loses rank)
  long sparse_work = 0, dense_work = 0;  // multiply-adds of the reflectors' applications
};

constexpr SparseQrPlan sparse_qr_plan() {
  constexpr int kU = kCommandedCount, kA = kActuatedCount;
  ActuatorPattern p = kActuatorPattern;
  SparseQrPlan plan;
  std::array<bool, kA> retired{};
  std::array<bool, kU> done{};
  for (int k = 0; k < kU; ++k) {
    int best = -1, best_count = kA + 1;
    for (int c = 0; c < kU; ++c) {
      if (done[static_cast<std::size_t>(c)]) continue;
      int n = 0;
      for (int i = 0; i < kA; ++i) n += !retired[static_cast<std::size_t>(i)] && p[static_cast<std::size_t>(i)][static_cast<std::size_t>(c)];
      if (n < best_count) best = c, best_count = n;
    }
    if (best_count == 0) {
      plan.feasible = false;
      return plan;
    }
    auto& rows = plan.rows[static_cast<std::size_t>(k)];
    int n = 0;
    for (int i = 0; i < kA; ++i)
      if (!retired[static_cast<std::size_t>(i)] && p[static_cast<std::size_t>(i)][static_cast<std::size_t>(best)]) rows[static_cast<std::size_t>(n++)] = i;
    plan.column[static_cast<std::size_t>(k)] = best;
    plan.count[static_cast<std::size_t>(k)] = n;
    done[static_cast<std::size_t>(best)] = true;
    for (int c = 0; c < kU; ++c) {
      if (done[static_cast<std::size_t>(c)]) continue;
      bool meets = false;
      for (int i = 0; i < n; ++i) meets = meets || p[static_cast<std::size_t>(rows[static_cast<std::size_t>(i)])][static_cast<std::size_t>(c)];
      if (!meets) continue;
      plan.meets[static_cast<std::size_t>(k)][static_cast<std::size_t>(c)] = true;
      for (int i = 0; i < n; ++i) p[static_cast<std::size_t>(rows[static_cast<std::size_t>(i)])][static_cast<std::size_t>(c)] = true;
      plan.sparse_work += 2 * n;
    }
    plan.dense_work += 2L * (kA - k) * (kU - k - 1);
    retired[static_cast<std::size_t>(rows[0])] = true;
  }
  return plan;
}
inline constexpr SparseQrPlan kSparseQr = sparse_qr_plan();
// Worth it where it skips at least a third of the dense QR's work; a dense J_beta (the excavator's)
// keeps the dense path.
inline constexpr bool kUseSparseQr = kSparseQr.feasible && 3 * kSparseQr.sparse_work <= 2 * kSparseQr.dense_work;

// Whether A has a nonzero where the structure says zero: J_beta from inverse_dynamics never does,
// a matrix a caller builds may (then the dense path answers).
[[maybe_unused]] bool breaks_pattern(const ActuatorJacobian& A) {
  bool broken = false;
  for (int r = 0; r < kActuatedCount; ++r)
    for (int c = 0; c < kCommandedCount; ++c)
      if (!kActuatorPattern[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)]) broken = broken || A(r, c) != 0;
  return broken;
}

// min_norm_solve_dense's answer by the plan's sparse QR: the same reflectors on a row-permuted A,
// skipping the structural zeros, with the same condition test. Loop bounds and row indices are
// compile-time constants (kSparseQr), so the compiler unrolls every loop.
// (A template: compiled only where min_norm_solve_fast takes it.)
template <int = 0>
bool min_norm_solve_sparse(const ActuatorJacobian& A, const CommandVector& Qstar, TorqueVector& x) {
  constexpr int kU = kCommandedCount;
  constexpr const SparseQrPlan& plan = kSparseQr;
  ActuatorJacobian qr = A;
  std::array<std::array<double, kActuatedCount>, kU> v{};
  CommandVector tau;
  CommandMatrix R = CommandMatrix::Zero();  // in step order: R(k, j) on step j's column
  const bool full_rank = [&]<int... k>(std::integer_sequence<int, k...>) {
    const auto step = [&](auto K) {
      constexpr int s = decltype(K)::value, n = plan.count[s], c = plan.column[s];
      constexpr auto rows = plan.rows[s];
      double norm2 = 0;
      for (int i = 0; i < n; ++i) norm2 += qr(rows[i], c) * qr(rows[i], c);
      const double alpha = qr(rows[0], c), norm = std::sqrt(norm2);
      if (!(norm > 0)) return false;
      const double beta = alpha >= 0 ? -norm : norm, scale = 1 / (alpha - beta);
      auto& vs = v[s];
      vs[0] = 1;
      for (int i = 1; i < n; ++i) vs[i] = qr(rows[i], c) * scale;
      tau(s) = (beta - alpha) / beta;
      R(s, s) = beta;
      for (int j = 0; j < kU; ++j) {
        if (!plan.meets[s][j]) continue;
        double projection = 0;
        for (int i = 0; i < n; ++i) projection += vs[i] * qr(rows[i], j);
        projection *= tau(s);
        for (int i = 0; i < n; ++i) qr(rows[i], j) -= vs[i] * projection;
      }
      return true;
    };
    return (step(std::integral_constant<int, k>{}) && ...);
  }(std::make_integer_sequence<int, kU>{});
  if (!full_rank) return false;
  // R's row k is step k's first row, on the columns reduced after it (retired rows no longer change).
  for (int k = 0; k < kU; ++k)
    for (int j = k + 1; j < kU; ++j) R(k, j) = qr(plan.rows[static_cast<std::size_t>(k)][0], plan.column[static_cast<std::size_t>(j)]);
  if (!(condition_bound(R) <= kConditionLimit)) return false;
  // R^T y = (Q* in step order), then x = H_0 ... H_{n-1} y placed on R's rows.
  x.setZero();
  for (int k = 0; k < kU; ++k) {
    double sum = Qstar(plan.column[static_cast<std::size_t>(k)]);
    for (int l = 0; l < k; ++l) sum -= R(l, k) * x(plan.rows[static_cast<std::size_t>(l)][0]);
    x(plan.rows[static_cast<std::size_t>(k)][0]) = sum / R(k, k);
  }
  [&]<int... k>(std::integer_sequence<int, k...>) {
    const auto reflect = [&](auto K) {
      constexpr int s = kU - 1 - decltype(K)::value, n = plan.count[s];
      constexpr auto rows = plan.rows[s];
      double d = 0;
      for (int i = 0; i < n; ++i) d += v[s][i] * x(rows[i]);
      d *= tau(s);
      for (int i = 0; i < n; ++i) x(rows[i]) -= v[s][i] * d;
    };
    (reflect(std::integral_constant<int, k>{}), ...);
  }(std::make_integer_sequence<int, kU>{});
  return true;
}

// The minimum-norm x with A^T x = Q*, A actuated x commanded with full column rank: from A = Q R
// (Householder, each reflector stored below R's diagonal), x = Q [R^-T Q*; 0]. Unpivoted, on the
// model's fixed sizes: a fraction of Eigen's column-pivoted QR, whose inner loops run on dynamic-size
// blocks. Plain loops over compile-time bounds, which the compiler unrolls as it sees fit: as fast
// as an unrolled template per column (the excavator's 8 x 4 torque split 255-265 ns against
// 255-295 ns, alternating, 2026-12-07), which cost each model 0.6 s of compile, the wheeled
// quadruped's 3.5 s (ten columns of sixteen rows). Returns false, leaving the answer to the pivoted
// QR, unless condition_bound(R) <= kConditionLimit.
// (A template: compiled only where min_norm_solve_fast takes it.)
template <int = 0>
bool min_norm_solve_dense(const ActuatorJacobian& A, const CommandVector& Qstar, TorqueVector& x) {
  constexpr int kU = kCommandedCount, kA = kActuatedCount;
  ActuatorJacobian qr = A;
  CommandVector tau;
  for (int k = 0; k < kU; ++k) {
    double norm2 = 0;
    for (int i = k; i < kA; ++i) norm2 += qr(i, k) * qr(i, k);
    const double alpha = qr(k, k), norm = std::sqrt(norm2);
    if (!(norm > 0)) return false;  // a zero column (or NaN): the pivoted QR says what is wrong
    const double beta = alpha >= 0 ? -norm : norm, scale = 1 / (alpha - beta);
    for (int i = k + 1; i < kA; ++i) qr(i, k) *= scale;  // v, whose first entry is 1
    tau(k) = (beta - alpha) / beta;
    qr(k, k) = beta;
    for (int j = k + 1; j < kU; ++j) {
      double projection = qr(k, j);
      for (int i = k + 1; i < kA; ++i) projection += qr(i, k) * qr(i, j);
      projection *= tau(k);
      qr(k, j) -= projection;
      for (int i = k + 1; i < kA; ++i) qr(i, j) -= qr(i, k) * projection;
    }
  }
  if (!solve_transposed_R(qr, Qstar, x)) return false;
  for (int k = kU - 1; k >= 0; --k) {
    double projection = x(k);
    for (int i = k + 1; i < kA; ++i) projection += qr(i, k) * x(i);
    projection *= tau(k);
    x(k) -= projection;
    for (int i = k + 1; i < kA; ++i) x(i) -= qr(i, k) * projection;
  }
  return true;
}

bool min_norm_solve_fast(const ActuatorJacobian& A, const CommandVector& Qstar, TorqueVector& x) {
  if constexpr (kUseSparseQr)
    if (!breaks_pattern(A)) return min_norm_solve_sparse<>(A, Qstar, x);
  return min_norm_solve_dense<>(A, Qstar, x);
}

// The motion no actuator acts on, for the message of a rank loss: the unit combination n of the
// commanded speeds with A n = 0 (A's rows are the actuators' rates per commanded speed, up to
// a weighting, which leaves n as it is): the eigenvector of A^T A of the smallest eigenvalue,
// written with its largest entry +1 and entries below 1e-9 of it left out. (Wheels that roll
// freely give one where they all point the same way: the whole machine rolls along them and no
// actuated joint moves.)
[[gnu::noinline, gnu::cold]] std::string unactuated_motion(const ActuatorJacobian& At) {
  const CommandMatrix normal = At.transpose().lazyProduct(At);  // fixed size, as in matrix_of
  CommandVector n = numerics::smallest_eigenvector(normal);
  Eigen::Index largest = 0;
  n.cwiseAbs().maxCoeff(&largest);
  n /= n(largest);
  std::string combination;
  for (int k = 0; k < kCommandedCount; ++k) {
    if (std::abs(n(k)) < 1e-9) continue;
    const std::string_view name = gen::kCoordinateNames[static_cast<std::size_t>(kCommandedSpeeds[static_cast<std::size_t>(k)])];
    combination += combination.empty() ? fmt::format("{:.6g} {}'", n(k), name)
                                       : fmt::format(" {} {:.6g} {}'", n(k) < 0 ? '-' : '+', std::abs(n(k)), name);
  }
  return fmt::format("the speeds {} move no actuator (wheels that roll freely, a joint that is not actuated): "
                     "actuate a joint they move or drive the wheels ({{wheel: NAME}} under dynamics.actuated), or command "
                     "fewer speeds",
                     combination);
}

// The same with column pivoting and a rank test, for poses where the fast path declines: compiled
// once, at run-time sizes (numerics.hpp), being off the hot path. Kept out of line and cold, so
// that the fast path's frame stays small.
[[gnu::noinline, gnu::cold]] TorqueVector min_norm_solve_pivoted(const ActuatorJacobian& At, const CommandVector& Qstar, const Weighting& weighting) {
  constexpr int kU = kCommandedCount;
  // From A^T P = Q R (column-pivoted, rank-revealing QR), x = Q [R^-T P^T Q*; 0].
  if (!At.allFinite())  // no rank to speak of, and no combination to name
    throw Error("J_beta", "the actuator Jacobian has a non-finite entry: the pose or the parameters are outside the model's domain");
  // 1e-13 relative to the largest pivot: only a real rank loss, not ID-3's 1e6 conditioning.
  TorqueVector x;
  const int rank = numerics::min_norm_solve_pivoted(At, Qstar, 1e-13, x);
  if (rank < kU) {
    std::string u;
    for (int k : kCommandedSpeeds) u += fmt::format("{}{}'", u.empty() ? "" : ", ", gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    throw Error("J_beta", fmt::format("the actuator Jacobian has rank {} < {} with {}: the {} actuators cannot produce "
                                      "every generalized force on u = [{}] in this pose: {}",
                                      rank, kU, weighting.label(), kActuatedCount, u, unactuated_motion(At)));
  }
  return x;
}

// The minimum-norm x with A^T x = Q*: the fast path, else the pivoted QR (which throws on a rank loss).
TorqueVector min_norm_solve(const ActuatorJacobian& At, const CommandVector& Qstar, const Weighting& weighting) {
  TorqueVector x;
  if (!min_norm_solve_fast(At, Qstar, x)) x = min_norm_solve_pivoted(At, Qstar, weighting);
  return x;
}

// A full weight matrix: tau = S x with S = L^-T of W = L L^T, which matrix_of factorized.
[[gnu::noinline]] TorqueVector distribute_torques_weight_matrix(const ActuatorJacobian& J_beta, const CommandVector& Qstar,
                                                                const Weighting& weighting) {
  const TorqueMatrix& S = *weighting.matrix;
  return S.lazyProduct(min_norm_solve(S.transpose().lazyProduct(J_beta), Qstar, weighting));
}

}  // namespace

TorqueVector distribute_torques(const ActuatorJacobian& J_beta, const CommandVector& Qstar,
                                const Weighting& weighting) {
  // S with S S^T = W^-1: tau = S x and |x| = sqrt(tau^T W tau). Diagonal for every kind but a full
  // weight matrix (out of line below: its 8 x 8 products cost more than the QR).
  if (weighting.kind == Weighting::Kind::matrix) return distribute_torques_weight_matrix(J_beta, Qstar, weighting);
  if (weighting.kind == Weighting::Kind::contacts)
    throw Error("weighting", "the weights that keep the contacts need the step's contact forces: distribute_torques_on_contacts "
                             "(contacts.hpp) computes them");
  TorqueVector S;
  switch (weighting.kind) {
    case Weighting::Kind::model_weights: {
      S = model_weight_diagonal().cwiseInverse().cwiseSqrt();
      break;
    }
    case Weighting::Kind::contribution:  // W_ii^-1 = |row i| directly: a zero row gets zero torque
      for (int i = 0; i < kActuatedCount; ++i) S(i) = std::sqrt(J_beta.row(i).norm());
      break;
    // A uniform scale of W does not change the minimum-norm torques: divide it out (largest weight
    // 1) so weights of 1e308 or 1e-307 neither overflow nor fall below the rank threshold.
    default: S = (weighting.diagonal / weighting.diagonal.maxCoeff()).cwiseInverse().cwiseSqrt(); break;
  }
  return S.cwiseProduct(min_norm_solve(S.asDiagonal() * J_beta, Qstar, weighting));
}

#else

TorqueVector distribute_torques(const ActuatorJacobian&, const CommandVector&, const Weighting&) {
  throw Error("dynamics", fmt::format("model {} has no dynamics section: it has no actuated joints to share torques",
                                      gen::kModelName));
}

#endif

WLX_MODEL_NAMESPACE_END
