// The ground's forces at the contacts from the multipliers of the equations of motion, and the
// momentum balance that checks them (contacts.hpp).
#include "wlx/contacts.hpp"

#include "wlx/kinematics.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <type_traits>

WLX_MODEL_NAMESPACE_BEGIN

using contacts_detail::at;

namespace {

// A template on the rows' type, so that for a model without wheels (0-row matrices, whose rows
// Eigen refuses at compile time) nothing is compiled.
template <typename Rows>
void subtract_row(const Rows& rows, int w, double scale, Coordinates& r) {
  if constexpr (Rows::RowsAtCompileTime > 0) r.noalias() -= rows.row(w).transpose() * scale;
}

// The multipliers of the closure rows (lambda) and of the rolling rows (mu) for the generalized
// forces r = tau_bodies - B^T tau on s, from the dependent joints' equations (the limbs' blocks,
// whose inverses data holds) and the dependent pair's (J_beta, factorized): r_dep = Phi_dep^T lambda
// + C_dep^T mu gives lambda = lambda_0 - Lambda mu with lambda_0 = Phi_dep^-T r_dep and Lambda the
// wheel adjoint; on the pair, J_beta^T mu = r_pair - Phi_pair^T lambda_0.
void multipliers(const Data& d, const Coordinates& r, gen::ClosureVector& lambda, WheelVector& mu) {
  lambda.setZero();
  [&]<std::size_t... L>(std::index_sequence<L...>) {
    const auto limb = [&](auto Lc) {
      constexpr gen::LimbInfo b = gen::kLimbs[decltype(Lc)::value];
      Eigen::Matrix<double, gen::kMaxLimbSize, 1> rhs = Eigen::Matrix<double, gen::kMaxLimbSize, 1>::Zero();
      for (int j = 0; j < b.size; ++j) rhs(j) = r(b.joints[at(j)]);
      const Eigen::Matrix<double, gen::kMaxLimbSize, 1> x = d.limb_inverse[decltype(Lc)::value].transpose() * rhs;
      for (int i = 0; i < b.size; ++i) lambda(b.rows[at(i)]) = x(i);
    };
    (limb(std::integral_constant<std::size_t, L>{}), ...);
  }(std::make_index_sequence<static_cast<std::size_t>(gen::kLimbCount)>{});
  if constexpr (kWheelCount > 0) {
    const DependentPair pair = dynamics_pair();
    WheelVector rhs;
    for (int w = 0; w < kWheelCount; ++w) {
      const int k = pair.index[at(w)];
      rhs(w) = r(k) - d.dPhi_ds.col(k).dot(lambda);
    }
    d.J_beta_lu.solve_transposed(rhs, mu);
    lambda.noalias() -= d.wheel_adjoint * mu;
  } else {
    static_cast<void>(mu);
  }
}

// The actuators' generalized forces B^T tau on s: a joint's torque on its coordinate, a drive's
// along its drive row.
void subtract_actuators(const Data& d, const TorqueVector& tau, Coordinates& r) {
  for (int a = 0; a < kActuatedCount; ++a) {
    const int joint = kActuatedJoints[at(a)];
    if (joint >= 0) {
      r(joint) -= tau(a);
    } else {
      subtract_row(d.drive, kActuatedWheels[at(a)], tau(a), r);
    }
  }
}

// The contacts' forces and moments from the multipliers and the drives' torques.
void wrenches(const Model& model, const Data& d, const gen::ClosureVector& lambda, const WheelVector& mu,
              const TorqueVector& tau, ContactPoints& force, ContactPoints& moment) {
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  for (int c = 0; c < kContactCount; ++c) {
    const gen::ContactInfo& info = gen::kContacts[at(c)];
    const Eigen::Matrix3d& R = d.frame_rotations[at(info.frame)];
    Eigen::Vector3d f = Eigen::Vector3d::Zero(), m = Eigen::Vector3d::Zero();
    for (int a = 0; a < 3; ++a) {
      if (info.point_rows[at(a)] >= 0) f(a) += lambda(info.point_rows[at(a)]);
      if (info.level_rows[at(a)] >= 0) m += lambda(info.level_rows[at(a)]) * R.col(a).cross(up);
    }
    if (info.wheel >= 0) {
      const gen::WheelInfo& wheel = gen::kWheels[at(info.wheel)];
      if constexpr (kWheelCount > 0) f += mu(info.wheel) * R.col(wheel.lateral_axis);
      // A drive's torque reaches the ground through the (massless) wheel: tau a + rho x f = 0 with
      // rho = -r u the rim offset gives the force tau / r along the forward axis.
      for (int a = 0; a < kActuatedCount; ++a)
        if (kActuatedWheels[at(a)] == info.wheel) f += tau(a) / (model.params().*wheel.radius) * R.col(wheel.forward_axis);
    }
    force.col(c) = f;
    moment.col(c) = m;
  }
}

}  // namespace

std::string contact_name(int contact) { return std::string(gen::kContacts[at(contact)].name); }

