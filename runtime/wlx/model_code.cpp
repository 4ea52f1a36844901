// This model's code for the generic runtime (wlx/model_code.hpp): the generated functions on a
// workspace of the model's own fixed-size types, behind plain function pointers.
#include "wlx/model_code.hpp"

#include "wlx/ik.hpp"
#include "wlx/model.hpp"

#include <array>
#include <cstddef>
#include <new>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

struct Workspace {
  Workspace() {
    s.setZero();
    frame_positions.setZero();
    for (auto& R : frame_rotations) R.setZero();
    Phi.setZero();
    // Called with zero_fill = false, as the model's own runtime calls it (model.hpp, Data): the
    // structural zeros are written once, here.
    dPhi_ds.setZero();
    sdot.setZero();
    C.setZero();
    spin.setZero();
    dPhi_ds_dot_sdot.setZero();
    C_dot_sdot.setZero();
    for (std::size_t k = 0; k < gen::kParamInfo.size(); ++k) param_storage[k] = &(params.*gen::kParamInfo[k].member);
  }
  Coordinates s;
  gen::FramePositions frame_positions;
  gen::FrameRotations frame_rotations;
  gen::ClosureVector Phi;
  gen::ClosureJacobian dPhi_ds;
  Coordinates sdot;
  gen::WheelRows C, spin;
  gen::ClosureVector dPhi_ds_dot_sdot;
  gen::WheelVector C_dot_sdot;
  std::array<int, gen::kLimbCount> branches{};
  Params params;
  std::array<double*, gen::kParamInfo.size()> param_storage{};
};

Workspace& of(void* w) noexcept { return *static_cast<Workspace*>(w); }

ClosedFormStatus report(gen::IkStatus status, int limb, const gen::IkDiagnostics& why, ClosedFormFailure* failure) noexcept {
  if (failure != nullptr) *failure = {limb, why.stage, why.value, why.low, why.high, why.aux};
  return closed_form_status(status);
}

template <class T>
double* data_or_null(T& m) noexcept {
  return m.size() == 0 ? nullptr : m.data();
}

constexpr std::array<ModelCodeClosedForm, gen::kLimbCount> closed_forms() {
  std::array<ModelCodeClosedForm, gen::kLimbCount> out{};
  for (std::size_t l = 0; l < out.size(); ++l) {
    const gen::ClosedFormInfo& cf = gen::kClosedForm[l];
    out[l].exists = cf.solve != nullptr;
    out[l].branches = cf.solve != nullptr ? cf.branches : 1;
    out[l].pattern = cf.pattern.data();
    for (std::size_t b = 0; b < 3; ++b) out[l].bits[b] = cf.bits[b].data() != nullptr ? cf.bits[b].data() : "";
    for (std::size_t f = 0; f < 2; ++f) out[l].failures[f] = cf.failures[f].data() != nullptr ? cf.failures[f].data() : "";
  }
  return out;
}
// The generated texts are string literals: their views' data() end in a NUL, so they serve as C strings.
constexpr std::array<ModelCodeClosedForm, gen::kLimbCount> kClosedForms = closed_forms();

// The names as C strings: the generated views are of string literals, NUL-terminated.
template <std::size_t N>
constexpr std::array<const char*, N> c_strings(const std::array<std::string_view, N>& names) {
  std::array<const char*, N> out{};
  for (std::size_t k = 0; k < N; ++k) out[k] = names[k].data();
  return out;
}
constexpr auto kCoordinateNames = c_strings(gen::kCoordinateNames);
constexpr auto kFrameNames = c_strings(gen::kFrameNames);
constexpr std::array<const char*, gen::kParamInfo.size()> kParameterNames = [] {
  std::array<const char*, gen::kParamInfo.size()> out{};
  for (std::size_t k = 0; k < out.size(); ++k) out[k] = gen::kParamInfo[k].name.data();
  return out;
}();
constexpr std::array<IkLimb, gen::kLimbCount> kLimbViews = [] {
  std::array<IkLimb, gen::kLimbCount> out{};
  for (std::size_t l = 0; l < out.size(); ++l) {
    const gen::LimbInfo& b = gen::kLimbs[l];
    out[l] = {b.size, b.rows.data(), b.joints.data(), b.input_count, b.inputs.data()};
  }
  return out;
}();

constexpr std::array<const char*, gen::kWheelCount> kWheelNames = [] {
  std::array<const char*, gen::kWheelCount> out{};
  for (std::size_t w = 0; w < out.size(); ++w) out[w] = gen::kWheels[w].name.data();
  return out;
}();

