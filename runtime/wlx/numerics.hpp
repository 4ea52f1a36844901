// Model-independent numerics, compiled once (the library wlx::numerics) rather than once per model:
// the small dense QP of the contact-keeping torque distribution, the decompositions that run off
// the hot paths (building a message, the null space of a distribution that then solves QPs), and
// Newton's IK steps. Every function takes dynamic-size matrices, so one compiled copy serves every
// model's sizes. Newton's steps work on bounded-size matrices (at most kMaxLimbJoints) and allocate
// nothing; the others allocate. The hot paths of a step (the fused update, the dependent rates,
// the inverse-dynamics step, forward dynamics) keep their fixed-size decompositions in the
// per-model runtime: there sizes known at compile time are the speed.
#pragma once

#include <Eigen/Core>

namespace wlx::qp {

struct Result {
  Eigen::VectorXd x;       // the solution
  Eigen::VectorXd lambda;  // the constraints' multipliers (>= 0)
  int iterations = 0;
  bool converged = false;
  double gap = 0;        // the mean complementarity s . lambda / m at the end
  double residual = 0;   // the largest relative primal or dual residual at the end
};

// A small dense convex quadratic programme, min 1/2 x^T H x + c^T x subject to A x >= b, by a
// primal-dual interior-point method with Mehrotra's predictor-corrector (Nocedal and Wright,
// Numerical Optimization, 2nd ed., algorithm 16.4). For the contact-keeping torque distribution:
// a handful of variables and up to a few hundred constraints per step, where a factorization of
// the n x n normal matrix per iteration costs microseconds. H is positive semidefinite, and
// H + A^T D A positive definite for positive D (every variable bounded by the constraints or
// penalized by H). Debian has no small dense QP solver library (OSQP, qpOASES and quadprog are not
// packaged for C++); docs/architecture.md says why this one.
//
// Converged when the complementarity and the residuals, relative to the data's scale, are below
// `tolerance`. A problem without a solution (infeasible constraints) ends with converged false.
Result solve(const Eigen::MatrixXd& H, const Eigen::VectorXd& c, const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
             double tolerance = 1e-11, int max_iterations = 120);

}  // namespace wlx::qp

namespace wlx::numerics {

// The most dependent joints one limb may have (wlx-gen refuses a larger limb): the bound of the
// bounded-size matrices Newton's IK steps use below, which therefore allocate nothing.
inline constexpr int kMaxLimbJoints = 16;

// One Newton step of a limb's closure, J step = -r, for a square J of at most kMaxLimbJoints rows:
// by LU with full pivoting where J's reciprocal condition estimate exceeds 1e-12, else (a singular
// pose: a straight leg, a lever at 90 degrees) the Levenberg-Marquardt step
// -(J^T J + mu I)^-1 J^T r with mu = 1e-8 max(1, |J|_F^2). Allocates nothing.
void newton_step(const Eigen::Ref<const Eigen::MatrixXd>& J, const Eigen::Ref<const Eigen::VectorXd>& r,
                 Eigen::Ref<Eigen::VectorXd> step) noexcept;

// The damped least-squares step argmin |J step + r|^2 + mu |step|^2, as the least-squares problem
// [J; sqrt(mu) I] step = [-r; 0] by QR (the normal equations would square J's condition number,
// 1e6 at the thesis' worst poses). J square, at most kMaxLimbJoints rows. Allocates nothing.
void damped_least_squares_step(const Eigen::Ref<const Eigen::MatrixXd>& J, const Eigen::Ref<const Eigen::VectorXd>& r, double mu,
                               Eigen::Ref<Eigen::VectorXd> step) noexcept;

// The eigenvector of the symmetric matrix `S` for its smallest eigenvalue (unit length; its sign
// as the eigensolver leaves it).
Eigen::VectorXd smallest_eigenvector(const Eigen::Ref<const Eigen::MatrixXd>& S);

// An orthonormal basis of the null space of A^T for a tall A (rows >= cols) of full column rank:
// the last rows - cols columns of Q in a full QR decomposition A = Q R.
Eigen::MatrixXd left_null_space(const Eigen::Ref<const Eigen::MatrixXd>& A);

// S = L^-T for the symmetric positive definite W = L L^T, so that S S^T = W^-1. Returns false
// (S untouched) when W is not positive definite to working precision.
bool inverse_cholesky_factor(const Eigen::Ref<const Eigen::MatrixXd>& W, Eigen::MatrixXd& S);

}  // namespace wlx::numerics
