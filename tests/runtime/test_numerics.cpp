// The model-independent numerics (runtime/wlx/numerics.hpp), compiled once for every model: the
// QP against problems solved by hand (KKT conditions), and each decomposition against the
// property that defines it; and Newton's limb steps (runtime/wlx/limb_steps.hpp), which each
// model compiles at its own limb size, likewise; and the wheels' LU and condition number
// (runtime/wlx/small_dense.hpp) against Eigen's decompositions.
#include "wlx/limb_steps.hpp"
#include "wlx/numerics.hpp"
#include "wlx/small_dense.hpp"

#include <doctest/doctest.h>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <random>

TEST_CASE("qp::solve: an unconstrained problem (no rows) is solved in one exact step; x = -H^-1 c") {
  Eigen::MatrixXd H(2, 2);
  H << 4, 1, 1, 3;
  const Eigen::VectorXd c = Eigen::Vector2d(1, -2);
  const wlx::qp::Result r = wlx::qp::solve(H, c, Eigen::MatrixXd(0, 2), Eigen::VectorXd(0));
  REQUIRE(r.converged);
  CHECK(r.iterations == 1);
  // x = -H^-1 c = -(1/11) [3 -1; -1 4] [1; -2] = [-5/11; 9/11], to rounding (H's condition is 2).
  CHECK((r.x - Eigen::Vector2d(-5.0 / 11, 9.0 / 11)).norm() <= 1e-14);
  CHECK(r.lambda.size() == 0);
}

TEST_CASE("qp::solve: an active row: min 1/2 |x|^2 - x1 - x2 with x1 + x2 <= 1 gives x = (1/2, 1/2), multiplier 1/2") {
  // KKT: x - (1, 1) - A^T lambda = 0 with A = [-1 -1] (the row -x1 - x2 >= -1), active:
  // x_i = 1 - lambda and x1 + x2 = 1, so lambda = 1/2.
  const Eigen::MatrixXd H = Eigen::MatrixXd::Identity(2, 2);
  const Eigen::VectorXd c = Eigen::Vector2d(-1, -1);
  Eigen::MatrixXd A(2, 2);
  A << -1, -1, 1, 0;  // and x1 >= -5, which stays inactive (multiplier 0)
  const Eigen::VectorXd b = Eigen::Vector2d(-1, -5);
  const wlx::qp::Result r = wlx::qp::solve(H, c, A, b);
  REQUIRE(r.converged);
  // The interior-point method stops at a complementarity gap of 1e-11 of the data's scale (2):
  // the solution and the multipliers are that close to the exact ones.
  CHECK((r.x - Eigen::Vector2d(0.5, 0.5)).norm() <= 1e-9);
  CHECK(std::abs(r.lambda(0) - 0.5) <= 1e-9);
  CHECK(std::abs(r.lambda(1)) <= 1e-9);
  CHECK(r.iterations >= 1);
  CHECK(r.iterations < 120);
}

TEST_CASE("qp::solve: rows no x satisfies (x >= 1 and x <= 0) end without converging") {
  const Eigen::MatrixXd H = Eigen::MatrixXd::Constant(1, 1, 1.0);
  Eigen::MatrixXd A(2, 1);
  A << 1, -1;
  const wlx::qp::Result r = wlx::qp::solve(H, Eigen::VectorXd::Zero(1), A, Eigen::Vector2d(1, 0), 1e-11, 60);
  CHECK_FALSE(r.converged);
  CHECK(r.iterations <= 60);
}

TEST_CASE("numerics: the smallest eigenvector, the left null space and the inverse Cholesky factor, by what defines them") {
  Eigen::MatrixXd S = Eigen::Vector3d(3, 1, 2).asDiagonal();
  const Eigen::VectorXd v = wlx::numerics::smallest_eigenvector(S);
  CHECK(std::abs(std::abs(v(1)) - 1) <= 1e-15);
  CHECK(std::abs(v(0)) + std::abs(v(2)) <= 1e-15);

  Eigen::MatrixXd A(4, 2);
  A << 1, 2, 0, 1, 3, -1, 2, 0.5;
  const Eigen::MatrixXd N = wlx::numerics::left_null_space(A);
  REQUIRE(N.rows() == 4);
  REQUIRE(N.cols() == 2);
  CHECK((A.transpose() * N).norm() <= 1e-14);                                // in the null space of A^T
  CHECK((N.transpose() * N - Eigen::Matrix2d::Identity()).norm() <= 1e-14);  // orthonormal

  Eigen::MatrixXd W(3, 3);
  W << 4, 1, 0.5, 1, 3, 0.2, 0.5, 0.2, 2;
  Eigen::MatrixXd F;
  REQUIRE(wlx::numerics::inverse_cholesky_factor(W, F));
  CHECK((F * F.transpose() - W.inverse()).norm() <= 1e-14);  // S S^T = W^-1
  CHECK((F.transpose() * W * F - Eigen::Matrix3d::Identity()).norm() <= 1e-14);
  W(2, 2) = -1;  // indefinite
  Eigen::MatrixXd untouched = Eigen::MatrixXd::Constant(1, 1, 7.0);
  CHECK_FALSE(wlx::numerics::inverse_cholesky_factor(W, untouched));
  CHECK(untouched(0, 0) == 7.0);
}

