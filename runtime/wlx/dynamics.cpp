#include "wlx/dynamics.hpp"

#include "wlx/error.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
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

// Row r of J_beta for the drive of wheel w: row w of the drives' rates per commanded speed (their
// rows times T, one product for all of them). A template, so that for a model without wheels (a
// 0-row matrix, whose row Eigen refuses at compile time) nothing is compiled.
template <typename Rates, typename Jacobian>
void drive_rate_row(const Rates& drive_rates, int w, Jacobian& J_beta, int r) {
  if constexpr (Rates::RowsAtCompileTime > 0) J_beta.row(r) = drive_rates.row(w);
}

}  // namespace

void throw_no_dynamics_section() {
  throw Error("dynamics", fmt::format("model {} has no dynamics section: name its commanded speeds, actuated joints and "
                                      "gravity in the model file (docs/model-format.md, Dynamics)",
                                      gen::kModelName));
}

#if __has_include(<wlx/gen/reduced_dynamics.hpp>)
namespace {

// Both formulations' velocity level: dPhi/ds and C(s) (a generated pass), the rate basis T,
// s' = T u and J_beta.
void velocity_level(const Params& p, Data& d, const Coordinates& s, const CommandVector& u, DynamicsTerms& out,
                    const DependentPair& pair, const NonholonomicOptions& options) {
  gen::dynamics_update(s, p, {.dPhi_ds = &d.dPhi_ds, .C = &d.C, .drive = kHasWheelDrives ? &d.drive : nullptr}, false);
  factorize_dependent_rates(d, pair, options);
  rate_basis(d, kCommandedSpeeds, pair, out.T);
  out.sdot.noalias() = out.T.lazyProduct(u);  // the velocity level's solve, once T is known
  // A joint's rate is its coordinate's, T's row; a wheel drive's is its drive row times T.
  Eigen::Matrix<double, kWheelCount, kCommandedCount> drive_rates;
  if constexpr (kHasWheelDrives) drive_rates.noalias() = d.drive.lazyProduct(out.T);  // not through the GEMM kernel
  for (int r = 0; r < kActuatedCount; ++r) {
    const int joint = kActuatedJoints[static_cast<std::size_t>(r)];
    if (joint >= 0)
      out.J_beta.row(r) = out.T.row(joint);
    else
      drive_rate_row(drive_rates, kActuatedWheels[static_cast<std::size_t>(r)], out.J_beta, r);
  }
}

}  // namespace
#endif

void inverse_dynamics(const Model& model, Data& d, const Coordinates& s, const CommandVector& u,
                      const CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options) {
// wlx-gen writes reduced_dynamics.hpp only for a model file with a dynamics section (and removes a
// stale one), so that the runtime compiles for every model.
#if !__has_include(<wlx/gen/reduced_dynamics.hpp>)
  static_cast<void>(model), static_cast<void>(d), static_cast<void>(s), static_cast<void>(u), static_cast<void>(u_dot);
  static_cast<void>(out), static_cast<void>(options);
  throw_no_dynamics_section();
#else
  const Params& p = model.params();
  const DependentPair pair = dynamics_pair();
  // Three generated passes: dPhi/ds and C(s), which give the rate basis T; at (s, s' = T u) the
  // convective terms, which give s''_bias; at (s, s', s'') the bodies' Newton-Euler equations,
  // summed back along the chains and projected on u (Q* = T^T tau), with no mass matrix.
  velocity_level(p, d, s, u, out, pair, options);
  gen::convective(s, out.sdot, p, {.dPhi_ds_dot_sdot = &d.dPhi_ds_dot_sdot, .C_dot_sdot = &d.C_dot_sdot});
  solve_bias_accelerations(d, out.sddot_bias, pair);
  out.sddot = out.T.lazyProduct(u_dot) + out.sddot_bias;
  gen::generalized_forces(s, out.sdot, out.sddot, out.T, p, {.Qstar = &out.Qstar});
#endif
}

void equations_of_motion(const Model& model, Data& d, const Coordinates& s, const CommandVector& u, DynamicsTerms& out,
                         const NonholonomicOptions& options) {
#if !__has_include(<wlx/gen/reduced_dynamics.hpp>)
  static_cast<void>(model), static_cast<void>(d), static_cast<void>(s), static_cast<void>(u), static_cast<void>(out);
  static_cast<void>(options);
  throw_no_dynamics_section();
#else
  const Params& p = model.params();
  const DependentPair pair = dynamics_pair();
  // Two generated passes: dPhi/ds and C(s), which give T; at (s, s' = T u, T) the convective terms
  // and Kane's sums over the bodies (M, the velocity and gravity forces and their gain on
  // s''_bias), sharing their subexpressions.
  velocity_level(p, d, s, u, out, pair, options);
  CommandVector b_velocity;
  gen::reduced_dynamics(s, out.sdot, out.T, p,
                        {.dPhi_ds_dot_sdot = &d.dPhi_ds_dot_sdot,
                         .C_dot_sdot = &d.C_dot_sdot,
                         .M = &out.M,
                         .b_velocity = &b_velocity,
                         .B_bias = &out.B_bias,
                         .Q_gravity = &out.Q_gravity},
                        false);  // B_bias's structural zeros: set once, by DynamicsTerms
  solve_bias_accelerations(d, out.sddot_bias, pair);
  out.sddot = out.sddot_bias;
  out.b = b_velocity + out.B_bias.lazyProduct(out.sddot_bias);
#endif
}

