#include "wlx/nonholonomic.hpp"

#include "wlx/error.hpp"
#include "wlx/ik.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

constexpr int kNq = kInputCount;
constexpr int kLimbMax = gen::kMaxLimbSize;
using LimbMatrix = Eigen::Matrix<double, kLimbMax, kLimbMax>;
using LimbVector = Eigen::Matrix<double, kLimbMax, 1>;

std::string_view name_of(int coordinate) { return gen::kCoordinateNames[static_cast<std::size_t>(coordinate)]; }

bool is_pair_candidate(int coordinate) {
  for (int k : gen::kPairCandidates)
    if (k == coordinate) return true;
  return false;
}

// Calls f(std::integral_constant<int, L>) for every limb L: the limb's rows and joints are then
// compile-time constants (gen::kLimbs is constexpr), so the block copies below unroll with fixed
// indices, as fast as code written for one robot.
template <class F>
void for_each_limb(F&& f) {
  [&]<std::size_t... L>(std::index_sequence<L...>) {
    (f(std::integral_constant<int, static_cast<int>(L)>{}), ...);
  }(std::make_index_sequence<static_cast<std::size_t>(kLimbCount)>{});
}

// Factorizes each limb's block of dPhi/ds and solves the adjoint Phi_dep^T Lambda = C_dep^T: one
// right-hand side per wheel instead of one per input (Phi_dep^-1 Phi_q). The wheel rows reduced to
// the inputs, C_hat = C_q - Lambda^T Phi_q, are then formed only where needed (reduced_column).
void reduce(Data& d) {
  for_each_limb([&](auto L) {
    constexpr Limb limb = decltype(L)::value;
    constexpr gen::LimbInfo b = gen::kLimbs[static_cast<std::size_t>(limb)];
    LimbMatrix block = LimbMatrix::Identity();
    Eigen::Matrix<double, kLimbMax, kWheelCount> rhs = Eigen::Matrix<double, kLimbMax, kWheelCount>::Zero();
    for (int j = 0; j < b.size; ++j) {
      const int joint = b.joints[static_cast<std::size_t>(j)];
      for (int i = 0; i < b.size; ++i) block(i, j) = d.dPhi_ds(b.rows[static_cast<std::size_t>(i)], joint);
      // A row of a matrix with no columns is a block at an offset from a null pointer (undefined
      // behaviour that UBSan reports) for a model without wheels: nothing to copy there.
      if constexpr (kWheelCount > 0) rhs.row(j) = d.C.col(joint).transpose();
    }
    auto& inverse = d.limb_inverse[static_cast<std::size_t>(limb)];
    inverse = block.inverse();
    // A singular block means the limb's joint rates are not determined by its target's motion.
    const double rcond = 1.0 / (block.cwiseAbs().colwise().sum().maxCoeff() * inverse.cwiseAbs().colwise().sum().maxCoeff());
    if (!(rcond > 1e-13))
      throw Error(std::string(limb_name(limb)),
                  fmt::format("the closure Jacobian of this limb is singular (reciprocal condition {:.2g}): {}; its joint "
                              "rates are undefined here",
                              std::isfinite(rcond) ? rcond : 0.0,  // an exactly singular block inverts to inf/NaN
                              "its joints cannot move its targets in every direction here (a chain stretched straight "
                              "or folded, or two joint axes aligned)"),
                  ErrorKind::singular);
    if constexpr (kWheelCount > 0) {
      const Eigen::Matrix<double, kLimbMax, kWheelCount> lambda = inverse.transpose().lazyProduct(rhs);
      for (int i = 0; i < b.size; ++i) d.wheel_adjoint.row(b.rows[static_cast<std::size_t>(i)]) = lambda.row(i);
    }
  });
}

