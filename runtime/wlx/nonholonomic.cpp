#include "wlx/nonholonomic.hpp"

#include "wlx/error.hpp"
#include "wlx/ik.hpp"
#include "wlx/rate_algorithms.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

WLX_MODEL_NAMESPACE_BEGIN

namespace {
std::string wheel_hint();  // below
}  // namespace

namespace {

std::string_view name_of(int coordinate) { return gen::kCoordinateNames[static_cast<std::size_t>(coordinate)]; }


// The model as the dependent rates' algorithms see it (wlx/rate_algorithms.hpp), over a Data (D:
// Data or const Data).
template <class D>
class FixedRates {
 public:
  static constexpr int kLimbSize = gen::kMaxLimbSize;
  static constexpr int kWheels = kWheelCount;
  static constexpr int kClosureRows = gen::kClosureCount;
  static constexpr int kInputs = kInputCount;

  explicit FixedRates(D& data) : data_(data) {}
  int limb_size() const { return gen::kMaxLimbSize; }
  int wheel_count() const { return kWheelCount; }
  int closure_rows() const { return gen::kClosureCount; }
  int input_count() const { return kInputCount; }
  D& data() const { return data_; }
  // Calls f(std::integral_constant<int, L>, limb L) for every limb L: the limb's rows and joints
  // are then compile-time constants (gen::kLimbs is constexpr), so the block copies unroll with
  // fixed indices, as fast as code written for one robot.
  template <class F>
  void for_each_limb(F&& f) const {
    [&]<std::size_t... L>(std::index_sequence<L...>) {
      (f(std::integral_constant<int, static_cast<int>(L)>{}, limb_view(static_cast<int>(L))), ...);
    }(std::make_index_sequence<static_cast<std::size_t>(kLimbCount)>{});
  }
  template <class Limb>
  auto& limb_inverse(Limb limb) const {
    return data_.limb_inverse[static_cast<std::size_t>(static_cast<int>(limb))];
  }
  std::string_view coordinate_name(int k) const { return name_of(k); }
  template <class Limb>
  std::string_view limb_title(Limb limb) const {
    return limb_name(static_cast<int>(limb));
  }
  std::string raise_a_wheel_hint() const { return wheel_hint(); }

 private:
  static constexpr IkLimb limb_view(int l) {
    const gen::LimbInfo& b = gen::kLimbs[static_cast<std::size_t>(l)];
    return {b.size, b.rows.data(), b.joints.data(), b.input_count, b.inputs.data()};
  }
  D& data_;
};

}  // namespace

double condition_number(const WheelMatrix& J) { return rate_algorithms::condition_number<kWheelCount>(J); }

namespace {
// The model's pairs as the algorithms see them.
struct FixedPairs {
  int wheel_count() const { return kWheelCount; }
  std::string_view coordinate_name(int k) const { return name_of(k); }
  int coordinate_index(const std::string& name) const { return ::wlx::WLX_MODEL::coordinate_index(name); }
  const auto& pair_candidates() const { return gen::kPairCandidates; }
  const auto& pairs() const { return gen::kPairs; }
};
}  // namespace

std::string DependentPair::label() const { return rate_algorithms::pair_label(FixedPairs{}, *this); }


DependentPair dependent_pair(const std::vector<std::string>& names, const std::string& field) {
  const std::vector<int> index = rate_algorithms::pair_coordinates(FixedPairs{}, names, field);
  DependentPair pair;
  std::copy(index.begin(), index.end(), pair.index.begin());
  return pair;
}

DependentPair named_pair(std::string_view name, const std::string& field) {
  return {rate_algorithms::named_pair(FixedPairs{}, name, field).coordinates};
}

namespace {
// The singular-J_beta hint, from the model: the wheels' ground-level inputs, and those the nominal
// pose sets off the ground plane (the excavator's raises one wheel for exactly this reason).
std::string wheel_hint() {
  std::string grounds, nominal;
  for (const gen::WheelInfo& wheel : gen::kWheels) {
    grounds += fmt::format("{}{}", grounds.empty() ? "" : ", ", name_of(wheel.ground));
    const double z = settings().nominal_inputs[static_cast<std::size_t>(wheel.ground)];
    if (z != 0) nominal += fmt::format("{}{} = {:g} m", nominal.empty() ? "" : ", ", name_of(wheel.ground), z);
  }
  return fmt::format("Raise one wheel ({}{}) or choose another dependent pair.", grounds,
                     nominal.empty() ? "" : "; the model's nominal pose has " + nominal);
}
}  // namespace

