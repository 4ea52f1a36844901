// Inverse dynamics on the commanded speeds (the generated recursive pass and rate basis), the
// equations of motion M, b, Q_gravity, and the bodies' energies, centre of mass and inertias
// (dynamics.hpp); the torques' distribution is torque_distribution.cpp's.
#include "wlx/dynamics.hpp"

#include "wlx/error.hpp"

#include <fmt/format.h>

WLX_MODEL_NAMESPACE_BEGIN

Eigen::Matrix3d world_inertia(const Params& p, int body, const Eigen::Matrix3d& R) {
  const auto& info = gen::kBodyMass[static_cast<std::size_t>(body)];
  const Eigen::Vector3d I(p.*info.inertia[0], p.*info.inertia[1], p.*info.inertia[2]);
  return R * I.asDiagonal() * R.transpose();
}

Eigen::Vector3d centre_of_mass(const Model& model, const Data& data) {
  const Params& p = model.params();
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  for (int b = 0; b < gen::kBodyCount; ++b) com += (p.*gen::kBodyMass[static_cast<std::size_t>(b)].mass) * data.body_com.col(b);
  return com / model.total_mass();
}

namespace {

double mass(const Params& p, int body) { return p.*gen::kBodyMass[static_cast<std::size_t>(body)].mass; }

// Row r of J_beta for the drive of wheel w: row w of the drives' rates per commanded speed (their
// rows times T, one product for all of them). A template, so that for a model without wheels (a
// 0-row matrix, whose row Eigen refuses at compile time) nothing is compiled.
template <typename Rates, typename Jacobian>
void drive_rate_row(const Rates& drive_rates, int w, Jacobian& J_beta, int r) {
  if constexpr (Rates::RowsAtCompileTime > 0) J_beta.row(r) = drive_rates.row(w);
}

}  // namespace

void throw_no_dynamics_section() {
  throw Error("dynamics", fmt::format("model {} has no dynamics section: name its commanded speeds, actuated joints and "
                                      "gravity in the model file (docs/model-format.md, Dynamics)",
                                      gen::kModelName));
}

#if __has_include(<wlx/gen/reduced_dynamics.hpp>)
namespace {

// Both formulations' velocity level: dPhi/ds and C(s) (a generated pass), the rate basis T,
// s' = T u and J_beta.
void velocity_level(const Params& p, Data& d, const Coordinates& s, const CommandVector& u, DynamicsTerms& out,
                    const DependentPair& pair, const NonholonomicOptions& options) {
  gen::dynamics_update(s, p, {.dPhi_ds = &d.dPhi_ds, .C = &d.C, .drive = kHasWheelDrives ? &d.drive : nullptr}, false);
  factorize_dependent_rates(d, pair, options);
  rate_basis(d, kCommandedSpeeds, pair, out.T);
  out.sdot.noalias() = out.T.lazyProduct(u);  // the velocity level's solve, once T is known
  // A joint's rate is its coordinate's, T's row; a wheel drive's is its drive row times T.
  // A drive row's structural nonzeros are its hub's coordinates (kDriveColumns): a ninth of the product.
  Eigen::Matrix<double, kWheelCount, kCommandedCount> drive_rates;
  if constexpr (kHasWheelDrives)
    for (int w = 0; w < kWheelCount; ++w) {
      const auto& columns = gen::kDriveColumns[static_cast<std::size_t>(w)];
      drive_rates.row(w).setZero();
      for (int i = 0; i < columns.count; ++i) {
        const int c = columns.index[static_cast<std::size_t>(i)];
        drive_rates.row(w) += d.drive(w, c) * out.T.row(c);
      }
    }
  for (int r = 0; r < kActuatedCount; ++r) {
    const int joint = kActuatedJoints[static_cast<std::size_t>(r)];
    if (joint >= 0)
      out.J_beta.row(r) = out.T.row(joint);
    else
      drive_rate_row(drive_rates, kActuatedWheels[static_cast<std::size_t>(r)], out.J_beta, r);
  }
}

}  // namespace
#endif

