#include "wlx/dynamics.hpp"

#include "wlx/error.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <fmt/format.h>

#include <cmath>
#include <tuple>
#include <utility>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

Eigen::Matrix3d world_inertia(const Params& p, int body, const Eigen::Matrix3d& R) {
  const auto& info = gen::kBodyMass[static_cast<std::size_t>(body)];
  const Eigen::Vector3d I(p.*info.inertia[0], p.*info.inertia[1], p.*info.inertia[2]);
  return R * I.asDiagonal() * R.transpose();
}

double mass(const Params& p, int body) { return p.*gen::kBodyMass[static_cast<std::size_t>(body)].mass; }

// Calls f(std::integral_constant<int, i>) for every body i, so that its column list is a
// compile-time constant.
template <class F>
void for_each_body(F&& f) {
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    (f(std::integral_constant<int, static_cast<int>(I)>{}), ...);
  }(std::make_index_sequence<static_cast<std::size_t>(gen::kBodyCount)>{});
}

// What T = ds'/du holds in the row of each of a body's Jacobian columns. T's structure is fixed by
// the model file: the commanded speeds' rows are unit rows, the dynamics pair's and the dependent
// joints' rows are dense, and the rows of the other inputs (held constant) are zero. Sorting the
// columns by it at compile time leaves the dense ones for the products: 26 of the excavator's 60.
struct BodyColumnClasses {
  int dense_count = 0;  // columns whose T row is dense
  std::array<int, gen::kMaxBodyColumns> dense{};
  int commanded_count = 0;  // columns of a commanded speed: their T row is the unit row of speed k
  std::array<int, gen::kMaxBodyColumns> commanded_column{}, commanded_speed{};
};

constexpr BodyColumnClasses classify_columns(int body) {
  const gen::BodyColumns columns = gen::kBodyColumns[static_cast<std::size_t>(body)];
  const auto pair = gen::kPairs[gen::kDynamicsPair].coordinates;
  BodyColumnClasses out;
  for (int c = 0; c < columns.count; ++c) {
    const int j = columns.index[static_cast<std::size_t>(c)];
    int speed = -1;
    for (int k = 0; k < kCommandedCount; ++k)
      if (kCommandedSpeeds[static_cast<std::size_t>(k)] == j) speed = k;
    bool in_pair = false;
    for (int w : pair) in_pair = in_pair || w == j;
    if (speed >= 0) {
      out.commanded_column[static_cast<std::size_t>(out.commanded_count)] = j;
      out.commanded_speed[static_cast<std::size_t>(out.commanded_count++)] = speed;
    } else if (j >= kInputCount || in_pair) {
      out.dense[static_cast<std::size_t>(out.dense_count++)] = j;
    }
  }
  return out;
}

inline constexpr auto kBodyColumnClasses = [] {
  std::array<BodyColumnClasses, static_cast<std::size_t>(gen::kBodyCount)> out{};
  for (int i = 0; i < gen::kBodyCount; ++i) out[static_cast<std::size_t>(i)] = classify_columns(i);
  return out;
}();

}  // namespace

