// Model-independent numerics, compiled once (the library wlx::numerics) rather than once per model:
// the small dense QP of the contact-keeping torque distribution and the decompositions that run off
// the hot paths (building a message, the null space of a distribution that then solves QPs, the
// pivoted QR where the inverse dynamics' fixed-size fast path declines). Every
// function takes dynamic-size matrices, so one compiled copy serves every model's sizes. The hot
// paths (the fused update, the dependent rates, the inverse-dynamics step, forward dynamics, Newton's
// IK steps) keep fixed sizes in the per-model runtime (as loops where Eigen's decompositions would
// unroll: small_dense.hpp, limb_steps.hpp): there sizes known at compile time are the speed, and
// they allocate nothing; these functions allocate.
#pragma once

#include <Eigen/Core>

namespace wlx::qp {

struct Result {
  Eigen::VectorXd x;       // the solution
  Eigen::VectorXd lambda;  // the constraints' multipliers (>= 0)
  int iterations = 0;      // the interior-point steps taken
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

// The eigenvector of the symmetric matrix `S` for its smallest eigenvalue (unit length; its sign
// as the eigensolver leaves it).
Eigen::VectorXd smallest_eigenvector(const Eigen::Ref<const Eigen::MatrixXd>& S);

// An orthonormal basis of the null space of A^T for a tall A (rows >= cols) of full column rank:
// the last rows - cols columns of Q in a full QR decomposition A = Q R.
Eigen::MatrixXd left_null_space(const Eigen::Ref<const Eigen::MatrixXd>& A);

// S = L^-T for the symmetric positive definite W = L L^T, so that S S^T = W^-1. Returns false
// (S untouched) when W is not positive definite to working precision.
bool inverse_cholesky_factor(const Eigen::Ref<const Eigen::MatrixXd>& W, Eigen::MatrixXd& S);

// The minimum-norm x with M^T x = b for a tall M (rows >= cols), from the column-pivoted
// (rank-revealing) Householder QR M P = Q R: x = Q [R^-T P^T b; 0]. Returns M's rank, counting the
// pivots above `threshold` times the largest; x is written only when the rank is full (cols). For
// the poses where the inverse dynamics' fixed-size unpivoted fast path declines: off the hot path,
// and at fixed sizes the pivoted QR alone cost 3.7 s of each model's compile.
int min_norm_solve_pivoted(const Eigen::Ref<const Eigen::MatrixXd>& M, const Eigen::Ref<const Eigen::VectorXd>& b,
                           double threshold, Eigen::Ref<Eigen::VectorXd> x);

}  // namespace wlx::numerics
