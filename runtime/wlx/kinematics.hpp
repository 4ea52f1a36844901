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

// The inputs the closure's point rows tie to a frame (a contact's x, y, z on the ground), set from
// where that frame is, and their rates from those rows differentiated (0 = dPhi/ds s'): what a
// state measured on the machine's tree alone (a physics engine's joints and floating base) leaves
// out. The other coordinates of s and sdot are read, not changed. Leaves data's frames and
// dPhi/ds at the completed s.
void complete_tied_inputs(const Model& model, Data& data, Coordinates& s, Coordinates& sdot) noexcept;

WLX_MODEL_NAMESPACE_END