void inverse_dynamics(const Model& model, Data& d, const Coordinates& s, const CommandVector& u,
                      const CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options) {
  const Params& p = model.params();
  const DependentPair pair = dynamics_pair();
  // Two fused generated passes instead of four: dPhi/ds, C(s) and the bodies' Jacobians at s, then
  // every convective term at (s, s'); they share their subexpressions (the frames' rotations).
  gen::dynamics_update(s, p,
                       {.dPhi_ds = &d.dPhi_ds,
                        .C = &d.C,
                        .com = &d.body_com,
                        .rotations = &d.body_rotations,
                        .Jv = &d.body_Jv,
                        .Jw = &d.body_Jw},
                       false);
  factorize_dependent_rates(d, pair, options);
  out.T = rate_basis(d, kCommandedSpeeds, pair);
  out.sdot.noalias() = out.T.lazyProduct(u);  // the velocity level's solve, once T is known
  gen::dynamics_convective(s, out.sdot, p,
                           {.dPhi_ds_dot_sdot = &d.dPhi_ds_dot_sdot,
                            .C_dot_sdot = &d.C_dot_sdot,
                            .Jv_dot_sdot = &d.body_Jv_dot_sdot,
                            .Jw_dot_sdot = &d.body_Jw_dot_sdot});
  Coordinates bias = Coordinates::Zero();  // s'' with u' = 0
  solve_dependent_accelerations_prepared(d, bias, pair);
  out.sddot = out.T.lazyProduct(u_dot) + bias;
  out.M.setZero();
  out.b.setZero();
  out.Q_gravity.setZero();
  const Eigen::Vector3d gravity(0, 0, -(p.*gen::kGravity));
  constexpr int kU = kCommandedCount;
  // Per body, over its Jacobian columns with a dense row of T only (a compile-time list, so every
  // product below is fixed-size and unrolled); the columns of the commanded speeds are added, the
  // others are skipped (their rows of T, s' and s''_bias are zero).
  for_each_body([&](auto body) {
    constexpr int i = decltype(body)::value;
    constexpr BodyColumnClasses columns = kBodyColumnClasses[static_cast<std::size_t>(i)];
    constexpr int K = columns.dense_count;
    const auto& Jv = d.body_Jv[static_cast<std::size_t>(i)];
    const auto& Jw = d.body_Jw[static_cast<std::size_t>(i)];
    // Partial velocities P = [dv/du; domega/du] = J T, and J s''_bias (without the convective terms).
    Eigen::Matrix<double, 6, kU> partial;
    Eigen::Matrix<double, 6, 1> bias_motion = Eigen::Matrix<double, 6, 1>::Zero();
    if constexpr (K > 0) {
      Eigen::Matrix<double, 6, K> J;
      Eigen::Matrix<double, K, kU> T_k;
      Eigen::Matrix<double, K, 1> bias_k;
      for (int c = 0; c < K; ++c) {
        const int j = columns.dense[static_cast<std::size_t>(c)];
        J.col(c) << Jv.col(j), Jw.col(j);
        T_k.row(c) = out.T.row(j);
        bias_k(c) = bias(j);
      }
      partial.noalias() = J.lazyProduct(T_k);
      bias_motion.noalias() = J.lazyProduct(bias_k);
    } else {
      partial.setZero();
    }
    for (int c = 0; c < columns.commanded_count; ++c) {
      const int j = columns.commanded_column[static_cast<std::size_t>(c)];
      const int k = columns.commanded_speed[static_cast<std::size_t>(c)];
      partial.col(k).template head<3>() += Jv.col(j);
      partial.col(k).template tail<3>() += Jw.col(j);
    }
    const double m = mass(p, i);
    // The rotational rows in body axes, where the inertia is diagonal: R^T B, R^T alpha, and
    // omega = B u (s' = T u). P = [A; R^T B] and D = diag(m, m, m, I): M += P^T D P in one product.
    const Eigen::Matrix3d& R = d.body_rotations[static_cast<std::size_t>(i)];
    const auto& info = gen::kBodyMass[static_cast<std::size_t>(i)];
    Eigen::Matrix<double, 6, 1> D;
    D << m, m, m, p.*info.inertia[0], p.*info.inertia[1], p.*info.inertia[2];
    Eigen::Matrix<double, 6, kU> P;
    P.template topRows<3>() = partial.template topRows<3>();
    P.template bottomRows<3>().noalias() = R.transpose().lazyProduct(partial.template bottomRows<3>());
    const Eigen::Matrix<double, 6, kU> DP = D.asDiagonal() * P;
    out.M.noalias() += P.transpose().lazyProduct(DP);
    // Generalized inertia forces of the bias motion: P^T [m a_bias; I alpha + omega x I omega].
    const Eigen::Vector3d omega_body = P.template bottomRows<3>().lazyProduct(u);
    const Eigen::Vector3d spin = D.template tail<3>().cwiseProduct(omega_body);
    Eigen::Matrix<double, 6, 1> force;
    force.template head<3>() = m * (d.body_Jv_dot_sdot.col(i) + bias_motion.template head<3>());
    force.template tail<3>() =
        D.template tail<3>().cwiseProduct(R.transpose() * (d.body_Jw_dot_sdot.col(i) + bias_motion.template tail<3>())) +
        omega_body.cross(spin);
    out.b.noalias() += P.transpose().lazyProduct(force);
    out.Q_gravity.noalias() += P.template topRows<3>().transpose().lazyProduct(m * gravity);
  });
  out.Qstar = out.M * u_dot + out.b - out.Q_gravity;
  for (int r = 0; r < kActuatedCount; ++r) out.J_beta.row(r) = out.T.row(kActuatedJoints[static_cast<std::size_t>(r)]);
}

double potential_energy(const Model& model, Data& d, const Coordinates& s) {
  const Params& p = model.params();
  gen::bodies(s, Coordinates::Zero(), p, {.com = &d.body_com}, false);
  double V = 0;
  for (int i = 0; i < gen::kBodyCount; ++i) V += mass(p, i) * (p.*gen::kGravity) * d.body_com(2, i);
  return V;
}

