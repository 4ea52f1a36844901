// Open-tree inverse dynamics from the generated body kinematics alone (Kane's sums over the bodies):
// what a peer library computes on the model's open tree (KDL's tree RNE in bench/kdl_peer.hpp,
// MuJoCo's mj_rne in tests/bench/test_mujoco_peer.cpp). Header-only, per model, no peer's headers.
#pragma once

#include <wlx/gen/all.hpp>
#include <wlx/model_namespace.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross

WLX_MODEL_NAMESPACE_BEGIN
namespace open_tree {

// The generalized force on every coordinate for s, s', s'' with gravity, no contact and no closure.
// Coordinates no body depends on get 0.
struct OpenTreeWorkspace {
  OpenTreeWorkspace() {
    for (auto& J : Jv) J.setZero();
    for (auto& J : Jw) J.setZero();
  }
  gen::BodyVectors com, Jv_dot_sdot, Jw_dot_sdot;
  gen::BodyRotations rotations;
  gen::BodyJacobians Jv, Jw;
};
inline void open_tree_inverse_dynamics(const gen::Params& p, const gen::Coordinates& s, const gen::Coordinates& sdot,
                                       const gen::Coordinates& sddot, OpenTreeWorkspace& w, gen::Coordinates& Q) {
  gen::bodies(s, sdot, p,
              {.com = &w.com, .rotations = &w.rotations, .Jv = &w.Jv, .Jw = &w.Jw, .Jv_dot_sdot = &w.Jv_dot_sdot, .Jw_dot_sdot = &w.Jw_dot_sdot},
              false);
  Q.setZero();
  const Eigen::Vector3d gravity(0, 0, -(p.*gen::kGravity));
  for (int b = 0; b < gen::kBodyCount; ++b) {
    const auto& info = gen::kBodyMass[static_cast<std::size_t>(b)];
    const auto& cols = gen::kBodyColumns[static_cast<std::size_t>(b)];
    const auto& Jv = w.Jv[static_cast<std::size_t>(b)];
    const auto& Jw = w.Jw[static_cast<std::size_t>(b)];
    const Eigen::Matrix3d& R = w.rotations[static_cast<std::size_t>(b)];
    const Eigen::Matrix3d I = R * Eigen::Vector3d(p.*info.inertia[0], p.*info.inertia[1], p.*info.inertia[2]).asDiagonal() * R.transpose();
    Eigen::Vector3d a = w.Jv_dot_sdot.col(b), omega = Eigen::Vector3d::Zero(), alpha = w.Jw_dot_sdot.col(b);
    for (int k = 0; k < cols.count; ++k) {
      const int c = cols.index[static_cast<std::size_t>(k)];
      a += Jv.col(c) * sddot(c);
      omega += Jw.col(c) * sdot(c);
      alpha += Jw.col(c) * sddot(c);
    }
    const Eigen::Vector3d force = p.*info.mass * (a - gravity);
    const Eigen::Vector3d torque = I * alpha + omega.cross(I * omega);
    for (int k = 0; k < cols.count; ++k) {
      const int c = cols.index[static_cast<std::size_t>(k)];
      Q(c) += Jv.col(c).dot(force) + Jw.col(c).dot(torque);
    }
  }
}

}  // namespace open_tree
WLX_MODEL_NAMESPACE_END
