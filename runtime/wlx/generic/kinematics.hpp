// Forward kinematics and the loop closure over a model's generated functions, at run-time sizes
// (wlx/kinematics.hpp is the model's own runtime's).
#pragma once

#include "wlx/generic/model.hpp"

namespace wlx::generic {

// Fills data.frame_positions and data's frame rotations for the coordinates s.
void forward_kinematics(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& s);

// Fills data.Phi and, when with_jacobian, data.dPhi_ds.
void closure(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& s, bool with_jacobian);

}  // namespace wlx::generic
