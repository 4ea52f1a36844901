// One model's compiled code as code compiled once for every model sees it (the generic runtime,
// wlx/generic/): the generated functions behind plain function pointers, working on a workspace
// that keeps their inputs and outputs at the model's own fixed sizes, so that the generic runtime
// copies nothing and the generated code runs exactly as in the model's own runtime.
//
// What the code is, not what the robot is: the robot's names, structure and numbers are its
// description (model.json, wlx/generic/description.hpp), read at run time. Only what exists as
// code is here: the functions, the sizes they were generated for (checked against the
// description), and the closed forms wlx-gen found (a limb has one only as code).
//
// Each model's runtime library defines wlx::<model>::model_code() (runtime/wlx/model_code.cpp).
// Nothing here depends on a model: this header is the one both sides include.
#pragma once

#include "wlx/ik_options.hpp"  // ClosedFormStatus, ClosedFormFailure, IkLimb

namespace wlx {

// Changed whenever ModelCode's layout changes: a generic runtime refuses code of another version.
inline constexpr int kModelCodeVersion = 1;

// A limb's closed form (the generated gen::kClosedForm[limb]); exists false: wlx-gen found none.
struct ModelCodeClosedForm {
  bool exists = false;
  int branches = 1;
  const char* pattern = "";
  const char* bits[3] = {"", "", ""};      // what each branch bit selects
  const char* failures[2] = {"", ""};     // each failing stage's message, with {value} {low} {high} {aux}
};

// Where a workspace keeps the functions' inputs and outputs: column-major arrays at ModelCode's
// sizes (nullptr for an empty one).
struct ModelCodeArrays {
  double* s = nullptr;                // coordinates: the input of every function, ik's output
  double* frame_positions = nullptr;  // 3 x frames
  double* frame_rotations = nullptr;  // frames matrices 3 x 3, one after another
  double* Phi = nullptr;              // closure rows
  double* dPhi_ds = nullptr;          // closure rows x coordinates
  double* sdot = nullptr;             // coordinates: their rates (convective's input)
  double* C = nullptr;                // wheels x coordinates: the rolling rows, sideways
  double* spin = nullptr;             // wheels x coordinates: the wheels' spin rates' rows
  double* dPhi_ds_dot_sdot = nullptr; // closure rows: (d/dt dPhi/ds) s'
  double* C_dot_sdot = nullptr;       // wheels: (d/dt C) s'
  int* branches = nullptr;            // per limb: the branch ik_all takes
  double* const* params = nullptr;    // per parameter (model.json's order): where its value is kept
};

struct ModelCode {
  int version = 0;  // kModelCodeVersion of the code that filled this in
  const char* model = "";
  int coordinates = 0, inputs = 0, frames = 0, closure_rows = 0, limbs = 0, params = 0, wheels = 0;
  const ModelCodeClosedForm* closed_forms = nullptr;  // per limb
  // What the code was generated for, to check a description against (generic::Model): the names
  // in the code's order, and each limb's rows, joints and the inputs its rows read.
  const char* const* coordinate_names = nullptr;  // per coordinate
  const char* const* frame_names = nullptr;       // per frame
  const char* const* parameter_names = nullptr;   // per parameter
  const IkLimb* limb_views = nullptr;             // per limb
  const char* const* wheel_names = nullptr;       // per wheel, in the rolling rows' order

  // A workspace (zeroed; its structural zeros stay zero: every call leaves them) and its arrays.
  void* (*create_workspace)() = nullptr;
  void (*destroy_workspace)(void* workspace) noexcept = nullptr;
  ModelCodeArrays (*arrays)(void* workspace) noexcept = nullptr;

  // s -> frame_positions, frame_rotations.
  void (*kinematics)(void* workspace) noexcept = nullptr;
  // s -> Phi, and dPhi_ds when with_jacobian.
  void (*closure)(void* workspace, bool with_jacobian) noexcept = nullptr;
  // s -> dPhi_ds and C (the fused kinematic update: they share most of their terms).
  void (*rolling_rows)(void* workspace) noexcept = nullptr;
  // s -> C and spin.
  void (*wheel_rows)(void* workspace) noexcept = nullptr;
  // s, sdot -> dPhi_ds_dot_sdot and C_dot_sdot.
  void (*convective)(void* workspace) noexcept = nullptr;
  // Every limb that has a closed form, on its branch in `branches`, from the inputs in s into s's
  // dependent joints (the fused pass; the others' joints are left as they are).
  ClosedFormStatus (*ik_all)(void* workspace, ClosedFormFailure* failure) noexcept = nullptr;
  // One limb's closed form on a branch, from the inputs in s into s (exists must be true).
  ClosedFormStatus (*ik_limb)(void* workspace, int limb, int branch, ClosedFormFailure* failure) noexcept = nullptr;
};

}  // namespace wlx
