// Inverse dynamics with redundant actuation (thesis 6.3; docs/excavator.md section 7).
//
// Commanded speeds u = [z_C', x_C', roll', pitch'], (y_C', yaw') dependent through the wheels,
// every other input constant. Kane's method on the 7 bodies, with s' = T u + 0 and
// s'' = T u' + s''_bias from the non-holonomic solve, gives Q* = M u' + b - Q_gravity. The 8
// actuators share Q* by weighted least norm: J_beta^T tau = Q*, minimising tau^T W tau.
#pragma once

#include "wlx/model.hpp"
#include "wlx/nonholonomic.hpp"

#include <array>
#include <string>

WLX_MODEL_NAMESPACE_BEGIN

static_assert(gen::kHasDynamics, "the model file has no dynamics section");
static_assert(gen::kHasClearance, "the model file has no clearance box");
static_assert(gen::kCommanded.size() == 4 && gen::kActuated.size() == 8,
              "the inverse dynamics is written for 4 commanded speeds and 8 actuators (fixed-size solves)");
// The commanded speeds u, the actuated joints and the pair the wheels make dependent: the model
// file's dynamics section.
inline constexpr std::array<int, 4> kCommandedSpeeds = gen::kCommanded;
inline constexpr std::array<int, 8> kActuatedJoints = gen::kActuated;
inline DependentPair dynamics_pair() noexcept { return {gen::kPairs[gen::kDynamicsPair].coordinates}; }

using Vector4 = Eigen::Vector4d;
using Vector8 = Eigen::Matrix<double, 8, 1>;
using ActuatorJacobian = Eigen::Matrix<double, 8, 4>;

struct DynamicsTerms {
  Eigen::Matrix<double, kCoordinateCount, 4> T;  // s' = T u
  Coordinates sdot;                               // T u
  Coordinates sddot;                              // T u' + s''_bias
  Eigen::Matrix4d M;                              // generalized mass matrix on u
  Vector4 b;                                      // velocity-dependent terms
  Vector4 Q_gravity;                              // generalized gravity force
  Vector4 Qstar;                                  // M u' + b - Q_gravity
  ActuatorJacobian J_beta;                        // beta' = J_beta u
};

// Q* and its parts at s (closure satisfied) for speeds u and accelerations u_dot. Uses and
// overwrites data's kinematic buffers; allocates nothing.
void inverse_dynamics(const Model& model, const Coordinates& s, const Vector4& u, const Vector4& u_dot, Data& data,
                      DynamicsTerms& out, const NonholonomicOptions& options = {});

// Potential and kinetic energy of the 7 bodies (for the energy checks).
double potential_energy(const Model& model, const Coordinates& s, Data& data);
double kinetic_energy(const Model& model, const Coordinates& s, const Coordinates& sdot, Data& data);

struct Weighting {
  enum class Kind { strong_weak, contribution, diagonal, matrix };
  Kind kind = Kind::strong_weak;
  Vector8 diagonal = Vector8::Ones();                     // W for Kind::diagonal
  Eigen::Matrix<double, 8, 8> matrix = Eigen::Matrix<double, 8, 8>::Identity();  // W for Kind::matrix
  std::string label() const;

  // Thesis 6.3.3 weighting 1: W = diag(0.01, 100, 1, 0.01, 100, 1, 0.01, 0.01).
  static Weighting strong_weak() { return {}; }
  // Thesis 6.3.3 weighting 2: W_ii = 1 / |row i of J_beta|, recomputed at every step.
  static Weighting contribution() { return {Kind::contribution, Vector8::Ones(), Eigen::Matrix<double, 8, 8>::Identity()}; }
  // Throws wlx::Error (field "weighting") unless every entry is positive and finite.
  static Weighting diagonal_of(const Vector8& w);
  // Throws unless symmetric positive definite.
  static Weighting matrix_of(const Eigen::Matrix<double, 8, 8>& W);
};

// The model file's default weights (for the excavator, thesis 6.3.3 weighting 1).
inline const Vector8 kStrongWeakDiagonal = Eigen::Map<const Vector8>(gen::kDefaultWeights.data());

// tau = W^-1 J_beta (J_beta^T W^-1 J_beta)^-1 Q*, computed as the minimum-norm solution of the
// row-scaled system J_beta^T S x = Q*, tau = S x with S S^T = W^-1, which stays accurate where
// J_beta^T W^-1 J_beta is badly conditioned. Throws wlx::Error when J_beta has rank below 4.
Vector8 distribute_torques(const ActuatorJacobian& J_beta, const Vector4& Qstar, const Weighting& weighting);

WLX_MODEL_NAMESPACE_END