// The dependent joints' part of s'' or s' for a closure right-hand side: Phi_dep x = -v.
void solve_closure(const Data& d, const gen::ClosureVector& v, Coordinates& out) {
  for_each_limb([&](auto L) {
    constexpr gen::LimbInfo b = gen::kLimbs[static_cast<std::size_t>(decltype(L)::value)];
    LimbVector rhs = LimbVector::Zero();
    for (int i = 0; i < b.size; ++i) rhs(i) = -v(b.rows[static_cast<std::size_t>(i)]);
    const LimbVector x = d.limb_inverse[static_cast<std::size_t>(decltype(L)::value)] * rhs;
    for (int j = 0; j < b.size; ++j) out(b.joints[static_cast<std::size_t>(j)]) = x(j);
  });
}

// Column k of C_hat = C_q - Lambda^T Phi_q.
WheelVector reduced_column(const Data& d, int k) { return d.C.col(k) - d.wheel_adjoint.transpose().lazyProduct(d.dPhi_ds.col(k)); }

// The wheels' rows and the closure for input rates (or accelerations) `q` whose pair entries are
// zero, plus the convective terms: the pair's rates from J_beta pair' = -(C_q q + conv_C - Lambda^T
// (Phi_q q + conv_Phi)), then the dependent joints from Phi_dep x = -(Phi_q q' + conv_Phi) with q'
// = q and the pair's rates. Phi_q q is formed once; not at all when the input rates are all zero
// (kInputsZero: the bias accelerations of the inverse dynamics).
template <bool kInputsZero>
void solve_pair_and_closure(const Data& d, const DependentPair& pair, const gen::ClosureVector& conv_Phi,
                            const WheelVector& conv_C, Coordinates& out) {
  gen::ClosureVector closure = conv_Phi;
  WheelVector wheels = conv_C;
  if constexpr (!kInputsZero) {
    closure.noalias() += d.dPhi_ds.leftCols<kNq>().lazyProduct(out.head<kNq>());
    wheels.noalias() += d.C.leftCols<kNq>().lazyProduct(out.head<kNq>());
  }
  if constexpr (kWheelCount > 0) {
    WheelVector pair_rate = d.wheel_adjoint.transpose().lazyProduct(closure) - wheels;
    d.J_beta_lu.solve_in_place(pair_rate);
    for (int w = 0; w < kWheelCount; ++w) {
      const int k = pair.index[static_cast<std::size_t>(w)];
      out(k) = pair_rate(w);
      closure.noalias() += d.dPhi_ds.col(k) * pair_rate(w);
    }
  }
  solve_closure(d, closure, out);
}

}  // namespace

// Two wheels: the 2-norm condition number of [a b; c d] in closed form, without cancellation:
// sigma_max = (sqrt(p) + sqrt(q)) / 2 with p = (a + d)^2 + (b - c)^2 and q = (a - d)^2 + (b + c)^2
// (sums of squares: accurate even where the two singular values nearly agree, where the textbook
// sqrt(E^2 - 4 det^2) loses half the digits), and sigma_max sigma_min = |det|.
double condition_number(const WheelMatrix& J) {
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  if constexpr (kWheelCount == 0) {
    static_cast<void>(J);
    return 1;  // no wheels, no rates to solve for: nothing is ill-conditioned
  } else if constexpr (kWheelCount == 1) {
    return std::isfinite(J(0, 0)) && J(0, 0) != 0 ? 1 : kInfinity;
  } else if constexpr (kWheelCount == 2) {
    const double a = J(0, 0), b = J(0, 1), c = J(1, 0), d = J(1, 1);
    const double p = (a + d) * (a + d) + (b - c) * (b - c), q = (a - d) * (a - d) + (b + c) * (b + c);
    const double D = std::abs(a * d - b * c);
    if (!std::isfinite(p + q) || !(D > 0)) return kInfinity;
    const double smax = 0.5 * (std::sqrt(p) + std::sqrt(q));
    return smax * smax / D;
  } else {
    return small::condition_number<kWheelCount>(J);
  }
}

