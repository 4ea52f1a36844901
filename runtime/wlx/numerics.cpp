// The model-independent numerics (numerics.hpp), compiled once for every model.
#include "wlx/numerics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>

namespace wlx::qp {

Result solve(const Eigen::MatrixXd& H, const Eigen::VectorXd& c, const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
             double tolerance, int max_iterations) {
  const Eigen::Index n = H.rows(), m = A.rows();
  Result out;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd s = (A * x - b).cwiseMax(1.0);
  Eigen::VectorXd lambda = Eigen::VectorXd::Ones(m);
  const double scale = 1 + std::max({H.cwiseAbs().maxCoeff(), c.cwiseAbs().maxCoeff(), m ? A.cwiseAbs().maxCoeff() : 0.0,
                                     m ? b.cwiseAbs().maxCoeff() : 0.0});
  Eigen::MatrixXd K(n, n);
  Eigen::LLT<Eigen::MatrixXd> llt(n);
  Eigen::VectorXd rd(n), rp(m), dx(n), ds(m), dl(m), rhs(n), w(m);
  // The Newton step for the residuals (rd, rp) and complementarity target r_sl = s o lambda - sigma mu:
  // eliminating ds = A dx + rp and dl = -(lambda o ds + r_sl) / s gives (H + A^T D A) dx = -rd - A^T (...).
  const auto step = [&](const Eigen::VectorXd& r_sl) {
    w = (lambda.cwiseProduct(rp) + r_sl).cwiseQuotient(s);  // D rp + r_sl / s
    rhs = -rd - A.transpose() * w;
    dx = llt.solve(rhs);
    ds = A * dx + rp;
    dl = -(lambda.cwiseProduct(ds) + r_sl).cwiseQuotient(s);
  };
  const auto max_step = [](const Eigen::VectorXd& v, const Eigen::VectorXd& dv) {
    double alpha = 1;
    for (Eigen::Index i = 0; i < v.size(); ++i)
      if (dv(i) < 0) alpha = std::min(alpha, -v(i) / dv(i));
    return alpha;
  };
  for (int it = 0; it < max_iterations; ++it) {
    rd = H * x + c - A.transpose() * lambda;
    rp = A * x - s - b;  // (primal residual, with the slack)
    const double mu = m ? s.dot(lambda) / static_cast<double>(m) : 0.0;
    out.gap = mu;
    out.residual = std::max(rd.cwiseAbs().maxCoeff(), m ? rp.cwiseAbs().maxCoeff() : 0.0) / scale;
    if (mu <= tolerance * scale && out.residual <= tolerance) {
      out.converged = true;
      break;
    }
    K = H;
    K.noalias() += A.transpose() * lambda.cwiseQuotient(s).asDiagonal() * A;
    llt.compute(K);
    if (llt.info() != Eigen::Success) break;
    // Predictor (affine scaling), then the corrector with Mehrotra's centring.
    step(s.cwiseProduct(lambda));
    const double a_aff = std::min(max_step(s, ds), max_step(lambda, dl));
    // Without constraints (m = 0) there is no complementarity to centre: mu and mu_aff are 0.
    const double mu_aff = m ? (s + a_aff * ds).dot(lambda + a_aff * dl) / static_cast<double>(m) : 0.0;
    const double sigma = mu > 0 ? std::pow(mu_aff / mu, 3) : 0.0;
    step(s.cwiseProduct(lambda) + ds.cwiseProduct(dl) - Eigen::VectorXd::Constant(m, sigma * mu));
    // 0.995 of the way to the boundary keeps s and lambda positive; without constraints the
    // Newton step of a quadratic is exact, and the whole of it is taken.
    const double alpha = m ? 0.995 * std::min(max_step(s, ds), max_step(lambda, dl)) : 1.0;
    x += alpha * dx;
    s += alpha * ds;
    lambda += alpha * dl;
    ++out.iterations;  // the steps taken, whether or not the next test converges
    if (!(x.allFinite() && s.allFinite() && lambda.allFinite())) break;
  }
  out.x = x;
  out.lambda = lambda;
  return out;
}

}  // namespace wlx::qp

namespace wlx::numerics {

Eigen::VectorXd smallest_eigenvector(const Eigen::Ref<const Eigen::MatrixXd>& S) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(S);  // eigenvalues in increasing order
  return eigen.eigenvectors().col(0);
}

Eigen::MatrixXd left_null_space(const Eigen::Ref<const Eigen::MatrixXd>& A) {
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::MatrixXd Q = qr.householderQ();
  return Q.rightCols(A.rows() - A.cols());
}

bool inverse_cholesky_factor(const Eigen::Ref<const Eigen::MatrixXd>& W, Eigen::MatrixXd& S) {
  const Eigen::LLT<Eigen::MatrixXd> llt(W);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::MatrixXd L = llt.matrixL();
  S = L.transpose().triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(W.rows(), W.cols()));
  return true;
}

int min_norm_solve_pivoted(const Eigen::Ref<const Eigen::MatrixXd>& M, const Eigen::Ref<const Eigen::VectorXd>& b,
                           double threshold, Eigen::Ref<Eigen::VectorXd> x) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  qr.setThreshold(threshold);
  qr.compute(M);
  const Eigen::Index n = M.cols();
  const int rank = static_cast<int>(qr.rank());
  if (rank < n) return rank;
  const Eigen::MatrixXd R = qr.matrixR().topLeftCorner(n, n).triangularView<Eigen::Upper>();
  const Eigen::VectorXd y = R.transpose().triangularView<Eigen::Lower>().solve(qr.colsPermutation().transpose() * b);
  Eigen::VectorXd full = Eigen::VectorXd::Zero(M.rows());
  full.head(n) = y;
  full.applyOnTheLeft(qr.householderQ());
  x = full;
  return rank;
}

}  // namespace wlx::numerics
