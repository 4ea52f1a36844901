// Inverse dynamics with redundant actuation (thesis 6.3; docs/excavator.md section 7).
//
// The model file's dynamics section names the commanded speeds u (the excavator: z_C', x_C', roll',
// pitch'), the dependent pair the wheels determine (y_C', yaw') and the actuators; every other
// input is constant. With s' = T u and s'' = T u' + s''_bias from the non-holonomic solve, the
// bodies' equations projected on u give Q* = M u' + b - Q_gravity: inverse_dynamics by the recursive
// Newton-Euler equations (no M), equations_of_motion by composite rigid bodies (M, b, Q_gravity). The
// actuators share Q* by weighted least norm: J_beta^T tau = Q*, minimising tau^T W tau.
#pragma once

#include "wlx/model.hpp"
#include "wlx/nonholonomic.hpp"

#include <array>
#include <memory>
#include <string>

WLX_MODEL_NAMESPACE_BEGIN

// The commanded speeds u, the actuated joints and the pair the wheels make dependent: the model
// file's dynamics section (all empty without one: inverse_dynamics then throws). Sizes are
// compile-time, so every matrix below is fixed-size.
inline constexpr auto kCommandedSpeeds = gen::kCommanded;
// An actuator is a joint (kActuatedJoints: its coordinate) or a wheel's drive (kActuatedWheels: the
// wheel, whose spin relative to its hub is the drive's rate); -1 where not. kActuatorNames names
// them (the joint's coordinate, spin_<wheel> for a drive): the torques' order everywhere.
inline constexpr auto kActuatedJoints = gen::kActuated;
inline constexpr auto kActuatedWheels = gen::kActuatedWheels;
inline constexpr auto kActuatorNames = gen::kActuatorNames;
inline constexpr int kCommandedCount = static_cast<int>(kCommandedSpeeds.size());
inline constexpr int kActuatedCount = static_cast<int>(kActuatedJoints.size());
inline constexpr bool kHasWheelDrives = [] {
  for (int w : kActuatedWheels)
    if (w >= 0) return true;
  return false;
}();
static_assert(kActuatedCount >= kCommandedCount, "fewer actuators than commanded speeds: Q* cannot be produced");
inline DependentPair dynamics_pair() noexcept { return {gen::kPairs[gen::kDynamicsPair].coordinates}; }

using CommandVector = Eigen::Matrix<double, kCommandedCount, 1>;  // u, u', Q*
using CommandMatrix = Eigen::Matrix<double, kCommandedCount, kCommandedCount>;
using TorqueVector = Eigen::Matrix<double, kActuatedCount, 1>;  // tau, in kActuatorNames' order
using TorqueMatrix = Eigen::Matrix<double, kActuatedCount, kActuatedCount>;
using ActuatorJacobian = Eigen::Matrix<double, kActuatedCount, kCommandedCount>;

struct DynamicsTerms {
  Eigen::Matrix<double, kCoordinateCount, kCommandedCount> T;  // s' = T u
  Coordinates sdot;                                            // T u
  Coordinates sddot;                                           // T u' + s''_bias
  Coordinates sddot_bias;                                      // s''_bias: s'' at u' = 0
  CommandVector Qstar;                                         // M u' + b - Q_gravity
  // The bodies' inertia, velocity and gravity forces on every coordinate (generalized_forces' tau,
  // free with Q*; 0 on the held inputs): what contact_forces() balances. inverse_dynamics only.
  Coordinates tau_bodies = Coordinates::Zero();
  ActuatorJacobian J_beta;                                     // actuator rates beta' = J_beta u
  // Written by equations_of_motion() (inverse_dynamics needs none of them):
  CommandMatrix M;          // generalized mass matrix on u
  CommandVector b;          // velocity-dependent terms
  CommandVector Q_gravity;  // generalized gravity force
  // b = b_velocity + B_bias s''_bias (reduced_dynamics): the forces on u per unit bias
  // acceleration. Its structural zeros are written here, once; equations_of_motion never writes them.
  gen::CommandRows B_bias = gen::CommandRows::Zero();
};

