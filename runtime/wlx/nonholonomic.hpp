// Non-holonomic wheels (thesis 4, 5; docs/excavator.md section 5): the dependent rates, one per wheel, that
// keep the wheels from sliding sideways, at velocity and at acceleration level, from the generated C(s),
// dPhi/ds and convective terms (no numeric differentiation).
//
// With the dependent joints eliminated through the linearised closure
// (beta_dep' = -Phi_dep^-1 Phi_q q'), the wheel rows reduce to C_hat q' = 0 (wheels x inputs). Splitting
// q' into the chosen dependent pair and the commanded rest gives the thesis' eq. 4.9:
// J_beta pair' + phi_hat = 0, J_beta square with one row and one column per wheel. (The "pair" is
// the set of input rates the wheels' rolling determines, one per wheel: two for a machine on two
// wheels, n for n wheels; the rest of the inputs' rates are commanded.)
#pragma once

#include "wlx/ik_options.hpp"
#include "wlx/model.hpp"

#include <array>
#include <string>
#include <string_view>
#include <vector>

WLX_MODEL_NAMESPACE_BEGIN

using WheelMatrix = Eigen::Matrix<double, kWheelCount, kWheelCount>;

// The input rates, one per wheel, that the wheel constraints determine. The model file names the
// candidates (gen::kPairCandidates) and some choices (gen::kPairs).
struct DependentPair {
  std::array<int, kWheelCount> index = gen::kPairs[gen::kDefaultPair].coordinates;  // coordinate indices
  std::string label() const;  // "(y_C', yaw')"
};
// Validates names of the candidates (one per wheel, distinct); throws wlx::Error naming `field`.
DependentPair dependent_pair(const std::vector<std::string>& names, const std::string& field = "dependent");
// A pair the model file names (e.g. "A"); throws wlx::Error naming `field` when there is none.
DependentPair named_pair(std::string_view name, const std::string& field = "dependent");
inline DependentPair default_pair() noexcept { return {}; }

// NonholonomicOptions (J_beta's largest condition): wlx/ik_options.hpp.

// The 2-norm condition number sigma_max / sigma_min of J_beta; infinity for a singular matrix. For two
// wheels in closed form, accurate to a few ulp even where the singular values nearly agree; otherwise
// by one-sided Jacobi rotations (small_dense.hpp).
double condition_number(const WheelMatrix& J);

// Velocity level. `s`: all coordinates, closure satisfied. `sdot`: the commanded input rates
// (its pair entries are ignored). Fills the pair's rates and the dependent joint rates in
// sdot, and data.J_beta, data.cond_J_beta, data.C (and the closure Jacobian). Throws wlx::Error
// if J_beta is singular.
void solve_dependent_rates(const Model& model, Data& data, const Coordinates& s, Coordinates& sdot,
                           const DependentPair& pair, const NonholonomicOptions& options = {});

// Acceleration level (thesis eqs. 6.5-6.7). Needs the full sdot of the velocity level and the
// commanded input accelerations in sddot; fills the pair's and the dependent joints' accelerations.
// Must follow solve_dependent_rates at the same (s, sdot): it reuses its factorizations in data.
void solve_dependent_accelerations(const Model& model, Data& data, const Coordinates& s, const Coordinates& sdot,
                                   Coordinates& sddot, const DependentPair& pair);

// The same two levels when data's dPhi/ds and C(s), and its dPhi/ds' s' and C' s', are current
// already (the inverse-dynamics step computes them in its fused generated passes together with the
// bodies' Jacobians). factorize_dependent_rates is the velocity level's first half: the limb
// blocks' factorizations, J_beta and its condition (throws if singular), no rates; rate_basis()
// then gives s' = T u for any commanded rates u without another solve.
void factorize_dependent_rates(Data& data, const DependentPair& pair, const NonholonomicOptions& options = {});
void solve_dependent_accelerations_prepared(Data& data, Coordinates& sddot, const DependentPair& pair);
// The same with every input acceleration zero (s''_bias of the inverse dynamics): overwrites sddot.
void solve_bias_accelerations(Data& data, Coordinates& sddot, const DependentPair& pair);

// After solve_dependent_rates at s (same pair): the full rates s' caused by a unit rate of each
// input in `commanded` (one column each), every other commanded rate zero. Linear in the rates,
// so s' = T u for u the rates of `commanded`.
// `commanded` must not include the pair (wlx::Error otherwise).
template <std::size_t N>
Eigen::Matrix<double, kCoordinateCount, static_cast<int>(N)> rate_basis(const Data& data,
                                                                        const std::array<int, N>& commanded,
                                                                        const DependentPair& pair);
// The same into T (no copy of the result).
template <std::size_t N>
void rate_basis(const Data& data, const std::array<int, N>& commanded, const DependentPair& pair,
                Eigen::Matrix<double, kCoordinateCount, static_cast<int>(N)>& T);

// Velocity in K0 of each wheel's contact point (one column per wheel, in gen::kWheels' order) for the full sdot, from
// the generated rows: along the contact frame's x axis w * spin rate, along its lateral axis n_W the sideways velocity
// C s' (zero when the constraint holds), and vertically the ground level's rate z_W' (the contact frame stays level).
// Uses data.frame_rotations, data.C and data.spin.
Eigen::Matrix<double, 3, kWheelCount> contact_velocities(const Model& model, Data& data, const Coordinates& s,
                                                         const Coordinates& sdot);

// A wheel's contact point in output column names: its contact frame's name without underscores
// (W_l: x_Wl, y_Wl, vx_Wl, ...). The wheel's own name (gen::kWheels[w].name: nh_residual_l) is the other.
std::string contact_column_stem(int wheel);

// v_W . n_W per wheel for the full sdot: the thesis' residual check of the rolling constraint.
WheelVector sideways_velocity(const Model& model, Data& data, const Coordinates& s, const Coordinates& sdot);

WLX_MODEL_NAMESPACE_END
