#include "wlx/nonholonomic.hpp"

#include "wlx/error.hpp"
#include "wlx/ik.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <utility>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

constexpr int kNq = kInputCount;

std::string_view name_of(int coordinate) { return gen::kCoordinateNames[static_cast<std::size_t>(coordinate)]; }

bool is_pair_candidate(int coordinate) {
  for (int k : gen::kPairCandidates)
    if (k == coordinate) return true;
  return false;
}

// Calls f(std::integral_constant<int, L>) for every limb L: the limb's rows and joints are then
// compile-time constants (gen::kLimbs is constexpr), so the block copies below unroll with fixed
// indices, as fast as code written for one robot.
template <class F>
void for_each_limb(F&& f) {
  [&]<std::size_t... L>(std::index_sequence<L...>) {
    (f(std::integral_constant<int, static_cast<int>(L)>{}), ...);
  }(std::make_index_sequence<static_cast<std::size_t>(kLimbCount)>{});
}

// Factorizes each limb's block of dPhi/ds, solves the adjoint Phi_dep^T Lambda = C_dep^T and forms
// C_hat = C_q - Lambda^T Phi_q: 2 right-hand sides instead of the 18 of Phi_dep^-1 Phi_q.
void reduce(Data& d) {
  for_each_limb([&](auto L) {
    constexpr Limb limb = decltype(L)::value;
    constexpr gen::LimbInfo b = gen::kLimbs[static_cast<std::size_t>(limb)];
    Eigen::Matrix4d block = Eigen::Matrix4d::Identity();
    Eigen::Matrix<double, 4, 2> rhs = Eigen::Matrix<double, 4, 2>::Zero();
    for (int j = 0; j < b.size; ++j) {
      const int joint = b.joints[static_cast<std::size_t>(j)];
      for (int i = 0; i < b.size; ++i) block(i, j) = d.dPhi_ds(b.rows[static_cast<std::size_t>(i)], joint);
      rhs.row(j) = d.C.col(joint).transpose();
    }
    auto& inverse = d.limb_inverse[static_cast<std::size_t>(limb)];
    inverse = block.inverse();
    // A singular block means the limb's joint rates are not determined by its target's motion.
    const double rcond = 1.0 / (block.cwiseAbs().colwise().sum().maxCoeff() * inverse.cwiseAbs().colwise().sum().maxCoeff());
    if (!(rcond > 1e-13))
      throw Error(std::string(limb_name(limb)),
                  fmt::format("the closure Jacobian of this limb is singular (reciprocal condition {:.2g}): {}; its joint "
                              "rates are undefined here",
                              std::isfinite(rcond) ? rcond : 0.0,  // an exactly singular block inverts to inf/NaN
                              "its joints cannot move its targets in every direction here (a chain stretched straight "
                              "or folded, or two joint axes aligned)"));
    const Eigen::Matrix<double, 4, 2> lambda = inverse.transpose().lazyProduct(rhs);
    for (int i = 0; i < b.size; ++i) d.wheel_adjoint.row(b.rows[static_cast<std::size_t>(i)]) = lambda.row(i);
  });
  d.C_reduced = d.C.leftCols<kNq>() - d.wheel_adjoint.transpose().lazyProduct(d.dPhi_ds.leftCols<kNq>());
}

// The dependent joints' part of s'' or s' for a closure right-hand side: Phi_dep x = -v.
void solve_closure(const Data& d, const gen::ClosureVector& v, Coordinates& out) {
  for_each_limb([&](auto L) {
    constexpr gen::LimbInfo b = gen::kLimbs[static_cast<std::size_t>(decltype(L)::value)];
    Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
    for (int i = 0; i < b.size; ++i) rhs(i) = -v(b.rows[static_cast<std::size_t>(i)]);
    const Eigen::Vector4d x = d.limb_inverse[static_cast<std::size_t>(decltype(L)::value)] * rhs;
    for (int j = 0; j < b.size; ++j) out(b.joints[static_cast<std::size_t>(j)]) = x(j);
  });
}

}  // namespace

