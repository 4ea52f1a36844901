#include "wlx/generic/model.hpp"

#include "wlx/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <string>

namespace wlx::generic {

namespace {

std::vector<double> defaults(const Description& d) {
  std::vector<double> values;
  values.reserve(d.parameters.size());
  for (const Parameter& p : d.parameters) values.push_back(p.value);
  return values;
}

// The description and the code must describe one model: the same name and the same sizes.
void check_belong_together(const Description& d, const ModelCode& code) {
  const auto mismatch = [&](const std::string& what) {
    throw Error("model.json", fmt::format("it does not belong to the code compiled for model '{}': {} (regenerate and "
                                          "compile the model again)",
                                          code.model, what));
  };
  if (code.version != kModelCodeVersion)
    throw Error("model", fmt::format("its code was compiled for version {} of this interface, this runtime reads version {}: "
                                     "compile the model again",
                                     code.version, kModelCodeVersion));
  if (d.model != code.model) mismatch(fmt::format("it describes model '{}'", d.model));
  const auto same = [&](const char* what, std::size_t described, int compiled) {
    if (described != static_cast<std::size_t>(compiled)) mismatch(fmt::format("{} {}, the code {}", described, what, compiled));
  };
  same("coordinates", d.coordinates.size(), code.coordinates);
  same("inputs", static_cast<std::size_t>(d.input_count), code.inputs);
  same("frames", d.frames.size(), code.frames);
  same("closure rows", d.closure_rows.size(), code.closure_rows);
  same("limbs", d.limbs.size(), code.limbs);
  same("parameters", d.parameters.size(), code.params);
  same("wheels", d.wheels.size(), code.wheels);
  const auto same_name = [&](const char* what, const std::string& described, const char* compiled) {
    if (described != compiled) mismatch(fmt::format("{} '{}' where the code has '{}'", what, described, compiled));
  };
  for (std::size_t k = 0; k < d.coordinates.size(); ++k) same_name("coordinate", d.coordinates[k].name, code.coordinate_names[k]);
  for (std::size_t k = 0; k < d.frames.size(); ++k) same_name("frame", d.frames[k].name, code.frame_names[k]);
  for (std::size_t k = 0; k < d.parameters.size(); ++k) same_name("parameter", d.parameters[k].name, code.parameter_names[k]);
  for (std::size_t w = 0; w < d.wheels.size(); ++w) same_name("wheel", d.wheels[w].name, code.wheel_names[w]);
  for (std::size_t l = 0; l < d.limbs.size(); ++l) {
    const Limb& described = d.limbs[l];
    const IkLimb& compiled = code.limb_views[l];
    const auto same_list = [&](const std::vector<int>& a, int size, const int* b) {
      return a.size() == static_cast<std::size_t>(size) && std::equal(a.begin(), a.end(), b);
    };
    if (!same_list(described.joints, compiled.size, compiled.joints) || !same_list(described.rows, compiled.size, compiled.rows) ||
        !same_list(described.inputs, compiled.input_count, compiled.inputs))
      mismatch(fmt::format("limb {}'s joints, closure rows or inputs are not the code's", described.name));
    const ModelCodeClosedForm& cf = code.closed_forms[l];
    const int branch = d.settings.default_branch[l];
    if (branch >= (cf.exists ? cf.branches : 1))
      throw Error("model.json", fmt::format("settings.branches.{}: {} has branches 0 to {}, not {}", described.name, described.title,
                                            (cf.exists ? cf.branches : 1) - 1, branch));
  }
}

std::uint64_t next_identity() noexcept {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

}  // namespace

Model::Model(std::shared_ptr<const Description> description, const ModelCode& code)
    : Model(description, code, description ? defaults(*description) : std::vector<double>{}) {}

Model::Model(std::shared_ptr<const Description> description, const ModelCode& code, std::vector<double> params)
    : description_(std::move(description)), code_(&code), params_(std::move(params)), identity_(next_identity()) {
  if (!description_) throw Error("model", "no description");
  const Description& d = *description_;
  validate(d);
  check_belong_together(d, code);
  if (params_.size() != d.parameters.size())
    throw Error("params", fmt::format("{} values for the model's {} parameters", params_.size(), d.parameters.size()));
  // Each parameter's kind (from the model file) says which values make sense.
  for (std::size_t k = 0; k < params_.size(); ++k) check_parameter(d.parameters[k].name, d.parameters[k].kind, params_[k]);
  for (const Body& b : d.bodies) {
    const auto value = [&](int k) { return params_[static_cast<std::size_t>(k)]; };
    const auto name = [&](int k) { return std::string_view(d.parameters[static_cast<std::size_t>(k)].name); };
    check_principal_inertias({value(b.inertia[0]), value(b.inertia[1]), value(b.inertia[2])},
                             {name(b.inertia[0]), name(b.inertia[1]), name(b.inertia[2])});
    total_mass_ += value(b.mass);
  }
}

void check_coordinate_count(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& values, const char* name) {
  if (values.size() != model.description().coordinate_count())
    throw Error(name, fmt::format("{} values for the model's {} coordinates", values.size(), model.description().coordinate_count()));
}

Data::Data(const Model& model)
    : code_(&model.code()),
      workspace_(model.code().create_workspace()),
      arrays_(model.code().arrays(workspace_)),
      coordinate_count_(model.code().coordinates),
      frame_positions(arrays_.frame_positions, 3, model.code().frames),
      Phi(arrays_.Phi, model.code().closure_rows),
      dPhi_ds(arrays_.dPhi_ds, model.code().closure_rows, model.code().coordinates),
      C(arrays_.C, model.code().wheels, model.code().coordinates),
      spin(arrays_.spin, model.code().wheels, model.code().coordinates),
      dPhi_ds_dot_sdot(arrays_.dPhi_ds_dot_sdot, model.code().closure_rows),
      C_dot_sdot(arrays_.C_dot_sdot, model.code().wheels),
      wheel_adjoint(Eigen::MatrixXd::Zero(model.code().closure_rows, model.code().wheels)),
      J_beta(Eigen::MatrixXd::Zero(model.code().wheels, model.code().wheels)),
      limb_inverses(static_cast<std::size_t>(model.code().limbs * model.description().max_limb_size() * model.description().max_limb_size()), 0.0) {}

Data::~Data() { code_->destroy_workspace(workspace_); }

Eigen::Map<const Eigen::Matrix3d> Data::frame_rotation(int k) const {
  if (k < 0 || k >= code_->frames) throw Error("frame", fmt::format("no frame {} (the model has {})", k, code_->frames));
  return Eigen::Map<const Eigen::Matrix3d>(arrays_.frame_rotations + 9 * static_cast<std::ptrdiff_t>(k));
}

void* Data::workspace(const Model& model) {
  if (&model.code() != code_) throw Error("data", "this workspace was made for another model's code");
  if (loaded_ != model.identity()) {
    const std::vector<double>& p = model.params();
    for (std::size_t k = 0; k < p.size(); ++k) *arrays_.params[k] = p[k];
    loaded_ = model.identity();
  }
  return workspace_;
}

void Data::set_coordinates(const Eigen::Ref<const Eigen::VectorXd>& s) noexcept {
  Eigen::Map<Eigen::VectorXd>(arrays_.s, coordinate_count_) = s;
}

void Data::set_rates(const Eigen::Ref<const Eigen::VectorXd>& sdot) noexcept {
  Eigen::Map<Eigen::VectorXd>(arrays_.sdot, coordinate_count_) = sdot;
}

void Data::get_coordinates(Eigen::Ref<Eigen::VectorXd> s) const noexcept {
  s = Eigen::Map<const Eigen::VectorXd>(arrays_.s, coordinate_count_);
}

}  // namespace wlx::generic
