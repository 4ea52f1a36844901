#include "wlx/kinematics.hpp"

WLX_MODEL_NAMESPACE_BEGIN

void forward_kinematics(const Model& model, Data& data, const Coordinates& s) noexcept {
  gen::kinematics(s, model.params(), {.positions = &data.frame_positions, .rotations = &data.frame_rotations});
}

void kinematic_update(const Model& model, Data& data, const Coordinates& s) noexcept {
  gen::kinematic_update(s, model.params(),
                        {.positions = &data.frame_positions,
                         .rotations = &data.frame_rotations,
                         .Phi = &data.Phi,
                         .dPhi_ds = &data.dPhi_ds,
                         .C = &data.C},
                        false);
}

void closure(const Model& model, Data& data, const Coordinates& s, bool with_jacobian) noexcept {
  gen::closure(s, model.params(), {.Phi = &data.Phi, .dPhi_ds = with_jacobian ? &data.dPhi_ds : nullptr}, false);
}

WLX_MODEL_NAMESPACE_END
