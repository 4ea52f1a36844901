// Non-holonomic wheels (thesis 4, 5; docs/excavator.md section 5): the two dependent rates that keep both
// wheels from sliding sideways, at velocity and at acceleration level, from the generated C(s),
// dPhi/ds and convective terms (no numeric differentiation).
//
// With the 14 dependent joints eliminated through the linearised closure
// (beta_dep' = -Phi_dep^-1 Phi_q q'), the wheel rows reduce to C_hat q' = 0 (2 x 18). Splitting q'
// into the chosen dependent pair and the commanded rest gives the thesis' eq. 4.9:
// J_beta pair' + phi_hat = 0.
#pragma once

#include "wlx/model.hpp"

#include <array>
#include <string>
#include <string_view>

WLX_MODEL_NAMESPACE_BEGIN

static_assert(gen::kMaxLimbSize <= 4, "the limb blocks are inverted as 4 x 4 matrices");
static_assert(gen::kWheelCount == 2, "the non-holonomic solve is written for two wheels (a 2 x 2 J_beta)");

// The two input rates that the wheel constraints determine. The model file names the candidates
// (gen::kPairCandidates) and some pairs (gen::kPairs).
struct DependentPair {
  std::array<int, 2> index = gen::kPairs[gen::kDefaultPair].coordinates;  // coordinate indices
  std::string label() const;  // "(y_C', yaw')"
};
// Validates two names of the candidates (distinct); throws wlx::Error naming `field`.
DependentPair dependent_pair(std::string_view first, std::string_view second, const std::string& field = "dependent");
// A pair the model file names (e.g. "A"); throws wlx::Error naming `field` when there is none.
DependentPair named_pair(std::string_view name, const std::string& field = "dependent");
inline DependentPair default_pair() noexcept { return {}; }

struct NonholonomicOptions {
  // J_beta counts as singular above this condition number. The thesis scenarios reach 2.7e7
  // (ST-A1- crossing its singular point on the 1 ms grid); 1e10 leaves a wide margin while
  // stopping rates that would be rounding noise amplified by more than 1e10 * 1e-16 = 1e-6.
  double max_condition = 1e10;
};

// The 2-norm condition number sigma_max / sigma_min of a 2 x 2 matrix, in closed form and accurate
// to a few ulp even where the singular values nearly agree; infinity for a singular matrix.
double condition_number(const Eigen::Matrix2d& J);

// Velocity level. `s`: all 32 coordinates, closure satisfied. `sdot`: the commanded input rates
// (its pair entries are ignored). Fills the pair's rates and the 14 dependent joint rates in
// sdot, and data.J_beta, data.cond_J_beta, data.C (and the closure Jacobian). Throws wlx::Error
// if J_beta is singular.
void solve_dependent_rates(const Model& model, const Coordinates& s, Coordinates& sdot, const DependentPair& pair,
                           Data& data, const NonholonomicOptions& options = {});

// Acceleration level (thesis eqs. 6.5-6.7). Needs the full sdot of the velocity level and the
// commanded input accelerations in sddot; fills the pair's and the dependent joints' accelerations.
// Must follow solve_dependent_rates at the same (s, sdot): it reuses its factorizations in data.
void solve_dependent_accelerations(const Model& model, const Coordinates& s, const Coordinates& sdot,
                                   Coordinates& sddot, const DependentPair& pair, Data& data);

// After solve_dependent_rates at s (same pair): the full rates s' caused by a unit rate of each
// input in `commanded` (one column each), every other commanded rate zero. Linear in the rates,
// so s' = T u for u the rates of `commanded`.
Eigen::Matrix<double, kCoordinateCount, 4> rate_basis(const std::array<int, 4>& commanded, const DependentPair& pair,
                                                      const Data& data);

// Velocity in K0 of each wheel's contact point (columns l, r) for the full sdot, from the
// generated rows: along the contact frame's x axis w * spin rate, along its lateral axis n_W the
// sideways velocity C s' (zero when the constraint holds), and vertically the ground level's
// rate z_W' (the contact frame stays level). Uses data.frame_rotations, data.C and data.spin.
Eigen::Matrix<double, 3, 2> contact_velocities(const Model& model, const Coordinates& s, const Coordinates& sdot,
                                               Data& data);

// v_W . n_W per wheel for the full sdot: the thesis' residual check of the rolling constraint.
Eigen::Vector2d sideways_velocity(const Model& model, const Coordinates& s, const Coordinates& sdot, Data& data);

WLX_MODEL_NAMESPACE_END