double potential_energy(const Model& model, Data& d, const Coordinates& s) {
  const Params& p = model.params();
  // if constexpr: for a model with gravity the test is false at compile time (GCC's -Waddress).
  if constexpr (gen::kGravity == nullptr) throw Error("dynamics", "the model file has no dynamics section, so no gravity parameter");
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
    case Kind::model_weights: return "weighting 1 (the model file's weights)";
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
#if __has_include(<wlx/gen/reduced_dynamics.hpp>)  // (no actuated joints without: nothing to factorize)
  if ((W / W.cwiseAbs().maxCoeff()).llt().info() != Eigen::Success)
    throw Error("weighting", "the weight matrix must be positive definite");
#endif
  Weighting out;
  out.kind = Kind::matrix;
  out.matrix = W;
  return out;
}

// The torque split, for a model with commanded speeds (a dynamics section: wlx-gen writes
// reduced_dynamics.hpp then); fixed-size blocks of empty matrices would not compile.
#if __has_include(<wlx/gen/reduced_dynamics.hpp>)
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
  // The 1-norm bound that keeps n cond_1 below the pivoted QR's 1e13: 1e12 up to 9 speeds (as it
  // always was), 0.9e13 / n beyond.
  constexpr double kConditionLimit = kU <= 9 ? 1e12 : 0.9e13 / kU;
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
    if (!(condition <= kConditionLimit)) return false;
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

// The motion no actuator acts on, for the message of a rank loss: the unit combination n of the
// commanded speeds with A n = 0 (A's rows are the actuators' rates per commanded speed, up to
// a weighting, which leaves n as it is): the eigenvector of A^T A of the smallest eigenvalue,
// written with its largest entry +1 and entries below 1e-9 of it left out. (Wheels that roll
// freely give one where they all point the same way: the whole machine rolls along them and no
// actuated joint moves.)
[[gnu::noinline, gnu::cold]] std::string unactuated_motion(const ActuatorJacobian& At) {
  const Eigen::SelfAdjointEigenSolver<CommandMatrix> eigen(At.transpose() * At);
  CommandVector n = eigen.eigenvectors().col(0);
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

// The same with column pivoting and a rank test: for poses where the fast path declines. Kept out
// of line: inlined, its dynamic-size blocks cost the fast path a 2 KB stack frame.
[[gnu::noinline, gnu::cold]] TorqueVector min_norm_solve_pivoted(const ActuatorJacobian& At, const CommandVector& Qstar, const Weighting& weighting) {
  constexpr int kU = kCommandedCount;
  // From A^T P = Q R (column-pivoted, rank-revealing QR), x = Q [R^-T P^T Q*; 0].
  if (!At.allFinite())  // no rank to speak of, and no combination to name
    throw Error("J_beta", "the actuator Jacobian has a non-finite entry: the pose or the parameters are outside the model's domain");
  Eigen::ColPivHouseholderQR<ActuatorJacobian> qr;
  qr.setThreshold(1e-13);  // relative to the largest pivot: only a real rank loss, not ID-3's 1e6 conditioning
  qr.compute(At);
  if (qr.rank() < kU) {
    std::string u;
    for (int k : kCommandedSpeeds) u += fmt::format("{}{}'", u.empty() ? "" : ", ", gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    throw Error("J_beta", fmt::format("the actuator Jacobian has rank {} < {} with {}: the {} actuators cannot produce "
                                      "every generalized force on u = [{}] in this pose: {}",
                                      qr.rank(), kU, weighting.label(), kActuatedCount, u, unactuated_motion(At)));
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
    case Weighting::Kind::model_weights: {
      static const TorqueVector scale = kModelWeightDiagonal.cwiseInverse().cwiseSqrt();  // constant: once
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

#else

TorqueVector distribute_torques(const ActuatorJacobian&, const CommandVector&, const Weighting&) {
  throw Error("dynamics", fmt::format("model {} has no dynamics section: it has no actuated joints to share torques",
                                      gen::kModelName));
}

#endif

WLX_MODEL_NAMESPACE_END
