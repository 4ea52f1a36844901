// Pinocchio 3 as an optional peer (built when -DWLX_PINOCCHIO_DIR names its source tree; Debian has
// no package): a robot loaded from its URDF by Pinocchio's own parser, and its algorithms, behind
// an interface that names no Pinocchio type, so that only bench/pinocchio_peer.cpp compiles its
// headers (about a minute). The benchmark rows themselves are registered there too, on the same
// URDF as the model of WLX_PINOCCHIO_MODEL (bench_main.cpp sets them beside wlx's rows).
#pragma once

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace wlx_peer {

// How the URDF's root is joined to the world: Pinocchio's free flyer (position and unit
// quaternion, twist in the base frame: what a Pinocchio user takes, and the speed rows), or six
// joints x, y, z, then rotations about z, y, x (a composite joint): a base posed by wlx's
// coordinates x, y, z, yaw, pitch, roll, R = Rz(yaw) Ry(pitch) Rx(roll), with their rates as
// velocities (the agreement test).
enum class Root { free_flyer, euler_zyx };

class PinocchioRobot {
 public:
  PinocchioRobot(const std::string& urdf_file, Root root);
  ~PinocchioRobot();
  PinocchioRobot(const PinocchioRobot&) = delete;
  PinocchioRobot& operator=(const PinocchioRobot&) = delete;

  int nv() const;
  // Where joint `name`'s configuration and velocity start (-1 for no such joint); the root's are 0.
  int q_index(const std::string& name) const;
  int v_index(const std::string& name) const;
  int q_size(const std::string& name) const;  // 1 for a revolute joint, 2 for a continuous one (cos, sin)
  Eigen::VectorXd neutral() const;

  // The world placements of the frames of URDF links `links` at q (each a 3 x 4 [R | p]), from one
  // forward-kinematics pass; throws for a name that is no link.
  std::vector<Eigen::Matrix<double, 3, 4>> link_placements(const Eigen::VectorXd& q, const std::vector<std::string>& links);
  // The open tree's generalized forces with gravity (rnea).
  Eigen::VectorXd inverse_dynamics(const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& a);
  // Every joint's Jacobian in the world frame, 6 x nv, [v; omega] (computeJointJacobians' data.J).
  Eigen::MatrixXd joint_jacobians(const Eigen::VectorXd& q);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Registers the rows <model>/pinocchio_fk (framesForwardKinematics), _rnea, _crba, _aba and
// _jacobians (computeJointJacobians) on the URDF, loaded with a free flyer (wlx_bench only).
void register_pinocchio_benchmarks(const std::string& model, const std::string& urdf);
}  // namespace wlx_peer