// 2-norm condition number of a 2 x 2 matrix [a b; c d] in closed form, without cancellation:
// sigma_max = (sqrt(p) + sqrt(q)) / 2 with p = (a + d)^2 + (b - c)^2 and q = (a - d)^2 + (b + c)^2
// (sums of squares: accurate even where the two singular values nearly agree, where the textbook
// sqrt(E^2 - 4 det^2) loses half the digits), and sigma_max sigma_min = |det|.
double condition_number(const Eigen::Matrix2d& J) {
  const double a = J(0, 0), b = J(0, 1), c = J(1, 0), d = J(1, 1);
  const double p = (a + d) * (a + d) + (b - c) * (b - c), q = (a - d) * (a - d) + (b + c) * (b + c);
  const double D = std::abs(J.determinant());
  if (!std::isfinite(p + q)) return std::numeric_limits<double>::infinity();
  if (!(D > 0)) return std::numeric_limits<double>::infinity();
  const double smax = 0.5 * (std::sqrt(p) + std::sqrt(q));
  return smax * smax / D;
}

std::string DependentPair::label() const {
  return fmt::format("({}', {}')", name_of(index[0]), name_of(index[1]));
}

DependentPair dependent_pair(std::string_view first, std::string_view second, const std::string& field) {
  std::string valid;
  for (int k : gen::kPairCandidates) valid += fmt::format("{}{}", valid.empty() ? "" : ", ", name_of(k));
  DependentPair pair;
  const std::string_view names[2] = {first, second};
  for (int i = 0; i < 2; ++i) {
    const int k = coordinate_index(names[i]);
    if (k < 0 || !is_pair_candidate(k))
      throw Error(field, fmt::format("'{}' cannot be a dependent rate: choose 2 of {}", names[i], valid));
    pair.index[static_cast<std::size_t>(i)] = k;
  }
  if (pair.index[0] == pair.index[1])
    throw Error(field, fmt::format("the two dependent rates must differ, got '{}' twice", first));
  return pair;
}

DependentPair named_pair(std::string_view name, const std::string& field) {
  std::string valid;
  for (const auto& p : gen::kPairs) {
    if (p.name == name) return {p.coordinates};
    valid += fmt::format("{}{}", valid.empty() ? "" : ", ", p.name);
  }
  throw Error(field, fmt::format("the model names no dependent pair '{}'; its pairs are {}", name, valid));
}

void solve_dependent_rates(const Model& model, const Coordinates& s, Coordinates& sdot, const DependentPair& pair,
                           Data& d, const NonholonomicOptions& options) {
  // dPhi/ds and C(s) from the fused generated function: they share most subexpressions.
  gen::kinematic_update(s, model.params(), nullptr, nullptr, nullptr, &d.dPhi_ds, &d.C, false);
  reduce(d);
  Eigen::Matrix<double, kNq, 1> q_rate = sdot.head<kNq>();
  q_rate(pair.index[0]) = 0;
  q_rate(pair.index[1]) = 0;
  d.J_beta.col(0) = d.C_reduced.col(pair.index[0]);
  d.J_beta.col(1) = d.C_reduced.col(pair.index[1]);
  d.cond_J_beta = condition_number(d.J_beta);
  if (!(d.cond_J_beta <= options.max_condition))
    throw Error("dependent",
                fmt::format("J_beta for the dependent pair {} is singular: condition number {:.3g} exceeds the threshold "
                            "{:.3g}. The two wheels' sideways constraint lines coincide (collinear wheel axes, thesis "
                            "4.1.4), e.g. both wheels on the same level under a level cabin. Raise one wheel (the "
                            "thesis uses z_Wr = 0.05 m) or choose another dependent pair.",
                            pair.label(), d.cond_J_beta, options.max_condition));
  const Eigen::Vector2d phi_hat = d.C_reduced * q_rate;
  const Eigen::Vector2d pair_rate = -d.J_beta.partialPivLu().solve(phi_hat);
  q_rate(pair.index[0]) = pair_rate(0);
  q_rate(pair.index[1]) = pair_rate(1);
  sdot.head<kNq>() = q_rate;
  const gen::ClosureVector closure_rhs = d.dPhi_ds.leftCols<kNq>() * q_rate;
  solve_closure(d, closure_rhs, sdot);
}

