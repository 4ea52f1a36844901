// A model's machine in a physics engine (MuJoCo 2.2.2, Debian's libmujoco-dev): the model exported
// as `wlx export mjcf` writes it (mjcf_export.hpp), driven by torques and read back in wlx's
// coordinates. Compiled once into wlx, from the description alone: it names no model and reads no
// generated function; MuJoCo's types stay inside physics_engine.cpp. Built without MuJoCo, the
// constructor throws and physics_engine_missing() says why.
//
// Coordinates: each hinge and slide joint is the coordinate of its name; a floating base is
// MuJoCo's free joint, qpos = (x, y, z, quaternion of R = R_a1(q1) R_a2(q2) R_a3(q3)) and qvel =
// (world velocity, body-frame angular velocity) = G(s) s'. The inputs the closure ties to a
// contact (its x, y, z on the ground) are no joint of MuJoCo's: the caller completes them from
// the tree (complete_tied_inputs in the runtime's kinematics.hpp).
#pragma once

#include <Eigen/Core>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace wlx::cli {

// Why this wlx has no physics engine; empty when it has one.
std::string physics_engine_missing();

// One contact of the model (the description's `contacts`, in order) as MuJoCo sees it.
struct EngineContact {
  std::string name;
  // The ground's force on it along z (the sum over MuJoCo's contacts on its geom), N.
  double normal = 0;
  // The horizontal speed of its material point at the ground (a wheel's lowest point, a foot's),
  // m/s: what wlx's rolling and its feet hold at zero.
  double slip = 0;
};

// MuJoCo's coordinates of a state of wlx's: qpos, and qvel = G s', qacc = G s'' + G' s' (MuJoCo's
// dofs in its order; a wheel's spin is no coordinate of wlx's: its rows of G are zero).
struct EngineMapping {
  Eigen::MatrixXd G;  // dofs x coordinates
  Eigen::VectorXd Gdot_sdot, qpos;
};

// A floating base: the frame whose free joint it is, its position coordinates (x, y, z) and its
// angles with their axes (0 x, 1 y, 2 z), R = R_axis0(angle0) R_axis1(angle1) R_axis2(angle2).
struct EngineFreeBase {
  std::string frame;
  std::array<int, 3> position{}, angle{}, axis{};
};

class PhysicsEngine {
 public:
  // MuJoCo's model of the description (model.json's text); `coordinates`: the model's coordinate
  // names in order. Throws wlx::Error naming the field for what the export cannot express, or
  // naming MuJoCo's complaint.
  PhysicsEngine(const std::string& description_json, const std::vector<std::string>& coordinates);
  ~PhysicsEngine();
  PhysicsEngine(const PhysicsEngine&) = delete;
  PhysicsEngine& operator=(const PhysicsEngine&) = delete;

  double timestep() const;  // s: the export's option timestep
  EngineMapping mapping(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& sdot) const;
  const std::vector<EngineFreeBase>& free_bases() const;

  // Sets the machine to wlx's state, at rest in the wheels' spins but for rolling: each spinning
  // wheel turns so that its lowest point moves as little as it can sideways and forward.
  void set_state(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& sdot);
  // MuJoCo's state in wlx's coordinates, where the tree has them (the floating base's angles, the
  // joints); the other entries of s and sdot are left as they are, and the base's angles are read
  // as the nearest to those in s (no jump of 2 pi). The rates by least squares on qvel = G s' (a
  // wheel's spin is no coordinate of wlx's).
  void read_state(Eigen::Ref<Eigen::VectorXd> s, Eigen::Ref<Eigen::VectorXd> sdot) const;
  // Each actuator's torque or force (the description's `actuated`, in order) until the next call.
  // Returns what MuJoCo applies: tau within each motor's range (the export's `ctrlrange`, from the
  // model's torque limits), which MuJoCo clamps to. A torque that is not finite or beyond MuJoCo's
  // bound (mjMAXVAL, 1e10) is an error naming its actuator ("tau").
  Eigen::VectorXd set_torques(const Eigen::Ref<const Eigen::VectorXd>& tau);
  void step();
  // Why MuJoCo's simulation can no longer be trusted (it met accelerations, a state or controls that
  // were not finite or too large and reset itself, as MuJoCo does then, with its warning), or empty.
  std::string trouble() const;
  // The contacts now (the forces of the last step).
  std::vector<EngineContact> contacts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wlx::cli
