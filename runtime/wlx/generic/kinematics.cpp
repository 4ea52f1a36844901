#include "wlx/generic/kinematics.hpp"

#include "wlx/error.hpp"

#include <fmt/format.h>

namespace wlx::generic {

namespace {
void give_coordinates(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& s) {
  if (s.size() != model.description().coordinate_count())
    throw Error("s", fmt::format("{} values for the model's {} coordinates", s.size(), model.description().coordinate_count()));
  data.set_coordinates(s);
}
}  // namespace

void forward_kinematics(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& s) {
  void* w = data.workspace(model);
  give_coordinates(model, data, s);
  model.code().kinematics(w);
}

void closure(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& s, bool with_jacobian) {
  void* w = data.workspace(model);
  give_coordinates(model, data, s);
  model.code().closure(w, with_jacobian);
}

}  // namespace wlx::generic
