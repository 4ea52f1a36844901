#include "wlx/dynamics.hpp"

#include "wlx/error.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <fmt/format.h>

#include <cmath>
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

}  // namespace

void inverse_dynamics(const Model& model, Data& d, const Coordinates& s, const CommandVector& u,
                      const CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options) {
  const Params& p = model.params();
  out.sdot.setZero();
  for (int k = 0; k < kCommandedCount; ++k) out.sdot(kCommandedSpeeds[static_cast<std::size_t>(k)]) = u(k);
  const DependentPair pair = dynamics_pair();
  solve_dependent_rates(model, d, s, out.sdot, pair, options);
  out.T = rate_basis(d, kCommandedSpeeds, pair);
  Coordinates bias = Coordinates::Zero();  // s'' with u' = 0
  solve_dependent_accelerations(model, d, s, out.sdot, bias, pair);
  out.sddot = out.T.lazyProduct(u_dot) + bias;
  gen::bodies(s, out.sdot, p,
              {.com = &d.body_com,
               .rotations = &d.body_rotations,
               .Jv = &d.body_Jv,
               .Jw = &d.body_Jw,
               .Jv_dot_sdot = &d.body_Jv_dot_sdot,
               .Jw_dot_sdot = &d.body_Jw_dot_sdot},
              false);
  out.M.setZero();
  out.b.setZero();
  out.Q_gravity.setZero();
  const Eigen::Vector3d gravity(0, 0, -(p.*gen::kGravity));
  constexpr int kU = kCommandedCount;
  // Per body, over its non-zero Jacobian columns only (a compile-time list, so every product below
  // is fixed-size and unrolled); the dense 3 x 32 products were most of this function's time.
  for_each_body([&](auto body) {
    constexpr int i = decltype(body)::value;
    constexpr gen::BodyColumns columns = gen::kBodyColumns[static_cast<std::size_t>(i)];
    constexpr int K = columns.count;
    const auto& Jv = d.body_Jv[static_cast<std::size_t>(i)];
    const auto& Jw = d.body_Jw[static_cast<std::size_t>(i)];
    // The body's columns of Jv over Jw, and the matching rows of T, s' and s''_bias.
    Eigen::Matrix<double, 6, K> J;
    Eigen::Matrix<double, K, kU> T_k;
    Eigen::Matrix<double, K, 2> rates_k;  // s', s''_bias
    for (int c = 0; c < K; ++c) {
      const int j = columns.index[static_cast<std::size_t>(c)];
      J.col(c) << Jv.col(j), Jw.col(j);
      T_k.row(c) = out.T.row(j);
      rates_k(c, 0) = out.sdot(j);
      rates_k(c, 1) = bias(j);
    }
    // Partial velocities [dv/du; domega/du] = J T, and J [s', s''_bias] = [v, a_bias; omega, alpha_bias]
    // without the convective terms.
    const Eigen::Matrix<double, 6, kU> partial = J.lazyProduct(T_k);
    const Eigen::Matrix<double, 6, 2> motion = J.lazyProduct(rates_k);
    const double m = mass(p, i);
    const auto& A = partial.template topRows<3>();
    const Eigen::Vector3d a_bias = d.body_Jv_dot_sdot.col(i) + motion.template block<3, 1>(0, 1);
    // The rotational part in body axes, where the inertia is diagonal: R^T B, R^T omega, R^T alpha.
    const Eigen::Matrix3d& R = d.body_rotations[static_cast<std::size_t>(i)];
    const auto& info = gen::kBodyMass[static_cast<std::size_t>(i)];
    const Eigen::Vector3d inertia(p.*info.inertia[0], p.*info.inertia[1], p.*info.inertia[2]);
    const Eigen::Matrix<double, 3, kU> B_body = R.transpose().lazyProduct(partial.template bottomRows<3>());
    const Eigen::Vector3d omega_body = R.transpose() * motion.template block<3, 1>(3, 0);
    const Eigen::Vector3d alpha_body =
        R.transpose() * (d.body_Jw_dot_sdot.col(i) + motion.template block<3, 1>(3, 1));
    const Eigen::Vector3d spin = inertia.cwiseProduct(omega_body);
    out.M.noalias() += m * A.transpose().lazyProduct(A) + B_body.transpose().lazyProduct(inertia.asDiagonal() * B_body);
    out.b.noalias() += A.transpose().lazyProduct(m * a_bias) +
                       B_body.transpose().lazyProduct(inertia.cwiseProduct(alpha_body) + omega_body.cross(spin));
    out.Q_gravity.noalias() += A.transpose().lazyProduct(m * gravity);
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

TorqueVector distribute_torques(const ActuatorJacobian& J_beta, const CommandVector& Qstar,
                                const Weighting& weighting) {
  constexpr int kU = kCommandedCount;
  // S with S S^T = W^-1: tau = S x and |x| = sqrt(tau^T W tau).
  TorqueMatrix S = TorqueMatrix::Zero();
  switch (weighting.kind) {
    case Weighting::Kind::strong_weak: S.diagonal() = kStrongWeakDiagonal.cwiseInverse().cwiseSqrt(); break;
    case Weighting::Kind::contribution:  // W_ii^-1 = |row i| directly: a zero row gets zero torque
      for (int i = 0; i < kActuatedCount; ++i) S(i, i) = std::sqrt(J_beta.row(i).norm());
      break;
    // A uniform scale of W does not change the minimum-norm torques: divide it out (largest weight
    // 1) so weights of 1e308 or 1e-307 neither overflow nor fall below the rank threshold.
    case Weighting::Kind::diagonal:
      S.diagonal() = (weighting.diagonal / weighting.diagonal.maxCoeff()).cwiseInverse().cwiseSqrt();
      break;
    case Weighting::Kind::matrix: {
      const TorqueMatrix L = (weighting.matrix / weighting.matrix.cwiseAbs().maxCoeff()).llt().matrixL();
      S = L.transpose().triangularView<Eigen::Upper>().solve(TorqueMatrix::Identity());
      break;
    }
  }
  // Minimum-norm solution of A x = Q* with A = J_beta^T S (commanded x actuated): from A^T P = Q R
  // (column-pivoted, rank-revealing QR), x = Q [R^-T P^T Q*; 0].
  const ActuatorJacobian At = S.transpose().lazyProduct(J_beta);
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
  const CommandMatrix R = qr.matrixR().topLeftCorner<kU, kU>().triangularView<Eigen::Upper>();
  const CommandVector y = R.transpose().triangularView<Eigen::Lower>().solve(qr.colsPermutation().transpose() * Qstar);
  TorqueVector x = TorqueVector::Zero();
  x.head<kU>() = y;
  x.applyOnTheLeft(qr.householderQ());
  return S * x;
}

WLX_MODEL_NAMESPACE_END