void inverse_dynamics(const Model& model, Data& d, const Coordinates& s, const CommandVector& u,
                      const CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options) {
// wlx-gen writes reduced_dynamics.hpp only for a model file with a dynamics section (and removes a
// stale one), so that the runtime compiles for every model.
#if !__has_include(<wlx/gen/reduced_dynamics.hpp>)
  static_cast<void>(model), static_cast<void>(d), static_cast<void>(s), static_cast<void>(u), static_cast<void>(u_dot);
  static_cast<void>(out), static_cast<void>(options);
  throw_no_dynamics_section();
#else
  const Params& p = model.params();
  const DependentPair pair = dynamics_pair();
  // Three generated passes: dPhi/ds and C(s), which give the rate basis T; at (s, s' = T u) the
  // convective terms, which give s''_bias; at (s, s', s'') the bodies' Newton-Euler equations,
  // summed back along the chains and projected on u (Q* = T^T tau), with no mass matrix.
  velocity_level(p, d, s, u, out, pair, options);
  gen::convective(s, out.sdot, p, {.dPhi_ds_dot_sdot = &d.dPhi_ds_dot_sdot, .C_dot_sdot = &d.C_dot_sdot});
  solve_bias_accelerations(d, out.sddot_bias, pair);
  out.sddot = out.T.lazyProduct(u_dot) + out.sddot_bias;
  gen::generalized_forces(s, out.sdot, out.sddot, out.T, p, {.Qstar = &out.Qstar, .tau = &out.tau_bodies});
#endif
}

void equations_of_motion(const Model& model, Data& d, const Coordinates& s, const CommandVector& u, DynamicsTerms& out,
                         const NonholonomicOptions& options) {
#if !__has_include(<wlx/gen/reduced_dynamics.hpp>)
  static_cast<void>(model), static_cast<void>(d), static_cast<void>(s), static_cast<void>(u), static_cast<void>(out);
  static_cast<void>(options);
  throw_no_dynamics_section();
#else
  const Params& p = model.params();
  const DependentPair pair = dynamics_pair();
  // Two generated passes: dPhi/ds and C(s), which give T; at (s, s' = T u, T) the convective terms
  // and the composite-rigid-body pass (M, the velocity and gravity forces and their gain on
  // s''_bias), sharing their subexpressions.
  velocity_level(p, d, s, u, out, pair, options);
  CommandVector b_velocity;
  gen::reduced_dynamics(s, out.sdot, out.T, p,
                        {.dPhi_ds_dot_sdot = &d.dPhi_ds_dot_sdot,
                         .C_dot_sdot = &d.C_dot_sdot,
                         .M = &out.M,
                         .b_velocity = &b_velocity,
                         .B_bias = &out.B_bias,
                         .Q_gravity = &out.Q_gravity},
                        false);  // B_bias's structural zeros: set once, by DynamicsTerms
  solve_bias_accelerations(d, out.sddot_bias, pair);
  out.sddot = out.sddot_bias;
  out.b = b_velocity + out.B_bias.lazyProduct(out.sddot_bias);
#endif
}

double potential_energy(const Model& model, Data& d, const Coordinates& s) {
  const Params& p = model.params();
  // if constexpr: for a model with gravity the test is false at compile time (GCC's -Waddress).
  if constexpr (gen::kGravity == nullptr) throw Error("dynamics", "the model file has no dynamics section, so no gravity parameter");
  gen::bodies(s, Coordinates::Zero(), p, {.com = &d.body_com}, false);
  double V = 0;
  for (int i = 0; i < gen::kBodyCount; ++i) V += mass(p, i) * (p.*gen::kGravity) * d.body_com(2, i);
  return V;
}

double kinetic_energy(const Model& model, Data& d, const Coordinates& s, const Coordinates& sdot) {
  const Params& p = model.params();
  gen::bodies(s, sdot, p, {.rotations = &d.body_rotations, .Jv = &d.body_Jv, .Jw = &d.body_Jw}, false);
  double T = 0;
  for (int i = 0; i < gen::kBodyCount; ++i) {
    const Eigen::Vector3d v = d.body_Jv[static_cast<std::size_t>(i)] * sdot;
    const Eigen::Vector3d w = d.body_Jw[static_cast<std::size_t>(i)] * sdot;
    T += 0.5 * mass(p, i) * v.squaredNorm() + 0.5 * w.dot(world_inertia(p, i, d.body_rotations[static_cast<std::size_t>(i)]) * w);
  }
  return T;
}

WLX_MODEL_NAMESPACE_END