void contact_forces(const Model& model, Data& d, const Coordinates& s, const DynamicsTerms& terms, const TorqueVector& tau,
                    ContactForces& out) {
  if constexpr (!gen::kHasDynamics) throw_no_dynamics_section();
  forward_kinematics(model, d, s);
  Coordinates r = terms.tau_bodies;
  subtract_actuators(d, tau, r);
  gen::ClosureVector lambda;
  WheelVector mu = WheelVector::Zero();
  multipliers(d, r, lambda, mu);
  wrenches(model, d, lambda, mu, tau, out.force, out.moment);
  // The commanded speeds' equations, which the multipliers did not use: they hold when J_beta^T tau = Q*.
  double residual = 0;
  for (int k : kCommandedSpeeds) {
    double e = r(k) - d.dPhi_ds.col(k).dot(lambda);
    if constexpr (kWheelCount > 0) e -= d.C.col(k).dot(mu);
    residual = std::max(residual, std::abs(e));
  }
  const double scale = std::max(terms.tau_bodies.cwiseAbs().maxCoeff(), tau.cwiseAbs().maxCoeff());
  out.consistency = scale > 0 ? residual / scale : residual;
  for (int c = 0; c < kContactCount; ++c) {
    const gen::ContactInfo& info = gen::kContacts[at(c)];
    out.point.col(c) = d.frame_positions.col(info.frame);
    const Eigen::Vector3d f = out.force.col(c);
    out.normal(c) = f.z();
    out.tangential(c) = std::hypot(f.x(), f.y());
    out.lateral(c) = out.longitudinal(c) = 0;
    if (info.wheel >= 0) {
      const gen::WheelInfo& wheel = gen::kWheels[at(info.wheel)];
      const Eigen::Matrix3d& R = d.frame_rotations[at(info.frame)];
      out.lateral(c) = f.dot(R.col(wheel.lateral_axis));
      out.longitudinal(c) = f.dot(R.col(wheel.forward_axis));
    }
    out.friction_margin(c) = info.supports ? settings().friction[at(c)] * out.normal(c) - out.tangential(c) : 0.0;
  }
}

void contact_force_map(const Model& model, Data& d, const Coordinates& s, const DynamicsTerms& terms, ContactForceMap& out) {
  if constexpr (!gen::kHasDynamics) throw_no_dynamics_section();
  forward_kinematics(model, d, s);
  gen::ClosureVector lambda;
  WheelVector mu = WheelVector::Zero();
  ContactPoints moment;
  multipliers(d, terms.tau_bodies, lambda, mu);
  wrenches(model, d, lambda, mu, TorqueVector::Zero(), out.offset, moment);
  // Linear in tau: column a is the forces of a unit torque of actuator a alone.
  for (int a = 0; a < kActuatedCount; ++a) {
    const TorqueVector unit = TorqueVector::Unit(a);
    Coordinates r = Coordinates::Zero();
    subtract_actuators(d, unit, r);
    multipliers(d, r, lambda, mu);
    ContactPoints force;
    wrenches(model, d, lambda, mu, unit, force, moment);
    // (A generic lambda: for a model without actuators the 0-column block is never compiled.)
    [&](auto& gain) {
      if constexpr (std::decay_t<decltype(gain)>::ColsAtCompileTime > 0)
        for (int c = 0; c < kContactCount; ++c) gain.template block<3, 1>(3 * c, a) = force.col(c);
    }(out.gain);
  }
}

MomentumBalance momentum_balance(const Model& model, Data& d, const Coordinates& s, const Coordinates& sdot,
                                 const Coordinates& sddot, const ContactForces& forces) {
  const Params& p = model.params();
  gen::bodies(s, sdot, p,
              {.com = &d.body_com,
               .rotations = &d.body_rotations,
               .Jv = &d.body_Jv,
               .Jw = &d.body_Jw,
               .Jv_dot_sdot = &d.body_Jv_dot_sdot,
               .Jw_dot_sdot = &d.body_Jw_dot_sdot},
              false);
  const double g = gen::kHasDynamics ? p.*gen::kGravity : 0.0;
  const Eigen::Vector3d com = centre_of_mass(model, d);
  // Each sum's terms are added up with their largest magnitude kept: the residual is relative to it.
  Eigen::Vector3d force = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
  double force_scale = 0, moment_scale = 0;
  const auto add = [](Eigen::Vector3d& sum, double& scale, const Eigen::Vector3d& term) {
    sum += term;
    scale = std::max(scale, term.norm());
  };
  for (int c = 0; c < kContactCount; ++c) {
    add(force, force_scale, forces.force.col(c));
    add(moment, moment_scale, (forces.point.col(c) - com).cross(forces.force.col(c)));
    add(moment, moment_scale, forces.moment.col(c));
  }
  for (int b = 0; b < gen::kBodyCount; ++b) {
    const double m = p.*gen::kBodyMass[at(b)].mass;
    const Eigen::Matrix3d I = world_inertia(p, b, d.body_rotations[at(b)]);
    const Eigen::Vector3d a = d.body_Jv[at(b)] * sddot + d.body_Jv_dot_sdot.col(b);
    const Eigen::Vector3d w = d.body_Jw[at(b)] * sdot;
    const Eigen::Vector3d alpha = d.body_Jw[at(b)] * sddot + d.body_Jw_dot_sdot.col(b);
    const Eigen::Vector3d net = m * (Eigen::Vector3d(0, 0, -g) - a);  // gravity less the inertial force
    const Eigen::Vector3d arm = d.body_com.col(b) - com;
    add(force, force_scale, net);
    add(moment, moment_scale, arm.cross(net));
    add(moment, moment_scale, -(I * alpha + w.cross(I * w)));
  }
  return {force_scale > 0 ? force.norm() / force_scale : force.norm(), moment_scale > 0 ? moment.norm() / moment_scale : moment.norm()};
}

WLX_MODEL_NAMESPACE_END
