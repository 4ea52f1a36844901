#include "wlx/nonholonomic.hpp"

#include "wlx/error.hpp"
#include "wlx/ik.hpp"

#include <Eigen/SVD>
#include <fmt/format.h>

#include <cmath>
#include <limits>

namespace wlx {

namespace {

constexpr int kNq = kInputCount;

std::string_view name_of(int coordinate) { return gen::kCoordinateNames[static_cast<std::size_t>(coordinate)]; }

bool is_wheel_coupled(int coordinate) {
  for (int k : kWheelCoupledInputs)
    if (k == coordinate) return true;
  return false;
}

// Factorizes each limb's block of dPhi/ds and forms X = Phi_dep^-1 Phi_q and C_hat = C_q - C_dep X.
void reduce(Data& d) {
  for (Limb limb : kLimbs) {
    const LimbBlock b = limb_block(limb);
    Eigen::Matrix4d block = Eigen::Matrix4d::Identity();
    Eigen::Matrix<double, 4, kNq> rhs = Eigen::Matrix<double, 4, kNq>::Zero();
    for (int i = 0; i < b.size; ++i) {
      for (int j = 0; j < b.size; ++j) block(i, j) = d.dPhi_ds(b.first_row + i, b.joints[static_cast<std::size_t>(j)]);
      rhs.row(i) = d.dPhi_ds.block<1, kNq>(b.first_row + i, 0);
    }
    auto& lu = d.limb_lu[static_cast<std::size_t>(limb)];
    lu.compute(block);
    const Eigen::Matrix<double, 4, kNq> x = lu.solve(rhs);
    for (int j = 0; j < b.size; ++j) d.closure_sensitivity.row(b.joints[static_cast<std::size_t>(j)] - kNq) = x.row(j);
  }
  d.C_reduced = d.C.leftCols<kNq>() - d.C.rightCols<kDependentCount>() * d.closure_sensitivity;
}

// Phi_dep^-1 v, block by block with the factorizations of reduce().
gen::ClosureVector solve_closure(const Data& d, const gen::ClosureVector& v) {
  gen::ClosureVector out;
  for (Limb limb : kLimbs) {
    const LimbBlock b = limb_block(limb);
    Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
    for (int i = 0; i < b.size; ++i) rhs(i) = v(b.first_row + i);
    const Eigen::Vector4d x = d.limb_lu[static_cast<std::size_t>(limb)].solve(rhs);
    for (int j = 0; j < b.size; ++j) out(b.joints[static_cast<std::size_t>(j)] - kNq) = x(j);
  }
  return out;
}

double condition_number(const Eigen::Matrix2d& J) {
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(J);
  const double smax = svd.singularValues()(0), smin = svd.singularValues()(1);
  if (!std::isfinite(smax)) return std::numeric_limits<double>::infinity();
  return smin > 0 ? smax / smin : std::numeric_limits<double>::infinity();
}

}  // namespace

std::string DependentPair::label() const {
  return fmt::format("({}', {}')", name_of(index[0]), name_of(index[1]));
}

DependentPair dependent_pair(std::string_view first, std::string_view second, const std::string& field) {
  std::string valid;
  for (int k : kWheelCoupledInputs) valid += fmt::format("{}{}", valid.empty() ? "" : ", ", name_of(k));
  DependentPair pair;
  const std::string_view names[2] = {first, second};
  for (int i = 0; i < 2; ++i) {
    const int k = coordinate_index(names[i]);
    if (k < 0 || !is_wheel_coupled(k))
      throw Error(field, fmt::format("'{}' cannot be a dependent rate: choose 2 of {}", names[i], valid));
    pair.index[static_cast<std::size_t>(i)] = k;
  }
  if (pair.index[0] == pair.index[1])
    throw Error(field, fmt::format("the two dependent rates must differ, got '{}' twice", first));
  return pair;
}

void solve_dependent_rates(const Model& model, const Coordinates& s, Coordinates& sdot, const DependentPair& pair,
                           Data& d, const NonholonomicOptions& options) {
  gen::closure(s, model.params(), nullptr, &d.dPhi_ds);
  gen::nonholonomic(s, model.params(), &d.C, nullptr);
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
  sdot.tail<kDependentCount>() = -d.closure_sensitivity * q_rate;
}

void solve_dependent_accelerations(const Model& model, const Coordinates& s, const Coordinates& sdot,
                                   Coordinates& sddot, const DependentPair& pair, Data& d) {
  gen::convective(s, sdot, model.params(), &d.dPhi_ds_dot_sdot, &d.C_dot_sdot);
  const gen::ClosureVector y = solve_closure(d, d.dPhi_ds_dot_sdot);
  Eigen::Matrix<double, kNq, 1> q_acc = sddot.head<kNq>();
  q_acc(pair.index[0]) = 0;
  q_acc(pair.index[1]) = 0;
  // C s'' + (d/dt C) s' = 0 with s''_dep = -X q'' - y.
  const Eigen::Vector2d rhs = d.C_reduced * q_acc + d.C_dot_sdot - d.C.rightCols<kDependentCount>() * y;
  const Eigen::Vector2d pair_acc = -d.J_beta.partialPivLu().solve(rhs);
  q_acc(pair.index[0]) = pair_acc(0);
  q_acc(pair.index[1]) = pair_acc(1);
  sddot.head<kNq>() = q_acc;
  sddot.tail<kDependentCount>() = -d.closure_sensitivity * q_acc - y;
}

Eigen::Vector2d sideways_velocity(const Model& model, const Coordinates& s, const Coordinates& sdot, Data& d) {
  gen::nonholonomic(s, model.params(), &d.C, nullptr);
  return d.C * sdot;
}

}  // namespace wlx
