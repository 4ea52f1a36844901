// Inverse kinematics of the four limbs (thesis 3.3, MODEL.md 4): the closed form, with every
// branch, and the thesis' iterative method (Newton on the generated Phi and dPhi/ds).
//
// The closed form lives in the runtime, not in the generator: it is a structural solution of
// this chain (hip = roll-pitch-yaw + knee, lever = pitch-straddle + parallel guidance), needs
// branch selection and reach checks with precise error messages, and GiNaC cannot solve
// trigonometric systems; every geometry parameter still comes from Params, and the tests put
// each solution back into the generated forward kinematics.
#pragma once

#include "wlx/model.hpp"

#include <array>
#include <string_view>

namespace wlx {

enum class Limb { leg_l = 0, leg_r = 1, wheel_l = 2, wheel_r = 3 };
inline constexpr std::array<Limb, 4> kLimbs = {Limb::leg_l, Limb::leg_r, Limb::wheel_l, Limb::wheel_r};
std::string_view limb_name(Limb limb) noexcept;  // "left leg", ...

// Branch of a limb's closed form, as bits:
//   leg:   bit 0 set = knee below the hip-foot line (psi_4 < 0);
//          bit 1 set = hip yaw beyond 90 degrees (|psi_3| > 90 deg).
//   wheel: bit 0 set = lever over the other side (|theta_6 - (theta_3 + theta_6)| > 90 deg);
//          bit 1 set = camber beyond 90 degrees (|theta_2| > 90 deg);
//          bit 2 set = wheel upside down (hub below the contact point).
// 0 is MODEL.md's default for every limb.
inline constexpr int kLegBranchCount = 4;
inline constexpr int kWheelBranchCount = 8;
inline int branch_count(Limb limb) noexcept {
  return limb == Limb::leg_l || limb == Limb::leg_r ? kLegBranchCount : kWheelBranchCount;
}

// A limb's rows in Phi and its dependent joints (its block of dPhi/ds is square).
struct LimbBlock {
  int first_row = 0;
  int size = 0;                 // 3 for a leg, 4 for a wheel
  std::array<int, 4> joints{};  // coordinate indices; the 4th is unused for legs
};
LimbBlock limb_block(Limb limb) noexcept;

struct Branches {
  std::array<int, 4> limb{0, 0, 0, 0};  // indexed by Limb
};

// Solves one limb's dependent joints in s from its inputs in s. Throws wlx::Error when the
// target is out of reach (naming the limb, the distance and the reachable interval) or an input
// is not finite.
void solve_limb_closed_form(const Model& model, Limb limb, int branch, Coordinates& s);
// All four limbs.
void solve_ik_closed_form(const Model& model, Coordinates& s, const Branches& branches = {});

// Which branch of the closed form a solution lies on (for checking Newton results).
int classify_branch(const Model& model, Limb limb, const Coordinates& s);

struct NewtonOptions {
  double tolerance = 1e-13;  // on max |Phi| of the limb, in m or rad
  // A limb whose residual no damped step can lower any more has reached its rounding floor; it
  // counts as converged if that floor is below this (ill-conditioned poses amplify rounding).
  double floor_tolerance = 1e-10;
  int max_iterations = 50;
  bool damped = true;  // backtracking on |Phi| when a full step does not decrease it
};

struct NewtonReport {
  std::array<int, 4> iterations{0, 0, 0, 0};  // per limb
  double residual = 0;                        // max |Phi| over the solved limbs' equations at the end
  bool converged = false;
};

// Newton's method on Phi with the generated dPhi/ds, limb by limb (the limbs decouple), starting
// from the dependent joints already in s (warm start). Throws wlx::Error if a limb does not
// converge within max_iterations (naming the limb, its residual and the iterations).
NewtonReport solve_ik_newton(const Model& model, Coordinates& s, Data& data, const NewtonOptions& options = {});
// The same for one limb only; the other limbs' joints are left as they are.
NewtonReport solve_limb_newton(const Model& model, Limb limb, Coordinates& s, Data& data,
                               const NewtonOptions& options = {});

}  // namespace wlx