void solve_dependent_accelerations(const Model& model, const Coordinates& s, const Coordinates& sdot,
                                   Coordinates& sddot, const DependentPair& pair, Data& d) {
  gen::convective(s, sdot, model.params(), &d.dPhi_ds_dot_sdot, &d.C_dot_sdot);
  Eigen::Matrix<double, kNq, 1> q_acc = sddot.head<kNq>();
  q_acc(pair.index[0]) = 0;
  q_acc(pair.index[1]) = 0;
  // Phi_dep s''_dep = -(Phi_q q'' + conv_Phi) and C s'' + conv_C = 0 give
  // C_hat q'' = -(conv_C - Lambda^T conv_Phi).
  const Eigen::Vector2d rhs =
      d.C_reduced * q_acc + d.C_dot_sdot - d.wheel_adjoint.transpose() * d.dPhi_ds_dot_sdot;
  const Eigen::Vector2d pair_acc = -d.J_beta.partialPivLu().solve(rhs);
  q_acc(pair.index[0]) = pair_acc(0);
  q_acc(pair.index[1]) = pair_acc(1);
  sddot.head<kNq>() = q_acc;
  const gen::ClosureVector closure_rhs = d.dPhi_ds.leftCols<kNq>() * q_acc + d.dPhi_ds_dot_sdot;
  solve_closure(d, closure_rhs, sddot);
}

Eigen::Matrix<double, kCoordinateCount, 4> rate_basis(const std::array<int, 4>& commanded, const DependentPair& pair,
                                                      const Data& d) {
  // Input-rate columns: a unit commanded rate, and the pair's answer to it.
  Eigen::Matrix<double, 2, 4> ch;
  for (int k = 0; k < 4; ++k) ch.col(k) = d.C_reduced.col(commanded[static_cast<std::size_t>(k)]);
  const Eigen::Matrix<double, 2, 4> pair_rates = -d.J_beta.partialPivLu().solve(ch);
  Eigen::Matrix<double, kCoordinateCount, 4> T = Eigen::Matrix<double, kCoordinateCount, 4>::Zero();
  for (int k = 0; k < 4; ++k) {
    T(commanded[static_cast<std::size_t>(k)], k) = 1;
    T(pair.index[0], k) = pair_rates(0, k);
    T(pair.index[1], k) = pair_rates(1, k);
  }
  // Dependent joints: Phi_dep T_dep = -Phi_q T_q, all four columns per limb block at once.
  // T's input rows are zero except the commanded and the pair's: six columns of dPhi/ds, not 18.
  Eigen::Matrix<double, gen::kClosureCount, 4> rhs = Eigen::Matrix<double, gen::kClosureCount, 4>::Zero();
  std::array<int, 6> rows{commanded[0], commanded[1], commanded[2], commanded[3], pair.index[0], pair.index[1]};
  for (std::size_t r = 0; r < rows.size(); ++r) {
    bool seen = false;
    for (std::size_t q = 0; q < r; ++q) seen = seen || rows[q] == rows[r];
    if (!seen) rhs.noalias() += d.dPhi_ds.col(rows[r]) * T.row(rows[r]);
  }
  for_each_limb([&](auto L) {
    constexpr gen::LimbInfo b = gen::kLimbs[static_cast<std::size_t>(decltype(L)::value)];
    Eigen::Matrix4d block_rhs = Eigen::Matrix4d::Zero();
    for (int i = 0; i < b.size; ++i) block_rhs.row(i) = -rhs.row(b.rows[static_cast<std::size_t>(i)]);
    const Eigen::Matrix4d x = d.limb_inverse[static_cast<std::size_t>(decltype(L)::value)].lazyProduct(block_rhs);
    for (int j = 0; j < b.size; ++j) T.row(b.joints[static_cast<std::size_t>(j)]) = x.row(j);
  });
  return T;
}

Eigen::Matrix<double, 3, 2> contact_velocities(const Model& model, const Coordinates& s, const Coordinates& sdot,
                                               Data& d) {
  gen::kinematics(s, model.params(), nullptr, &d.frame_rotations);
  gen::nonholonomic(s, model.params(), &d.C, &d.spin, false);
  const Eigen::Vector2d spin = d.spin * sdot, sideways = d.C * sdot;
  Eigen::Matrix<double, 3, 2> v;
  for (int w = 0; w < 2; ++w) {
    const gen::WheelInfo& wheel = gen::kWheels[static_cast<std::size_t>(w)];
    const Eigen::Matrix3d& R = d.frame_rotations[static_cast<std::size_t>(wheel.contact_frame)];
    v.col(w) = R.col(wheel.forward_axis) * (model.params().*wheel.radius * spin(w)) + R.col(wheel.lateral_axis) * sideways(w) +
               Eigen::Vector3d::UnitZ() * sdot(wheel.ground);
  }
  return v;
}

Eigen::Vector2d sideways_velocity(const Model& model, const Coordinates& s, const Coordinates& sdot, Data& d) {
  gen::nonholonomic(s, model.params(), &d.C, nullptr, false);
  return d.C * sdot;
}

WLX_MODEL_NAMESPACE_END
