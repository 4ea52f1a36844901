#include "wlx/generic/nonholonomic.hpp"

#include "wlx/error.hpp"
#include "wlx/rate_algorithms.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace wlx::generic {

namespace {

// The singular-J_beta hint, from the model: the wheels' ground-level inputs, and those the nominal
// pose sets off the ground plane.
std::string wheel_hint(const Description& d) {
  std::string grounds, nominal;
  for (const Wheel& wheel : d.wheels) {
    if (wheel.ground < 0) continue;
    const std::string& name = d.coordinates[static_cast<std::size_t>(wheel.ground)].name;
    grounds += fmt::format("{}{}", grounds.empty() ? "" : ", ", name);
    const double z = d.settings.nominal_inputs[static_cast<std::size_t>(wheel.ground)];
    if (z != 0) nominal += fmt::format("{}{} = {:g} m", nominal.empty() ? "" : ", ", name, z);
  }
  return fmt::format("Raise one wheel ({}{}) or choose another dependent pair.", grounds,
                     nominal.empty() ? "" : "; the model's nominal pose has " + nominal);
}

// The model as the dependent rates' algorithms see it (wlx/rate_algorithms.hpp). At run-time sizes
// throughout, the limb blocks too: one instantiation for every model (the limb blocks' inverses are
// Eigen's LU then, where the model's own runtime inverts at its fixed size in closed form: the
// results agree to rounding, as every product's sum in another order does).
class GenericRates {
 public:
  static constexpr int kLimbSize = Eigen::Dynamic;
  static constexpr int kWheels = Eigen::Dynamic;
  static constexpr int kClosureRows = Eigen::Dynamic;
  static constexpr int kInputs = Eigen::Dynamic;

  GenericRates(const Model& model, Data& data) : d_(model.description()), data_(data), limb_size_(d_.max_limb_size()) {}
  int limb_size() const { return limb_size_; }
  int wheel_count() const { return d_.wheel_count(); }
  int closure_rows() const { return static_cast<int>(d_.closure_rows.size()); }
  int input_count() const { return d_.input_count; }
  Data& data() const { return data_; }
  template <class F>
  void for_each_limb(F&& f) const {
    for (int l = 0; l < static_cast<int>(d_.limbs.size()); ++l) {
      const Limb& b = d_.limbs[static_cast<std::size_t>(l)];
      f(l, IkLimb{static_cast<int>(b.joints.size()), b.rows.data(), b.joints.data(), static_cast<int>(b.inputs.size()), b.inputs.data()});
    }
  }
  Eigen::Map<Eigen::MatrixXd> limb_inverse(int l) const {
    return Eigen::Map<Eigen::MatrixXd>(data_.limb_inverses.data() + static_cast<std::ptrdiff_t>(l) * limb_size_ * limb_size_, limb_size_,
                                       limb_size_);
  }
  std::string_view coordinate_name(int k) const { return d_.coordinates[static_cast<std::size_t>(k)].name; }
  std::string_view limb_title(int l) const { return d_.limbs[static_cast<std::size_t>(l)].title; }
  std::string raise_a_wheel_hint() const { return wheel_hint(d_); }

 private:
  const Description& d_;
  Data& data_;
  int limb_size_;
};

// The model's pairs as the algorithms see them.
struct Pairs {
  const Description& d;
  int wheel_count() const { return d.wheel_count(); }
  std::string_view coordinate_name(int k) const { return d.coordinates[static_cast<std::size_t>(k)].name; }
  int coordinate_index(const std::string& name) const { return d.coordinate_index(name); }
  const std::vector<int>& pair_candidates() const { return d.pair_candidates; }
  const std::vector<Pair>& pairs() const { return d.pairs; }
};

template <class F>
decltype(auto) with_rates(const Model& model, Data& data, F&& f) {
  GenericRates p(model, data);
  return f(p);
}


void check_pair(const Model& model, const DependentPair& pair) {
  const Description& d = model.description();
  if (pair.index.size() != d.wheels.size())
    throw Error("dependent", fmt::format("{} rates for the model's {} wheels", pair.index.size(), d.wheels.size()));
  for (int k : pair.index)
    if (k < 0 || k >= d.input_count) throw Error("dependent", fmt::format("coordinate {} is not an input", k));
}

}  // namespace