std::string DependentPair::label() const {
  std::string names;
  for (int k : index) names += fmt::format("{}{}'", names.empty() ? "" : ", ", name_of(k));
  return "(" + names + ")";
}

DependentPair dependent_pair(const std::vector<std::string>& names, const std::string& field) {
  std::string valid;
  for (int k : gen::kPairCandidates) valid += fmt::format("{}{}", valid.empty() ? "" : ", ", name_of(k));
  if (names.size() != static_cast<std::size_t>(kWheelCount))
    throw Error(field, fmt::format("needs {} names, one dependent rate per wheel, got {}: choose from {}", kWheelCount,
                                   names.size(), valid));
  DependentPair pair;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const int k = coordinate_index(names[i]);
    if (k < 0 || !is_pair_candidate(k))
      throw Error(field, fmt::format("'{}' cannot be a dependent rate: choose {} of {}", names[i], kWheelCount, valid));
    for (std::size_t j = 0; j < i; ++j)
      if (pair.index[j] == k)
        throw Error(field, fmt::format("the dependent rates must differ, got '{}' twice", names[i]));
    pair.index[i] = k;
  }
  return pair;
}

DependentPair named_pair(std::string_view name, const std::string& field) {
  std::string valid;
  for (const auto& p : gen::kPairs) {
    if (p.name == name) return {p.coordinates};
    valid += fmt::format("{}{}", valid.empty() ? "" : ", ", p.name);
  }
  throw Error(field, fmt::format("the model names no dependent pair '{}'; its pairs are {}", name, valid));
}

// The singular-J_beta hint, from the model: the wheels' ground-level inputs, and those the nominal
// pose sets off the ground plane (the excavator's raises one wheel for exactly this reason).
std::string raise_a_wheel_hint() {
  std::string grounds, nominal;
  for (const gen::WheelInfo& wheel : gen::kWheels) {
    grounds += fmt::format("{}{}", grounds.empty() ? "" : ", ", name_of(wheel.ground));
    const double z = settings().nominal_inputs[static_cast<std::size_t>(wheel.ground)];
    if (z != 0) nominal += fmt::format("{}{} = {:g} m", nominal.empty() ? "" : ", ", name_of(wheel.ground), z);
  }
  return fmt::format("Raise one wheel ({}{}) or choose another dependent pair.", grounds,
                     nominal.empty() ? "" : "; the model's nominal pose has " + nominal);
}

void solve_dependent_rates(const Model& model, Data& d, const Coordinates& s, Coordinates& sdot,
                           const DependentPair& pair, const NonholonomicOptions& options) {
  // dPhi/ds and C(s) from the fused generated function: they share most subexpressions.
  gen::kinematic_update(s, model.params(), {.dPhi_ds = &d.dPhi_ds, .C = &d.C}, false);
  factorize_dependent_rates(d, pair, options);
  for (int k = 0; k < kWheelCount; ++k) sdot(pair.index[k]) = 0;
  solve_pair_and_closure<false>(d, pair, gen::ClosureVector::Zero(), WheelVector::Zero(), sdot);
}

void factorize_dependent_rates(Data& d, const DependentPair& pair, const NonholonomicOptions& options) {
  reduce(d);
  for (int k = 0; k < kWheelCount; ++k) d.J_beta.col(k) = reduced_column(d, pair.index[k]);
  d.cond_J_beta = condition_number(d.J_beta);
  d.J_beta_lu.compute(d.J_beta);  // once: the rate basis and the accelerations use it
  if (!(d.cond_J_beta <= options.max_condition))
    throw Error(
        "dependent",
        fmt::format("J_beta for the dependent pair {} is singular: condition number {:.3g} exceeds the threshold "
                    "{:.3g}. The wheels' sideways constraint lines coincide (collinear wheel axes), "
                    "e.g. wheels on the same level under a level body. {}",
                    pair.label(), d.cond_J_beta, options.max_condition, raise_a_wheel_hint()),
        ErrorKind::singular);
}