ModelCode make_model_code() noexcept {
  ModelCode c;
  c.version = kModelCodeVersion;
  c.model = gen::kModelName.data();
  c.coordinates = kCoordinateCount;
  c.inputs = kInputCount;
  c.frames = gen::kFrameCount;
  c.closure_rows = gen::kClosureCount;
  c.limbs = gen::kLimbCount;
  c.params = static_cast<int>(gen::kParamInfo.size());
  c.wheels = kWheelCount;
  c.closed_forms = kClosedForms.data();
  c.coordinate_names = kCoordinateNames.data();
  c.frame_names = kFrameNames.data();
  c.parameter_names = kParameterNames.data();
  c.limb_views = kLimbViews.data();
  c.wheel_names = kWheelNames.data();
  c.create_workspace = []() -> void* { return new Workspace; };
  c.destroy_workspace = [](void* w) noexcept { delete static_cast<Workspace*>(w); };
  c.arrays = [](void* w) noexcept {
    Workspace& ws = of(w);
    ModelCodeArrays a;
    a.s = ws.s.data();
    a.frame_positions = data_or_null(ws.frame_positions);
    a.frame_rotations = ws.frame_rotations.empty() ? nullptr : ws.frame_rotations[0].data();
    a.Phi = data_or_null(ws.Phi);
    a.dPhi_ds = data_or_null(ws.dPhi_ds);
    a.sdot = ws.sdot.data();
    a.C = data_or_null(ws.C);
    a.spin = data_or_null(ws.spin);
    a.dPhi_ds_dot_sdot = data_or_null(ws.dPhi_ds_dot_sdot);
    a.C_dot_sdot = data_or_null(ws.C_dot_sdot);
    a.branches = ws.branches.empty() ? nullptr : ws.branches.data();
    a.params = ws.param_storage.empty() ? nullptr : ws.param_storage.data();
    return a;
  };
  c.kinematics = [](void* w) noexcept {
    Workspace& ws = of(w);
    gen::kinematics(ws.s, ws.params, {.positions = &ws.frame_positions, .rotations = &ws.frame_rotations});
  };
  c.closure = [](void* w, bool with_jacobian) noexcept {
    Workspace& ws = of(w);
    gen::closure(ws.s, ws.params, {.Phi = &ws.Phi, .dPhi_ds = with_jacobian ? &ws.dPhi_ds : nullptr}, false);
  };
  // The rolling rows as the model's own runtime evaluates them (nonholonomic.cpp): the structural
  // zeros stay as the workspace was made.
  c.rolling_rows = [](void* w) noexcept {
    Workspace& ws = of(w);
    gen::kinematic_update(ws.s, ws.params, {.dPhi_ds = &ws.dPhi_ds, .C = &ws.C}, false);
  };
  c.wheel_rows = [](void* w) noexcept {
    Workspace& ws = of(w);
    gen::nonholonomic(ws.s, ws.params, {.C = &ws.C, .spin = &ws.spin}, false);
  };
  c.convective = [](void* w) noexcept {
    Workspace& ws = of(w);
    gen::convective(ws.s, ws.sdot, ws.params, {.dPhi_ds_dot_sdot = &ws.dPhi_ds_dot_sdot, .C_dot_sdot = &ws.C_dot_sdot});
  };
  c.ik_all = [](void* w, ClosedFormFailure* failure) noexcept {
    Workspace& ws = of(w);
    int failed = 0;
    gen::IkDiagnostics why;
    const gen::IkStatus status = gen::ik_all(ws.s, ws.params, ws.branches, ws.s, failed, why);
    return report(status, failed, why, failure);
  };
  c.ik_limb = [](void* w, int limb, int branch, ClosedFormFailure* failure) noexcept {
    Workspace& ws = of(w);
    gen::IkDiagnostics why;
    const auto solve = limb >= 0 && limb < gen::kLimbCount ? gen::kClosedForm[static_cast<std::size_t>(limb)].solve : nullptr;
    if (solve == nullptr) return report(gen::IkStatus::bad_branch, limb, why, failure);
    return report(solve(ws.s, ws.params, branch, ws.s, why), limb, why, failure);
  };
  return c;
}

}  // namespace

const ModelCode& model_code() noexcept {
  static const ModelCode code = make_model_code();
  return code;
}

WLX_MODEL_NAMESPACE_END