std::string pair_label(const Model& model, const DependentPair& pair) {
  check_pair(model, pair);
  return rate_algorithms::pair_label(Pairs{model.description()}, pair);
}

DependentPair dependent_pair(const Model& model, const std::vector<std::string>& names, const std::string& field) {
  return {rate_algorithms::pair_coordinates(Pairs{model.description()}, names, field)};
}

DependentPair named_pair(const Model& model, std::string_view name, const std::string& field) {
  return {rate_algorithms::named_pair(Pairs{model.description()}, name, field).coordinates};
}

DependentPair default_pair(const Model& model) {
  const Description& d = model.description();
  return {d.pairs[static_cast<std::size_t>(d.default_pair)].coordinates};
}

double condition_number(const Eigen::MatrixXd& J) {
  if (J.rows() != J.cols()) throw Error("J_beta", fmt::format("{} x {}, not square", J.rows(), J.cols()));
  return rate_algorithms::condition_number<Eigen::Dynamic>(J);
}

void solve_dependent_rates(const Model& model, Data& data, const Eigen::VectorXd& s, Eigen::VectorXd& sdot,
                           const DependentPair& pair, const NonholonomicOptions& options) {
  check_coordinate_count(model, s, "s");
  check_coordinate_count(model, sdot, "sdot");
  check_pair(model, pair);
  void* w = data.workspace(model);
  data.set_coordinates(s);
  model.code().rolling_rows(w);  // dPhi/ds and C(s)
  with_rates(model, data, [&](auto& p) {
    rate_algorithms::factorize(p, pair, options);
    for (int k : pair.index) sdot(k) = 0;
    rate_algorithms::solve_pair_and_closure<false>(p, pair, Eigen::VectorXd::Zero(p.closure_rows()),
                                                   Eigen::VectorXd::Zero(p.wheel_count()), sdot);
  });
}

namespace {
// The convective terms at (s, sdot) in data, for an acceleration level.
void convective_terms(const Model& model, Data& data, const Eigen::VectorXd& s, const Eigen::VectorXd& sdot, const DependentPair& pair) {
  check_coordinate_count(model, s, "s");
  check_coordinate_count(model, sdot, "sdot");
  check_pair(model, pair);
  void* w = data.workspace(model);
  data.set_coordinates(s);
  data.set_rates(sdot);
  model.code().convective(w);
}
}  // namespace

void solve_dependent_accelerations(const Model& model, Data& data, const Eigen::VectorXd& s, const Eigen::VectorXd& sdot,
                                   Eigen::VectorXd& sddot, const DependentPair& pair) {
  check_coordinate_count(model, sddot, "sddot");
  convective_terms(model, data, s, sdot, pair);
  with_rates(model, data, [&](auto& p) {
    for (int k : pair.index) sddot(k) = 0;
    rate_algorithms::solve_pair_and_closure<false>(p, pair, data.dPhi_ds_dot_sdot, data.C_dot_sdot, sddot);
  });
}

void solve_bias_accelerations(const Model& model, Data& data, const Eigen::VectorXd& s, const Eigen::VectorXd& sdot,
                              Eigen::VectorXd& sddot, const DependentPair& pair) {
  convective_terms(model, data, s, sdot, pair);
  sddot = Eigen::VectorXd::Zero(model.description().coordinate_count());
  with_rates(model, data, [&](auto& p) {
    rate_algorithms::solve_pair_and_closure<true>(p, pair, data.dPhi_ds_dot_sdot, data.C_dot_sdot, sddot);
  });
}

Eigen::MatrixXd rate_basis(const Model& model, Data& data, const std::vector<int>& commanded, const DependentPair& pair) {
  check_pair(model, pair);
  for (int c : commanded)
    if (c < 0 || c >= model.description().input_count) throw Error("commanded", fmt::format("coordinate {} is not an input", c));
  data.workspace(model);
  Eigen::MatrixXd T(model.description().coordinate_count(), static_cast<Eigen::Index>(commanded.size()));
  with_rates(model, data, [&](auto& p) { rate_algorithms::rate_basis(p, commanded, pair, T); });
  return T;
}

}  // namespace wlx::generic
