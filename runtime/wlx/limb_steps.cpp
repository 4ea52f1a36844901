// Newton's steps on one limb's closure (numerics.hpp), compiled once for every model (wlx::numerics),
// and into the viewer's WebAssembly module, whose IK takes them.
#include "wlx/numerics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>

namespace wlx::numerics {

namespace {
// Bounded-size matrices: their storage is inline (no heap), sized at run time up to the bound.
using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxLimbJoints, kMaxLimbJoints>;
using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxLimbJoints, 1>;
using StackedMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * kMaxLimbJoints, kMaxLimbJoints>;
using StackedVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 2 * kMaxLimbJoints, 1>;
}  // namespace

void newton_step(const Eigen::Ref<const Eigen::MatrixXd>& J, const Eigen::Ref<const Eigen::VectorXd>& r,
                 Eigen::Ref<Eigen::VectorXd> step) noexcept {
  const SmallMatrix Js = J;
  const SmallVector rs = r;
  const Eigen::FullPivLU<SmallMatrix> lu(Js);
  if (lu.rcond() > 1e-12) {
    step = -lu.solve(rs);
    return;
  }
  const double mu = 1e-8 * std::max(1.0, Js.squaredNorm());
  SmallMatrix normal = Js.transpose().lazyProduct(Js);
  normal.diagonal().array() += mu;
  const SmallVector gradient = Js.transpose().lazyProduct(rs);
  step = -normal.ldlt().solve(gradient);
}

void damped_least_squares_step(const Eigen::Ref<const Eigen::MatrixXd>& J, const Eigen::Ref<const Eigen::VectorXd>& r, double mu,
                               Eigen::Ref<Eigen::VectorXd> step) noexcept {
  const Eigen::Index n = J.cols();
  StackedMatrix stacked(2 * n, n);
  stacked.topRows(n) = J;
  stacked.bottomRows(n) = std::sqrt(mu) * SmallMatrix::Identity(n, n);
  StackedVector rhs(2 * n);
  rhs.head(n) = -r;
  rhs.tail(n).setZero();
  step = stacked.householderQr().solve(rhs);
}

}  // namespace wlx::numerics
