// Kane's sums on the commanded speeds written out over the bodies' full Jacobians from bodies():
// the independent reference for reduced_dynamics (tests/generated/test_reduced_dynamics.cpp) and
// the way it would be computed without it (wlx_bench's comparison row). For rates s' = T u:
//   P = [Jv; R^T Jw] T per body (angular rows in body axes), D = diag(m, m, m, I),
//   M = sum P^T D P, b_velocity = sum P^T [m Jv_dot s'; I R^T Jw_dot s' + omega x I omega],
//   B = sum P^T D [Jv; R^T Jw] (every column), Q_gravity = sum Pv^T m g.
#pragma once

#include <Eigen/Geometry>
#include <wlx/gen/all.hpp>

namespace wlx::test {

struct KaneSums {
  gen::CommandMatrix M;
  gen::CommandVector b_velocity, Q_gravity;
  gen::CommandRows B;
  // bodies()' outputs
  gen::BodyVectors com, Jv_dot, Jw_dot;
  gen::BodyRotations R;
  gen::BodyJacobians Jv, Jw;
};

inline void kane_over_bodies(const gen::Params& p, const gen::Coordinates& s, const gen::Coordinates& sdot,
                             const gen::RateBasis& T, KaneSums& out) {
  constexpr int kU = gen::kCommandedCount;
  gen::bodies(s, sdot, p,
              {.com = &out.com, .rotations = &out.R, .Jv = &out.Jv, .Jw = &out.Jw, .Jv_dot_sdot = &out.Jv_dot, .Jw_dot_sdot = &out.Jw_dot});
  out.M.setZero();
  out.b_velocity.setZero();
  out.Q_gravity.setZero();
  out.B.setZero();
  for (int i = 0; i < gen::kBodyCount; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const auto& info = gen::kBodyMass[k];
    const double m = p.*info.mass;
    const Eigen::Vector3d I(p.*info.inertia[0], p.*info.inertia[1], p.*info.inertia[2]);
    const Eigen::Matrix3d& R = out.R[k];
    Eigen::Matrix<double, 6, gen::kCoordinateCount> J;
    J << out.Jv[k], R.transpose() * out.Jw[k];
    const Eigen::Matrix<double, 6, kU> P = J * T;
    Eigen::Matrix<double, 6, 1> D;
    D << m, m, m, I;
    const Eigen::Matrix<double, kU, 6> PtD = P.transpose() * D.asDiagonal();
    out.M.noalias() += PtD * P;
    out.B.noalias() += PtD * J;
    const Eigen::Vector3d omega = R.transpose() * (out.Jw[k] * sdot);
    Eigen::Matrix<double, 6, 1> force;
    force << m * out.Jv_dot.col(i), I.cwiseProduct(R.transpose() * out.Jw_dot.col(i)) + omega.cross(I.cwiseProduct(omega));
    out.b_velocity.noalias() += P.transpose() * force;
    out.Q_gravity.noalias() += P.topRows<3>().transpose() * (m * Eigen::Vector3d(0, 0, -(p.*gen::kGravity)));
  }
}

}  // namespace wlx::test
