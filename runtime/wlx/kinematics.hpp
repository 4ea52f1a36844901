// Forward kinematics over the generated functions (thesis 3.4).
#pragma once

#include "wlx/model.hpp"

#include <Eigen/Core>

WLX_MODEL_NAMESPACE_BEGIN

// Fills data.frame_positions and data.frame_rotations for the coordinates s.
void forward_kinematics(const Model& model, Data& data, const Coordinates& s) noexcept;

// Position and orientation in K0 of one frame after forward_kinematics.
inline Eigen::Vector3d frame_position(const Data& data, int frame) { return data.frame_positions.col(frame); }
inline const Eigen::Matrix3d& frame_rotation(const Data& data, int frame) {
  return data.frame_rotations[static_cast<std::size_t>(frame)];
}

// The per-step kinematic update in one generated pass: frame poses, Phi, dPhi/ds and C(s).
void kinematic_update(const Model& model, Data& data, const Coordinates& s) noexcept;

// Fills data.Phi and, when with_jacobian, data.dPhi_ds.
void closure(const Model& model, Data& data, const Coordinates& s, bool with_jacobian) noexcept;

WLX_MODEL_NAMESPACE_END
