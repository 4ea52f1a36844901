#include "wlx/generic/kinematics.hpp"

namespace wlx::generic {

void forward_kinematics(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& s) {
  void* w = data.workspace(model);
  check_coordinate_count(model, s);
  data.set_coordinates(s);
  model.code().kinematics(w);
}

void closure(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& s, bool with_jacobian) {
  void* w = data.workspace(model);
  check_coordinate_count(model, s);
  data.set_coordinates(s);
  model.code().closure(w, with_jacobian);
}

}  // namespace wlx::generic