void solve_dependent_accelerations(const Model& model, Data& d, const Coordinates& s, const Coordinates& sdot,
                                   Coordinates& sddot, const DependentPair& pair) {
  gen::convective(s, sdot, model.params(), {.dPhi_ds_dot_sdot = &d.dPhi_ds_dot_sdot, .C_dot_sdot = &d.C_dot_sdot});
  solve_dependent_accelerations_prepared(d, sddot, pair);
}

void solve_dependent_accelerations_prepared(Data& d, Coordinates& sddot, const DependentPair& pair) {
  for (int k : pair.index) sddot(k) = 0;
  solve_pair_and_closure<false>(d, pair, d.dPhi_ds_dot_sdot, d.C_dot_sdot, sddot);
}

void solve_bias_accelerations(Data& d, Coordinates& sddot, const DependentPair& pair) {
  sddot.setZero();
  solve_pair_and_closure<true>(d, pair, d.dPhi_ds_dot_sdot, d.C_dot_sdot, sddot);
}

template <std::size_t N>
void rate_basis(const Data& d, const std::array<int, N>& commanded, const DependentPair& pair,
                Eigen::Matrix<double, kCoordinateCount, static_cast<int>(N)>& T) {
  constexpr int kU = static_cast<int>(N);
  for (int c : commanded)
    for (int k : pair.index)
      if (c == k) throw Error("commanded", fmt::format("{}' is a commanded rate and one of the dependent pair", name_of(c)));
  // Input-rate columns: a unit commanded rate, and the pair's answer to it.
  Eigen::Matrix<double, kWheelCount, kU> ch;
  for (int k = 0; k < kU; ++k) ch.col(k) = reduced_column(d, commanded[static_cast<std::size_t>(k)]);
  Eigen::Matrix<double, kWheelCount, kU> pair_rates;
  if constexpr (kWheelCount > 0) {
    pair_rates = -ch;
    d.J_beta_lu.solve_in_place(pair_rates);
  }
  T.setZero();
  for (int k = 0; k < kU; ++k) {
    T(commanded[static_cast<std::size_t>(k)], k) = 1;
    for (int w = 0; w < kWheelCount; ++w) T(pair.index[static_cast<std::size_t>(w)], k) = pair_rates(w, k);
  }
  // Dependent joints: Phi_dep T_dep = -Phi_q T_q, all columns per limb block at once. T's input
  // rows are zero except the commanded (unit rows) and the pair's: rhs = those columns of dPhi/ds
  // times them.
  Eigen::Matrix<double, gen::kClosureCount, kU> rhs;
  for (int k = 0; k < kU; ++k) rhs.col(k) = d.dPhi_ds.col(commanded[static_cast<std::size_t>(k)]);
  if constexpr (kWheelCount > 0)  // (fixed-size blocks of a matrix without rows do not compile)
    for (int w = 0; w < kWheelCount; ++w)
      rhs.noalias() += d.dPhi_ds.col(pair.index[static_cast<std::size_t>(w)]).lazyProduct(pair_rates.row(w));
  for_each_limb([&](auto L) {
    constexpr gen::LimbInfo b = gen::kLimbs[static_cast<std::size_t>(decltype(L)::value)];
    Eigen::Matrix<double, kLimbMax, kU> block_rhs = Eigen::Matrix<double, kLimbMax, kU>::Zero();
    for (int i = 0; i < b.size; ++i) block_rhs.row(i) = -rhs.row(b.rows[static_cast<std::size_t>(i)]);
    const Eigen::Matrix<double, kLimbMax, kU> x =
        d.limb_inverse[static_cast<std::size_t>(decltype(L)::value)].lazyProduct(block_rhs);
    for (int j = 0; j < b.size; ++j) T.row(b.joints[static_cast<std::size_t>(j)]) = x.row(j);
  });
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