// Newton's limb steps by what defines them, at one joint (a lever), at a leg's three and at nine
// (beyond any built-in model): J step = -r; the normal equations of the damped problems; no step
// for a singular or too badly conditioned J, and the step then left as it was. The residual bounds
// are about a hundred times N eps ||J||^2 ||step|| (J's entries are at most 4, the steps O(1)):
// they pass the rounding of any backward-stable solve and fail a wrong sign, pivot or scale.
template <int N>
void check_limb_steps() {
  CAPTURE(N);
  using namespace wlx::limb_steps;
  Square<N> J;
  Column<N> r;
  for (int i = 0; i < N; ++i) {
    r(i) = std::cos(1.0 + i);
    for (int j = 0; j < N; ++j) J(i, j) = (i == j ? 3.0 : 0.0) + std::sin(1.0 + 2 * i + 3 * j);
  }
  Column<N> step = Column<N>::Zero();
  REQUIRE(newton_step<N>(J, r, step));
  CHECK((J * step + r).cwiseAbs().maxCoeff() <= 1e-13);
  const auto check_damped = [&](const Square<N>& A, const char* what) {
    INFO(what);
    const double mu = 0.25;
    const Column<N> damped = damped_step<N>(A, r, mu), regularized = regularized_step<N>(A, r, mu);
    const Square<N> normal = A.transpose() * A + mu * Square<N>::Identity();
    CHECK((normal * damped + A.transpose() * r).cwiseAbs().maxCoeff() <= 1e-12);
    CHECK((normal * regularized + A.transpose() * r).cwiseAbs().maxCoeff() <= 1e-12);
  };
  check_damped(J, "a regular J");
  Column<N> untouched = Column<N>::Constant(7.0);
  if constexpr (N >= 2) {
    // A singular J (two equal rows) has no Newton step: the step is left as it was. The damped
    // steps, there for such a J, still solve their normal equations.
    Square<N> singular = J;
    singular.row(1) = singular.row(0);
    CHECK(!newton_step<N>(singular, r, untouched));
    CHECK(untouched == Column<N>::Constant(7.0));
    check_damped(singular, "a singular J");
    // Full rank but conditioned past the 1e-12 bound (1-norm condition 1e13): no Newton step
    // either; at 1e11 the step is taken, and solves the system.
    Square<N> ill = Square<N>::Identity();
    ill(1, 1) = 1e-13;
    CHECK(!newton_step<N>(ill, r, untouched));
    CHECK(untouched == Column<N>::Constant(7.0));
    ill(1, 1) = 1e-11;
    REQUIRE(newton_step<N>(ill, r, step));
    CHECK(std::abs(step(1) + r(1) * 1e11) <= 1e-14 * std::abs(r(1)) * 1e11);  // a diagonal solve: a rounding or two
    CHECK((ill * step + r).cwiseAbs().maxCoeff() <= 1e-15);
  } else {
    // One joint: a zero derivative has no Newton step.
    CHECK(!newton_step<N>(Square<N>::Zero(), r, untouched));
    CHECK(untouched == Column<N>::Constant(7.0));
    check_damped(Square<N>::Zero(), "a zero J");
  }
}

TEST_CASE("limb_steps: Newton's and the damped steps at a limb's size and beyond it") {
  check_limb_steps<1>();
  check_limb_steps<3>();
  check_limb_steps<9>();
}

