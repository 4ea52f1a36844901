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

void complete_tied_inputs(const Model& model, Data& data, Coordinates& s, Coordinates& sdot) noexcept {
  forward_kinematics(model, data, s);
  for (const auto& row : gen::kClosureRows)
    if (row.kind == gen::RowKind::point) s(row.target) = data.frame_positions(row.axis, row.frame);
  closure(model, data, s, true);
  // A point row is frame(s)[axis] - s_target: its own input's entry is -1, so the input's rate is
  // the rest of the row times the rates (no point row reads another row's input).
  for (std::size_t r = 0; r < gen::kClosureRows.size(); ++r) {
    const auto& row = gen::kClosureRows[r];
    if (row.kind != gen::RowKind::point) continue;
    double rate = 0;
    for (int k = 0; k < kCoordinateCount; ++k)
      if (k != row.target) rate += data.dPhi_ds(static_cast<int>(r), k) * sdot(k);
    sdot(row.target) = rate;
  }
}

WLX_MODEL_NAMESPACE_END