double kinetic_energy(const Model& model, Data& d, const Coordinates& s, const Coordinates& sdot) {
  const Params& p = model.params();
  gen::bodies(s, sdot, p, {.rotations = &d.body_rotations, .Jv = &d.body_Jv, .Jw = &d.body_Jw}, false);
  double T = 0;
  for (int i = 0; i < gen::kBodyCount; ++i) {
    const Eigen::Vector3d v = d.body_Jv[static_cast<std::size_t>(i)] * sdot;
    const Eigen::Vector3d w = d.body_Jw[static_cast<std::size_t>(i)] * sdot;
    T += 0.5 * mass(p, i) * v.squaredNorm() + 0.5 * w.dot(world_inertia(p, i, d.body_rotations[static_cast<std::size_t>(i)]) * w);
  }
  return T;
}

std::string Weighting::label() const {
  switch (kind) {
    case Kind::strong_weak: return "weighting 1 (strong/weak)";
    case Kind::contribution: return "weighting 2 (contribution)";
    case Kind::diagonal: return "diagonal weights";
    case Kind::matrix: return "weight matrix";
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
  // Scaled to a largest entry of 1 first: entries near 1e308 would overflow in the factorization.
  if ((W / W.cwiseAbs().maxCoeff()).llt().info() != Eigen::Success)
    throw Error("weighting", "the weight matrix must be positive definite");
  Weighting out;
  out.kind = Kind::matrix;
  out.matrix = W;
  return out;
}

namespace {

template <int k>
using Tail = Eigen::Matrix<double, kActuatedCount - k, 1>;

// Householder reflector k: zeroes qr's column k below the diagonal and applies itself to the
// columns right of it. Sizes are compile-time (k is), so Eigen unrolls and vectorizes every product.
template <int k>
bool householder_step(ActuatorJacobian& qr, Tail<k>& v, double& tau) {
  constexpr int n = kActuatedCount - k;
  const auto column = qr.col(k).template tail<n>();
  const double alpha = column(0), norm = column.norm();
  if (!(norm > 0)) return false;  // a zero column (or NaN): the pivoted QR says what is wrong
  const double beta = alpha >= 0 ? -norm : norm;
  v = column * (1 / (alpha - beta));  // one division, not one per entry
  v(0) = 1;
  tau = (beta - alpha) / beta;
  qr(k, k) = beta;
  if constexpr (k + 1 < kCommandedCount) {
    auto rest = qr.template block<n, kCommandedCount - k - 1>(k, k + 1);
    const Eigen::Matrix<double, 1, kCommandedCount - k - 1> projection = v.transpose().lazyProduct(rest);
    rest.noalias() -= (tau * v).lazyProduct(projection);
  }
  return true;
}

// The minimum-norm x with A^T x = Q*, A actuated x commanded with full column rank: from A = Q R
// (Householder), x = Q [R^-T Q*; 0]. Unpivoted, fixed-size and unrolled: a fraction of Eigen's
// column-pivoted QR, whose inner loops run on dynamic-size blocks. Returns false, leaving the
// answer to the pivoted QR, unless R's 1-norm condition number is at most 1e12: then
// sigma_min / sigma_max >= 1 / (n 1e12) > 1e-13 (cond_2 <= n cond_1; n <= 9 commanded speeds), so
// the pivoted QR's rank test would pass too, and both are backward stable: the same torques to
// rounding (tests/runtime/test_dynamics.cpp checks both paths against a long-double solution).
bool min_norm_solve_fast(const ActuatorJacobian& A, const CommandVector& Qstar, TorqueVector& x) {
  constexpr int kU = kCommandedCount;
  static_assert(kU <= 9, "the condition bound above assumes at most 9 commanded speeds");
  ActuatorJacobian qr = A;
  CommandVector tau;
  return [&]<int... k>(std::integer_sequence<int, k...>) {
    std::tuple<Tail<k>...> v;
    if (!(householder_step<k>(qr, std::get<k>(v), tau(k)) && ...)) return false;
    // R^-1 by back substitution, column by column: for the condition number.
    const CommandMatrix R = qr.template topRows<kU>().template triangularView<Eigen::Upper>();
    const CommandVector reciprocal = R.diagonal().cwiseInverse();
    CommandMatrix R_inverse = CommandMatrix::Zero();
    for (int j = 0; j < kU; ++j) {
      R_inverse(j, j) = reciprocal(j);
      for (int i = j - 1; i >= 0; --i) {
        double sum = 0;
        for (int l = i + 1; l <= j; ++l) sum += R(i, l) * R_inverse(l, j);
        R_inverse(i, j) = -sum * reciprocal(i);
      }
    }
    const double condition = R.cwiseAbs().colwise().sum().maxCoeff() * R_inverse.cwiseAbs().colwise().sum().maxCoeff();
    if (!(condition <= 1e12)) return false;
    // R^T y = Q* by forward substitution, then x = H_0 ... H_{n-1} [y; 0].
    x.setZero();
    for (int i = 0; i < kU; ++i) {
      double sum = Qstar(i);
      for (int l = 0; l < i; ++l) sum -= R(l, i) * x(l);
      x(i) = sum * reciprocal(i);
    }
    ((x.template tail<kActuatedCount - (kU - 1 - k)>() -=
      (tau(kU - 1 - k) * std::get<kU - 1 - k>(v).dot(x.template tail<kActuatedCount - (kU - 1 - k)>())) *
      std::get<kU - 1 - k>(v)),
     ...);
    return true;
  }(std::make_integer_sequence<int, kU>{});
}

// The same with column pivoting and a rank test: for poses where the fast path declines. Kept out
// of line: inlined, its dynamic-size blocks cost the fast path a 2 KB stack frame.
[[gnu::noinline, gnu::cold]] TorqueVector min_norm_solve_pivoted(const ActuatorJacobian& At, const CommandVector& Qstar, const Weighting& weighting) {
  constexpr int kU = kCommandedCount;
  // From A^T P = Q R (column-pivoted, rank-revealing QR), x = Q [R^-T P^T Q*; 0].
  Eigen::ColPivHouseholderQR<ActuatorJacobian> qr;
  qr.setThreshold(1e-13);  // relative to the largest pivot: only a real rank loss, not ID-3's 1e6 conditioning
  qr.compute(At);
  if (qr.rank() < kU) {
    std::string u;
    for (int k : kCommandedSpeeds) u += fmt::format("{}{}'", u.empty() ? "" : ", ", gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    throw Error("J_beta", fmt::format("the actuator Jacobian has rank {} < {} with {}: the {} actuators cannot produce "
                                      "every generalized force on u = [{}] in this pose",
                                      qr.rank(), kU, weighting.label(), kActuatedCount, u));
  }
  const CommandMatrix R = qr.matrixR().template topLeftCorner<kU, kU>().template triangularView<Eigen::Upper>();
  const CommandVector y = R.transpose().template triangularView<Eigen::Lower>().solve(qr.colsPermutation().transpose() * Qstar);
  TorqueVector x = TorqueVector::Zero();
  x.template head<kU>() = y;
  x.applyOnTheLeft(qr.householderQ());
  return x;
}

// The minimum-norm x with A^T x = Q*: the fast path, else the pivoted QR (which throws on a rank loss).
TorqueVector min_norm_solve(const ActuatorJacobian& At, const CommandVector& Qstar, const Weighting& weighting) {
  TorqueVector x;
  if (!min_norm_solve_fast(At, Qstar, x)) x = min_norm_solve_pivoted(At, Qstar, weighting);
  return x;
}

// A full weight matrix: S = L^-T from W = L L^T (scaled to a largest entry of 1, as above).
[[gnu::noinline]] TorqueVector distribute_torques_weight_matrix(const ActuatorJacobian& J_beta, const CommandVector& Qstar,
                                                                const Weighting& weighting) {
  const TorqueMatrix L = (weighting.matrix / weighting.matrix.cwiseAbs().maxCoeff()).llt().matrixL();
  const TorqueMatrix S = L.transpose().triangularView<Eigen::Upper>().solve(TorqueMatrix::Identity());
  return S.lazyProduct(min_norm_solve(S.transpose().lazyProduct(J_beta), Qstar, weighting));
}

}  // namespace

TorqueVector distribute_torques(const ActuatorJacobian& J_beta, const CommandVector& Qstar,
                                const Weighting& weighting) {
  // S with S S^T = W^-1: tau = S x and |x| = sqrt(tau^T W tau). Diagonal for every kind but a full
  // weight matrix (out of line below: its 8 x 8 products cost more than the QR).
  if (weighting.kind == Weighting::Kind::matrix) return distribute_torques_weight_matrix(J_beta, Qstar, weighting);
  TorqueVector S;
  switch (weighting.kind) {
    case Weighting::Kind::strong_weak: {
      static const TorqueVector scale = kStrongWeakDiagonal.cwiseInverse().cwiseSqrt();  // constant: once
      S = scale;
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

WLX_MODEL_NAMESPACE_END