TEST_CASE("numerics::min_norm_solve_pivoted: the minimum-norm solution of M^T x = b, and the rank where M loses it") {
  // M 6 x 3 of full rank: x solves M^T x = b and lies in M's column space (so it has the least
  // norm of all solutions: any other differs by a null-space vector of M^T, orthogonal to it).
  Eigen::MatrixXd M(6, 3);
  M << 1, 2, 0, 0, 1, 1, 3, 0, 1, 1, 1, 1, 0, 2, 5, 4, 0, 1;
  const Eigen::VectorXd b = Eigen::Vector3d(1, -2, 0.5);
  Eigen::VectorXd x(6);
  REQUIRE(wlx::numerics::min_norm_solve_pivoted(M, b, 1e-13, x) == 3);
  // M's entries are at most 5 and its condition number is about 3: residuals at rounding level.
  CHECK((M.transpose() * x - b).norm() <= 1e-13);
  const Eigen::MatrixXd P = M * (M.transpose() * M).inverse() * M.transpose();  // projector onto range(M)
  CHECK((P * x - x).norm() <= 1e-13);
  // A third column that is the sum of the first two: rank 2, and x is left as it was.
  M.col(2) = M.col(0) + M.col(1);
  Eigen::VectorXd untouched = Eigen::VectorXd::Constant(6, 7.0);
  CHECK(wlx::numerics::min_norm_solve_pivoted(M, b, 1e-13, untouched) == 2);
  CHECK(untouched == Eigen::VectorXd::Constant(6, 7.0));
}