void solve_dependent_rates(const Model& model, Data& d, const Coordinates& s, Coordinates& sdot,
                           const DependentPair& pair, const NonholonomicOptions& options) {
  // dPhi/ds and C(s) from the fused generated function: they share most subexpressions.
  gen::kinematic_update(s, model.params(), {.dPhi_ds = &d.dPhi_ds, .C = &d.C}, false);
  factorize_dependent_rates(d, pair, options);
  for (int k = 0; k < kWheelCount; ++k) sdot(pair.index[k]) = 0;
  rate_algorithms::solve_pair_and_closure<false>(FixedRates<Data>(d), pair, gen::ClosureVector::Zero(), WheelVector::Zero(), sdot);
}

void factorize_dependent_rates(Data& d, const DependentPair& pair, const NonholonomicOptions& options) {
  rate_algorithms::factorize(FixedRates<Data>(d), pair, options);
}

void solve_dependent_accelerations(const Model& model, Data& d, const Coordinates& s, const Coordinates& sdot,
                                   Coordinates& sddot, const DependentPair& pair) {
  gen::convective(s, sdot, model.params(), {.dPhi_ds_dot_sdot = &d.dPhi_ds_dot_sdot, .C_dot_sdot = &d.C_dot_sdot});
  solve_dependent_accelerations_prepared(d, sddot, pair);
}

void solve_dependent_accelerations_prepared(Data& d, Coordinates& sddot, const DependentPair& pair) {
  for (int k : pair.index) sddot(k) = 0;
  rate_algorithms::solve_pair_and_closure<false>(FixedRates<Data>(d), pair, d.dPhi_ds_dot_sdot, d.C_dot_sdot, sddot);
}

void solve_bias_accelerations(Data& d, Coordinates& sddot, const DependentPair& pair) {
  sddot.setZero();
  rate_algorithms::solve_pair_and_closure<true>(FixedRates<Data>(d), pair, d.dPhi_ds_dot_sdot, d.C_dot_sdot, sddot);
}

template <std::size_t N>
void rate_basis(const Data& d, const std::array<int, N>& commanded, const DependentPair& pair,
                Eigen::Matrix<double, kCoordinateCount, static_cast<int>(N)>& T) {
  rate_algorithms::rate_basis(FixedRates<const Data>(d), commanded, pair, T);
}

template <std::size_t N>
Eigen::Matrix<double, kCoordinateCount, static_cast<int>(N)> rate_basis(const Data& d, const std::array<int, N>& commanded,
                                                                        const DependentPair& pair) {
  Eigen::Matrix<double, kCoordinateCount, static_cast<int>(N)> T;
  rate_basis(d, commanded, pair, T);
  return T;
}

// The dynamics' commanded speeds are the one set the runtime asks a basis for (none without a
// dynamics section: wlx-gen then writes no reduced_dynamics.hpp).
#if __has_include(<wlx/gen/reduced_dynamics.hpp>)
template Eigen::Matrix<double, kCoordinateCount, static_cast<int>(gen::kCommanded.size())> rate_basis(
    const Data&, const std::array<int, gen::kCommanded.size()>&, const DependentPair&);
template void rate_basis(const Data&, const std::array<int, gen::kCommanded.size()>&, const DependentPair&,
                         Eigen::Matrix<double, kCoordinateCount, static_cast<int>(gen::kCommanded.size())>&);
#endif

Eigen::Matrix<double, 3, kWheelCount> contact_velocities(const Model& model, Data& d, const Coordinates& s,
                                                         const Coordinates& sdot) {
  gen::kinematics(s, model.params(), {.rotations = &d.frame_rotations});
  gen::nonholonomic(s, model.params(), {.C = &d.C, .spin = &d.spin}, false);
  const WheelVector spin = d.spin * sdot, sideways = d.C * sdot;
  Eigen::Matrix<double, 3, kWheelCount> v;
  for (int w = 0; w < kWheelCount; ++w) {
    const gen::WheelInfo& wheel = gen::kWheels[static_cast<std::size_t>(w)];
    const Eigen::Matrix3d& R = d.frame_rotations[static_cast<std::size_t>(wheel.contact_frame)];
    const Eigen::Vector3d vw = R.col(wheel.forward_axis) * (model.params().*wheel.radius * spin(w)) +
                               R.col(wheel.lateral_axis) * sideways(w) + Eigen::Vector3d::UnitZ() * sdot(wheel.ground);
    for (int i = 0; i < 3; ++i) v(i, w) = vw(i);  // element by element: compiles for no wheels too
  }
  return v;
}

std::string contact_column_stem(int wheel) {
  std::string stem(
      gen::kFrameNames[static_cast<std::size_t>(gen::kWheels[static_cast<std::size_t>(wheel)].contact_frame)]);
  std::erase(stem, '_');
  return stem;
}

WheelVector sideways_velocity(const Model& model, Data& d, const Coordinates& s, const Coordinates& sdot) {
  gen::nonholonomic(s, model.params(), {.C = &d.C}, false);
  return d.C * sdot;
}

WLX_MODEL_NAMESPACE_END
