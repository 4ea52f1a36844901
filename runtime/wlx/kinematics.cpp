#include "wlx/kinematics.hpp"

WLX_MODEL_NAMESPACE_BEGIN

void forward_kinematics(const Model& model, Data& data, const Coordinates& s) noexcept {
  gen::kinematics(s, model.params(), &data.frame_positions, &data.frame_rotations);
}

void kinematic_update(const Model& model, Data& data, const Coordinates& s) noexcept {
  gen::kinematic_update(s, model.params(), &data.frame_positions, &data.frame_rotations, &data.Phi, &data.dPhi_ds,
                        &data.C, false);
}

void closure(const Model& model, Data& data, const Coordinates& s, bool with_jacobian) noexcept {
  gen::closure(s, model.params(), &data.Phi, with_jacobian ? &data.dPhi_ds : nullptr, false);
}

WLX_MODEL_NAMESPACE_END