namespace {

// The LU's solves and the condition number at size N against Eigen's PartialPivLU and JacobiSVD, on
// random matrices with singular values from 1 down to 10^-k (U diag V^T with random orthogonal U, V).
// The references are Eigen's dynamic-size decompositions: one instantiation of each for the six
// sizes (fixed-size ones took about 20 s of this file's compile, sanitized 50 s); below its
// blocking size Eigen runs the same unblocked elimination on either.
using Dense = Eigen::MatrixXd;
template <int N>
void check_small_dense(std::mt19937& random) {
  using Square = Eigen::Matrix<double, N, N>;
  using Column = Eigen::Matrix<double, N, 1>;
  std::normal_distribution<double> normal;
  const auto gaussian = [&] { return Square::NullaryExpr([&](Eigen::Index, Eigen::Index) { return normal(random); }); };
  for (int trial = 0; trial < 200; ++trial) {
    const int k = trial % 11;  // condition numbers 1 to 1e10
    const Square U = Dense(Eigen::HouseholderQR<Dense>(Dense(gaussian())).householderQ());
    const Square V = Dense(Eigen::HouseholderQR<Dense>(Dense(gaussian())).householderQ());
    Column sigma;
    for (int i = 0; i < N; ++i) sigma(i) = N == 1 ? 1.0 : std::pow(10.0, -k * double(i) / (N - 1));
    const Square A = U * sigma.asDiagonal() * V.transpose();
    const Column b = Column::NullaryExpr([&](Eigen::Index) { return normal(random); });

    wlx::small::PartialPivotLu<N> lu;
    lu.compute(A);
    const Eigen::PartialPivLU<Dense> eigen{Dense(A)};
    Eigen::Matrix<double, N, 2> B;
    B << b, 2 * b;
    lu.solve_in_place(B);
    const Column x_eigen = eigen.solve(Eigen::VectorXd(b)), xt_eigen = eigen.transpose().solve(Eigen::VectorXd(b));
    Column xt;
    lu.solve_transposed(b, xt);
    // Both are backward stable and pivot the same way: the solutions agree to the condition
    // number times rounding, and the residuals are at rounding relative to |A| |x|.
    const double cond = sigma(0) / sigma(N - 1);
    CHECK((B.col(0) - x_eigen).norm() <= 1e-14 * cond * x_eigen.norm());
    CHECK((B.col(1) - 2 * x_eigen).norm() <= 2e-14 * cond * x_eigen.norm());
    CHECK((xt - xt_eigen).norm() <= 1e-14 * cond * xt_eigen.norm());
    // The same elimination in the same order: the same pivots, and factors equal to a few ulp of
    // the largest entry (the compilers may contract a multiply-add differently).
    const Square eigen_lu = eigen.matrixLU();
    CHECK((lu.lu - eigen_lu).cwiseAbs().maxCoeff() <= 8 * std::numeric_limits<double>::epsilon() * eigen_lu.cwiseAbs().maxCoeff());
    const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic> eigen_inverse = eigen.permutationP().transpose();  // row k of P A is A's row [k]
    const Eigen::VectorXi eigen_rows = eigen_inverse.indices();
    for (int i = 0; i < N; ++i) CHECK(lu.row[i] == eigen_rows(i));
    CHECK((A * B.col(0) - b).norm() <= 1e-14 * N * (1 + A.norm() * B.col(0).norm()));
    CHECK((A.transpose() * xt - b).norm() <= 1e-14 * N * (1 + A.norm() * xt.norm()));

    // The condition number against Eigen's SVD of the same stored A: any backward-stable method
    // finds sigma_min to about eps sigma_max, so the two agree to a relative 1e-14 cond (1e-4 at
    // 1e10, 1e-14 at 1), and both to the construction's sigma (whose rounding is of that order too).
    const Column sv = Eigen::JacobiSVD<Dense>(Dense(A)).singularValues();
    const double mine = wlx::small::condition_number<N>(A), eigens = sv(0) / sv(N - 1);
    CHECK(std::abs(mine - eigens) <= 1e-14 * cond * eigens);
    CHECK(std::abs(mine - cond) <= 1e-14 * cond * cond);

    // The Cholesky solve of the symmetric positive definite A A^T (condition cond^2, up to 1e10)
    // against Eigen's LLT, the same elimination: agreement to cond^2 times rounding.
    if (k <= 5) {
      const Square S = A * A.transpose();
      Column y;
      REQUIRE(wlx::small::cholesky_solve<N>(S, b, y));
      const Column y_eigen = Eigen::LLT<Dense>(Dense(S)).solve(Eigen::VectorXd(b));
      CHECK((y - y_eigen).norm() <= 1e-14 * cond * cond * y_eigen.norm());
      CHECK((S * y - b).norm() <= 1e-14 * N * (1 + S.norm() * y.norm()));
    }
  }
  // A structured matrix: a zero leading entry (a row swap first) and an exactly zero pivot later
  // (a singular A), factorized as Eigen does.
  if constexpr (N >= 2) {
    Square structured = Square::Identity();
    structured(0, 0) = 0;
    structured(1, 0) = 2;
    structured.row(N - 1) = structured.row(0);  // with N = 2: rows (0 1), (0 1) after the swap: singular
    wlx::small::PartialPivotLu<N> lu;
    lu.compute(structured);
    const Eigen::PartialPivLU<Dense> eigen{Dense(structured)};
    const Square eigen_lu = eigen.matrixLU();
    CHECK((lu.lu - eigen_lu).cwiseAbs().maxCoeff() == 0);
    const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic> eigen_inverse = eigen.permutationP().transpose();  // row k of P A is A's row [k]
    const Eigen::VectorXi eigen_rows = eigen_inverse.indices();
    for (int i = 0; i < N; ++i) CHECK(lu.row[i] == eigen_rows(i));
    CHECK(wlx::small::condition_number<N>(structured) >= 1e15);
  }
  // Scaled far from 1 (entries near 1e200 and 1e-200), the condition number is the same: no squared
  // norm overflows or underflows.
  {
    Square A = Square::Identity();
    if constexpr (N >= 2) A(0, 1) = 1;
    const double reference = wlx::small::condition_number<N>(A);
    CHECK(std::abs(wlx::small::condition_number<N>(Square(1e200 * A)) - reference) <= 1e-14 * reference);
    CHECK(std::abs(wlx::small::condition_number<N>(Square(1e-200 * A)) - reference) <= 1e-14 * reference);
  }
  // A matrix that is not positive definite (a negative or a zero pivot) has no Cholesky factor:
  // refused, with x untouched. So is a NaN pivot, which Eigen's LLT would let through (its test is
  // pivot <= 0): forward dynamics checks M's finiteness first, to say so.
  Column untouched = Column::Constant(3.0);
  CHECK_FALSE(wlx::small::cholesky_solve<N>(Square(-Square::Identity()), Column::Ones(), untouched));
  CHECK_FALSE(wlx::small::cholesky_solve<N>(Square(Square::Zero()), Column::Ones(), untouched));
  Square nan_pivot = Square::Identity();
  nan_pivot(N - 1, N - 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(wlx::small::cholesky_solve<N>(nan_pivot, Column::Ones(), untouched));
  CHECK(untouched == Column::Constant(3.0));
  // Singular and non-finite matrices have an infinite condition number.
  Square singular = gaussian();
  if constexpr (N > 1) singular.col(N - 1) = singular.col(0);
  else singular.setZero();
  CHECK(wlx::small::condition_number<N>(singular) >= 1e15);
  Square nan = gaussian();
  nan(0, 0) = std::numeric_limits<double>::quiet_NaN();
  CHECK(wlx::small::condition_number<N>(nan) == std::numeric_limits<double>::infinity());
}

}  // namespace

TEST_CASE("small_dense: the LU, the condition number and the Cholesky solve agree with Eigen's at sizes 1 to 6") {
  std::mt19937 random(20261206);
  check_small_dense<1>(random);
  check_small_dense<2>(random);
  check_small_dense<3>(random);
  check_small_dense<4>(random);
  check_small_dense<5>(random);
  check_small_dense<6>(random);
}
