// The immutable model (validated parameters and what follows from them) and the preallocated
// workspace the evaluations write into, in the spirit of Pinocchio's Model / Data split: after
// a Data is constructed, evaluating the model allocates nothing.
#pragma once

#include "wlx/model_namespace.hpp"
#include "wlx/settings.hpp"

#include <wlx/gen/all.hpp>

#include "wlx/small_dense.hpp"

#include <Eigen/LU>  // Matrix4d::inverse

#include <string_view>
#include <vector>

namespace wlx {
struct ModelCode;  // wlx/model_code.hpp
}

WLX_MODEL_NAMESPACE_BEGIN

using gen::Coordinates;
using gen::Params;

inline constexpr int kCoordinateCount = gen::kCoordinateCount;
inline constexpr int kInputCount = gen::kInputCount;
inline constexpr int kDependentCount = gen::kDependentCount;
inline constexpr int kWheelCount = gen::kWheelCount;
using WheelVector = Eigen::Matrix<double, kWheelCount, 1>;  // one entry per wheel, in gen::kWheels' order

class Model {
 public:
  // Validates every parameter (finite; lengths and masses positive; inertias physical) and
  // throws wlx::Error naming the first bad one.
  explicit Model(const Params& params);
  // The model at its settings' parameters (settings.hpp: the model file's values).
  Model() : Model(settings().params) {}

  const Params& params() const noexcept { return params_; }
  double total_mass() const noexcept { return total_mass_; }

 private:
  Params params_;
  double total_mass_ = 0;
};

// Workspace for one evaluation thread. Fixed-size members only: no heap allocation.
struct Data {
  // The matrix outputs with structural zeros start zeroed, and the runtime calls the generated
  // functions with zero_fill = false: rewriting those zeros every call cost more store bandwidth
  // than computing the nonzeros (about 50 ns of the fused update). Nothing else writes them.
  Data() noexcept {
    dPhi_ds.setZero();
    C.setZero();
    spin.setZero();
    drive.setZero();
    for (auto& J : body_Jv) J.setZero();
    for (auto& J : body_Jw) J.setZero();
  }

  gen::FramePositions frame_positions;
  gen::FrameRotations frame_rotations;
  gen::ClosureVector Phi;
  gen::ClosureJacobian dPhi_ds;
  gen::WheelRows C;
  gen::WheelRows spin;
  gen::WheelRows drive;  // wheel drives' rates (spin relative to the hub) = drive s'; rows of driven wheels
  gen::ClosureVector dPhi_ds_dot_sdot;
  gen::WheelVector C_dot_sdot;
  gen::BodyVectors body_com;
  gen::BodyRotations body_rotations;
  gen::BodyJacobians body_Jv;
  gen::BodyJacobians body_Jw;
  gen::BodyVectors body_Jv_dot_sdot;
  gen::BodyVectors body_Jw_dot_sdot;

  // Non-holonomic solve (nonholonomic.hpp): the inverses of the closure's per-limb blocks (smaller
  // limbs padded to the largest with a unit diagonal; at these sizes products beat factorizations),
  // the adjoint Lambda = Phi_dep^-T C_dep^T, and J_beta (one row and column per wheel): the pair's
  // columns of the wheel rows reduced to the inputs, C_hat = C_q - Lambda^T Phi_q.
  std::array<Eigen::Matrix<double, gen::kMaxLimbSize, gen::kMaxLimbSize>, gen::kLimbCount> limb_inverse;
  Eigen::Matrix<double, gen::kDependentCount, gen::kWheelCount> wheel_adjoint;
  Eigen::Matrix<double, gen::kWheelCount, gen::kWheelCount> J_beta;
  // J_beta's LU factorization (partial pivoting), once per step: every solve with J_beta uses it.
  small::PartialPivotLu<gen::kWheelCount> J_beta_lu;
  double cond_J_beta = 0;
};

// Index of a coordinate by its name in the model file, or -1.
int coordinate_index(std::string_view name) noexcept;
// Index of a frame of interest by name (C, hip_l, F_l, W_r, ...), or -1.
int frame_index(std::string_view name) noexcept;
// A pointer to the parameter of that name, or nullptr.
double* find_param(Params& params, std::string_view name) noexcept;

// The model's nominal inputs (its file's `nominal`), and the dependent joints at the start values of
// Newton's method (the file's `nominal` and limbs' `start`, else 0): solve them with the IK.
Coordinates nominal_inputs();

// This model's generated functions for the runtime compiled once for every model (wlx/generic/),
// behind plain function pointers (wlx/model_code.hpp).
const ModelCode& model_code() noexcept;

WLX_MODEL_NAMESPACE_END
