// The runtime compiled once for every model: a model is its description (model.json, read at run
// time) and its code (a ModelCode: the generated functions, compiled for that model alone). As in
// the model's own runtime (wlx/model.hpp) and in Pinocchio, Model is immutable (validated
// parameters) and Data is the workspace the algorithms write into, made once per thread.
//
// Sizes are the model's, known at run time. The algorithms are the model's own runtime's, written
// once for both (wlx/ik_algorithms.hpp, wlx/rate_algorithms.hpp), on the same generated code: the
// kinematics and the IK give the same results to the last bit, the dependent rates the same to
// rounding (Eigen orders a product's inner sum differently at fixed and at run-time sizes).
#pragma once

#include "wlx/generic/description.hpp"
#include "wlx/model_code.hpp"
#include "wlx/small_dense.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <vector>

namespace wlx::generic {

class Model;
// Throws wlx::Error naming `name` unless `values` has one entry per coordinate of the model.
void check_coordinate_count(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& values, const char* name = "s");

class Model {
 public:
  // The description with its code. Throws wlx::Error when they do not belong together (another
  // model, other sizes, code of another ModelCode version) or a parameter's default is refused
  // (as for `params` below).
  Model(std::shared_ptr<const Description> description, const ModelCode& code);
  // The same at other parameters' values (in description().parameters' order): each checked
  // against its kind, each body's inertias against the triangle inequality; wlx::Error names the
  // first refused one.
  Model(std::shared_ptr<const Description> description, const ModelCode& code, std::vector<double> params);

  const Description& description() const noexcept { return *description_; }
  const ModelCode& code() const noexcept { return *code_; }
  const std::vector<double>& params() const noexcept { return params_; }
  double total_mass() const noexcept { return total_mass_; }
  // Distinct for every Model made: a Data loads a model's parameters into its workspace once.
  std::uint64_t identity() const noexcept { return identity_; }

 private:
  std::shared_ptr<const Description> description_;
  const ModelCode* code_;
  std::vector<double> params_;
  double total_mass_ = 0;
  std::uint64_t identity_ = 0;
};

// A workspace: the model's code's (at its fixed sizes) and views of its arrays at run-time sizes.
// Made for a model, used with any Model of the same description and code.
class Data {
  // First: the views below are made from them.
  const ModelCode* code_;
  void* workspace_;
  ModelCodeArrays arrays_;
  int coordinate_count_;
  std::uint64_t loaded_ = 0;  // the identity of the model whose parameters the workspace holds

 public:
  explicit Data(const Model& model);
  ~Data();
  Data(const Data&) = delete;
  Data& operator=(const Data&) = delete;

  // The generated functions' outputs after the algorithm that fills them (kinematics.hpp).
  Eigen::Map<const Eigen::Matrix3Xd> frame_positions;  // 3 x frames
  Eigen::Map<const Eigen::VectorXd> Phi;                // closure rows
  Eigen::Map<const Eigen::MatrixXd> dPhi_ds;            // closure rows x coordinates
  // Frame k's orientation in K0 (columns: its axes); wlx::Error for a k that is no frame.
  Eigen::Map<const Eigen::Matrix3d> frame_rotation(int k) const;

  // The rolling rows and the convective terms after the algorithms that fill them (nonholonomic.hpp).
  Eigen::Map<const Eigen::MatrixXd> C;                  // wheels x coordinates
  Eigen::Map<const Eigen::MatrixXd> spin;               // wheels x coordinates
  Eigen::Map<const Eigen::VectorXd> dPhi_ds_dot_sdot;   // closure rows
  Eigen::Map<const Eigen::VectorXd> C_dot_sdot;         // wheels
  // The dependent rates' factorizations (nonholonomic.hpp): the adjoint Lambda = Phi_dep^-T C_dep^T,
  // J_beta (one row and column per wheel), its LU factorization and condition number, and the
  // inverses of the limbs' blocks of dPhi/ds (each the largest limb's size, padded with a unit diagonal).
  Eigen::MatrixXd wheel_adjoint;
  Eigen::MatrixXd J_beta;
  small::PartialPivotLu<Eigen::Dynamic> J_beta_lu;
  double cond_J_beta = 0;
  std::vector<double> limb_inverses;  // limbs x (size x size), column-major

  // For the algorithms: the workspace with `model`'s parameters loaded, and s given to it.
  void* workspace(const Model& model);
  const ModelCodeArrays& arrays() const noexcept { return arrays_; }
  void set_coordinates(const Eigen::Ref<const Eigen::VectorXd>& s) noexcept;
  void get_coordinates(Eigen::Ref<Eigen::VectorXd> s) const noexcept;
  void set_rates(const Eigen::Ref<const Eigen::VectorXd>& sdot) noexcept;

};

}  // namespace wlx::generic