// One inverse-dynamics step at s (closure satisfied) for speeds u and accelerations u_dot: T, s',
// s'', Q* and J_beta, what the torque split needs. Q* comes from the bodies' Newton-Euler equations
// (generalized_forces), without the mass matrix; equations_of_motion() adds M, b and Q_gravity.
// Uses and overwrites data's kinematic buffers; allocates nothing. Throws wlx::Error for a model
// file without a dynamics section (gen::kHasDynamics false).
void inverse_dynamics(const Model& model, Data& data, const Coordinates& s, const CommandVector& u,
                      const CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options = {});

// The equations of motion on the commanded speeds at s for speeds u, M u' + b - Q_gravity = Q*, by
// composite rigid bodies (reduced_dynamics, in one generated pass with the convective terms): T, s', s''_bias
// (and s'' at u' = 0), M, b, Q_gravity and J_beta; not Q*. For forward dynamics and whoever wants
// the mass matrix. With them, M u_dot + b - Q_gravity equals inverse_dynamics' Q* (two
// formulations; the tests compare them). Allocates nothing; throws as inverse_dynamics does.
void equations_of_motion(const Model& model, Data& data, const Coordinates& s, const CommandVector& u, DynamicsTerms& out,
                         const NonholonomicOptions& options = {});

// The wlx::Error every dynamics function throws for a model file without a dynamics section.
[[noreturn]] void throw_no_dynamics_section();

// Potential and kinetic energy of the bodies (for the energy checks).
double potential_energy(const Model& model, Data& data, const Coordinates& s);
// The whole machine's centre of mass in K0, from the bodies' centres that gen::bodies left in
// data.body_com (the energies, the momentum balance and the margins all sum it here).
Eigen::Vector3d centre_of_mass(const Model& model, const Data& data);
// A body's inertia about its centre of mass, in K0: its principal moments turned by its rotation R.
Eigen::Matrix3d world_inertia(const Params& p, int body, const Eigen::Matrix3d& R);
double kinetic_energy(const Model& model, Data& data, const Coordinates& s, const Coordinates& sdot);

struct Weighting {
  enum class Kind { model_weights, contribution, diagonal, matrix, contacts };
  Kind kind = Kind::model_weights;
  TorqueVector diagonal = TorqueVector::Ones();  // W for Kind::diagonal
  // For Kind::matrix, S = L^-T of the weight matrix W = L L^T (scaled to a largest entry of 1), which
  // matrix_of factorizes once; else null. Shared, so that a Weighting made at every step
  // (model_weights()) costs nothing, where a matrix member would write kActuatedCount^2 numbers each time.
  std::shared_ptr<const TorqueMatrix> matrix;
  std::string label() const;

  // The model file's default weights (dynamics.weights; the excavator's are the thesis' weighting 1).
  static Weighting model_weights() { return {}; }
  // Thesis 6.3.3 weighting 2: W_ii = 1 / |row i of J_beta|, recomputed at every step.
  static Weighting contribution() { return {Kind::contribution, TorqueVector::Ones(), nullptr}; }
  // Weighting 3: the torques that keep the machine on its contacts (contacts.hpp,
  // distribute_torques_on_contacts: it needs the step's contact forces, so distribute_torques
  // refuses it).
  static Weighting contacts() { return {Kind::contacts, TorqueVector::Ones(), nullptr}; }
  // Throws wlx::Error (field "weighting") unless every entry is positive and finite.
  static Weighting diagonal_of(const TorqueVector& w);
  // Throws unless symmetric positive definite.
  static Weighting matrix_of(const TorqueMatrix& W);
};

// The model file's default weights (settings().weights; for the excavator, thesis 6.3.3 weighting 1).
inline TorqueVector model_weight_diagonal() { return Eigen::Map<const TorqueVector>(settings().weights.data()); }

// tau = W^-1 J_beta (J_beta^T W^-1 J_beta)^-1 Q*, computed as the minimum-norm solution of the
// row-scaled system J_beta^T S x = Q*, tau = S x with S S^T = W^-1, which stays accurate where
// J_beta^T W^-1 J_beta is badly conditioned. Throws wlx::Error when J_beta's rank is below the number
// of commanded speeds.
TorqueVector distribute_torques(const ActuatorJacobian& J_beta, const CommandVector& Qstar, const Weighting& weighting);

WLX_MODEL_NAMESPACE_END
