#include "wlx/contacts.hpp"

#include "wlx/error.hpp"
#include "wlx/kinematics.hpp"
#include "wlx/numerics.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

std::size_t at(int i) { return static_cast<std::size_t>(i); }

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

namespace {

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// Signed distance of p to the polygon (counter-clockwise, n vertices): the smallest distance to an
// edge's line, positive on the inner side of all of them. A segment (n = 2) or a point (n = 1)
// encloses nothing: minus the distance to it. No support at all: 0 (polygon_size 0 says so).
double signed_distance(const std::array<Eigen::Vector2d, kContactCount>& v, int n, const Eigen::Vector2d& p) {
  if (n == 0) return 0;  // no support: polygon_size 0 says so (a margin of -infinity would not print)
  if (n == 1) return -(p - v[0]).norm();
  if (n == 2) {
    const Eigen::Vector2d e = v[1] - v[0];
    const double t = std::clamp((p - v[0]).dot(e) / e.squaredNorm(), 0.0, 1.0);
    return -(p - (v[0] + t * e)).norm();
  }
  double margin = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d a = v[at(i)], b = v[at((i + 1) % n)];
    margin = std::min(margin, cross2(b - a, p - a) / (b - a).norm());
  }
  return margin;
}

}  // namespace

void stability(const Model& model, Data& d, const Coordinates& s, const ContactForces& forces, Stability& out) {
  const Params& p = model.params();
  gen::bodies(s, Coordinates::Zero(), p, {.com = &d.body_com}, false);
  out.com = centre_of_mass(model, d);

  // The supporting contacts in load, then their convex hull (Andrew's monotone chain) seen from above.
  std::array<int, kContactCount> loaded{};
  int n = 0;
  for (int c = 0; c < kContactCount; ++c)
    if (gen::kContacts[at(c)].supports && forces.normal(c) > 0) loaded[at(n++)] = c;
  const auto xy = [&](int c) { return Eigen::Vector2d(forces.point(0, c), forces.point(1, c)); };
  std::sort(loaded.begin(), loaded.begin() + n, [&](int a, int b) {
    return forces.point(0, a) < forces.point(0, b) || (forces.point(0, a) == forces.point(0, b) && forces.point(1, a) < forces.point(1, b));
  });
  std::array<int, 2 * kContactCount + 1> hull{};
  int h = 0;
  for (int pass = 0; pass < 2 && n > 0; ++pass) {
    const int start = h;
    for (int k = 0; k < n; ++k) {
      const int c = loaded[at(pass == 0 ? k : n - 1 - k)];
      while (h >= start + 2 && cross2(xy(hull[at(h - 1)]) - xy(hull[at(h - 2)]), xy(c) - xy(hull[at(h - 2)])) <= 0) --h;
      hull[at(h++)] = c;
    }
    --h;  // each chain's last point starts the other
  }
  if (n == 1) h = 1;
  out.polygon_size = std::min(h, kContactCount);
  std::array<Eigen::Vector2d, kContactCount> vertices{};
  for (int i = 0; i < out.polygon_size; ++i) {
    out.polygon[at(i)] = hull[at(i)];
    vertices[at(i)] = xy(hull[at(i)]);
  }
  const int m = out.polygon_size;
  out.static_margin = signed_distance(vertices, m, out.com.head<2>());

  // The support's net wrench (about K0's origin), and its zero-moment point on the plane z = h of
  // the loaded contacts' mean height: M - zmp x F has no horizontal part there.
  Eigen::Vector3d F = Eigen::Vector3d::Zero(), M = Eigen::Vector3d::Zero();
  double height = 0;
  for (int c = 0; c < kContactCount; ++c) {
    F += forces.force.col(c);
    M += forces.point.col(c).cross(forces.force.col(c)) + forces.moment.col(c);
  }
  for (int i = 0; i < m; ++i) height += forces.point(2, out.polygon[at(i)]) / m;
  out.zmp = F.z() > 0 ? Eigen::Vector3d((height * F.x() - M.y()) / F.z(), (M.x() + height * F.y()) / F.z(), height)
                      : Eigen::Vector3d(out.com.x(), out.com.y(), height);  // nothing carries the machine: no ZMP
  out.zmp_margin = signed_distance(vertices, m, out.zmp.head<2>());

  // Force-angle: the net force and moment on the CoM other than the support's, f_r = -F and
  // n_r = -(M - com x F), about each edge a -> b (the next vertex counter-clockwise; a segment's
  // two directions). l: from the CoM to the edge's axis, normal to it; the moment's part along the
  // axis becomes the equivalent couple of forces at distance |l|; theta from f* to l, positive while
  // l lies outward of f* (the machine is held up by that edge's side).
  const Eigen::Vector3d f_r = -F, n_r = -(M - out.com.cross(F));
  out.tip_angle = std::numeric_limits<double>::infinity();
  out.tip_edge = {-1, -1};
  const int edges = m >= 3 ? m : (m == 2 ? 2 : 0);
  for (int i = 0; i < edges; ++i) {
    const int ca = out.polygon[at(i)], cb = out.polygon[at((i + 1) % m)];
    const Eigen::Vector3d a = forces.point.col(ca), b = forces.point.col(cb);
    const Eigen::Vector3d axis = (b - a).normalized();
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - axis * axis.transpose();
    const Eigen::Vector3d l = across * (b - out.com);
    const Eigen::Vector3d f_star = across * f_r + l.normalized().cross(axis.dot(n_r) * axis) / l.norm();
    const double theta = std::atan2(-axis.dot(f_star.cross(l)), f_star.dot(l)) ;
    if (theta < out.tip_angle) out.tip_angle = theta, out.tip_edge = {ca, cb};
  }
  if (edges == 0) out.tip_angle = 0;  // one contact in load: no edge to stand on
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

double smallest_contact_margin(const Model& model, const ContactForces& forces) {
  const double weight = model.total_mass() * (gen::kHasDynamics ? model.params().*gen::kGravity : 1.0);
  double margin = std::numeric_limits<double>::infinity();
  for (int c = 0; c < kContactCount; ++c)
    if (gen::kContacts[at(c)].supports) margin = std::min({margin, forces.normal(c), forces.friction_margin(c)});
  return margin / weight;
}

ContactDistribution distribute_torques_on_contacts(const Model& model, Data& d, const Coordinates& s, const DynamicsTerms& terms,
                                                   const ContactDistributionOptions& options) {
  ContactDistribution out;
  if constexpr (!gen::kHasDynamics || kContactCount == 0) {
    static_cast<void>(s), static_cast<void>(terms), static_cast<void>(options), static_cast<void>(d);
    throw Error("weighting", fmt::format("model {} has no contacts with the ground (or no dynamics section): there is no "
                                         "margin to keep",
                                         gen::kModelName));
  } else {
    constexpr int kA = kActuatedCount, kU = kCommandedCount, kK = kA - kU;  // kK: the torques' free directions
    const double weight = model.total_mass() * (model.params().*gen::kGravity);
    // tau = tau_1 + scale N z: the model file's weights' torques plus the null space of J_beta^T (the last
    // columns of a full QR of J_beta), scaled so z is of order one.
    const TorqueVector tau_1 = distribute_torques(terms.J_beta, terms.Qstar, Weighting::model_weights());
    const Eigen::Matrix<double, kA, kK> N = numerics::left_null_space(terms.J_beta);
    const double scale = std::max(tau_1.cwiseAbs().maxCoeff(), weight * 1e-3);
    ContactForceMap map;
    contact_force_map(model, d, s, terms, map);
    // Each contact's force, over the weight, as f0 + F z.
    Eigen::Matrix<double, 3 * kContactSlots, 1> f0;
    for (int c = 0; c < kContactCount; ++c)
      f0.template segment<3>(3 * c) = map.offset.col(c) + map.gain.template middleRows<3>(3 * c) * tau_1;
    f0 /= weight;
    // Coefficient by coefficient (lazyProduct): Eigen's blocked product for these sizes compiles
    // its kernels for each model (0.5 s), and this runs once per distribution.
    const Eigen::Matrix<double, 3 * kContactSlots, kK> F = map.gain.lazyProduct(N) * (scale / weight);
    // Constraints on x = (z, t), rows a x >= b: each supporting contact's normal force >= t, its
    // friction margin along tangent directions >= t, and the torque limits.
    std::vector<Eigen::Matrix<double, 1, kK + 1>> rows;
    std::vector<double> bounds;
    const Settings& settings_in_use = settings();
    const auto add = [&](const Eigen::Matrix<double, 1, kK>& gain, double offset) {  // offset + gain z - t >= 0
      Eigen::Matrix<double, 1, kK + 1> row;
      row << gain, -1.0;
      rows.push_back(row);
      bounds.push_back(-offset);
    };
    const auto cone_cut = [&](int c, const Eigen::Vector2d& dir) {  // mu f_n - dir . f_t
      const double mu = settings_in_use.friction[at(c)];
      add(mu * F.row(3 * c + 2) - dir.x() * F.row(3 * c) - dir.y() * F.row(3 * c + 1),
          mu * f0(3 * c + 2) - dir.x() * f0(3 * c) - dir.y() * f0(3 * c + 1));
    };
    for (int c = 0; c < kContactCount; ++c) {
      if (!gen::kContacts[at(c)].supports) continue;
      add(F.row(3 * c + 2), f0(3 * c + 2));
      for (int j = 0; j < 8; ++j) cone_cut(c, Eigen::Vector2d(std::cos(j * 0.7853981633974483), std::sin(j * 0.7853981633974483)));
    }
    if (settings_in_use.has_torque_limits)
      for (int a = 0; a < kA; ++a) {
        const double limit = settings_in_use.torque_limits[at(a)];
        Eigen::Matrix<double, 1, kK + 1> row;
        row << scale * N.row(a), 0.0;
        rows.push_back(row), bounds.push_back(-limit - tau_1(a));   // tau_a >= -limit
        rows.push_back(-row), bounds.push_back(-limit + tau_1(a));  // tau_a <= limit
      }
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(kK + 1, kK + 1);
    H.topLeftCorner(kK, kK).diagonal().setConstant(options.regularization);
    Eigen::VectorXd cost = Eigen::VectorXd::Zero(kK + 1);
    cost(kK) = -1;
    TorqueVector tau = tau_1;
    for (int round = 0; round < options.max_rounds; ++round) {
      Eigen::MatrixXd A(static_cast<Eigen::Index>(rows.size()), kK + 1);
      Eigen::VectorXd b(static_cast<Eigen::Index>(rows.size()));
      for (std::size_t i = 0; i < rows.size(); ++i) A.row(static_cast<Eigen::Index>(i)) = rows[i], b(static_cast<Eigen::Index>(i)) = bounds[i];
      const qp::Result r = qp::solve(H, cost, A, b);
      out.iterations += r.iterations;
      ++out.programmes;
      // Converged, or stalled at rounding (the last digits of a degenerate optimum): both are the answer.
      if (!(r.converged || (r.residual <= 1e-6 && r.gap <= 1e-6)))
        throw Error("weighting", settings_in_use.has_torque_limits
                                     ? fmt::format("no torques within the actuators' limits (dynamics.torque_limits) produce "
                                                   "the generalized forces here (the contact-keeping programme has no solution: "
                                                   "residual {:.3g})",
                                                   r.residual)
                                     : fmt::format("the contact-keeping programme did not converge (residual {:.3g}, gap {:.3g})",
                                                   r.residual, r.gap));
      const Eigen::Matrix<double, kK, 1> z = r.x.head(kK);
      tau = tau_1 + scale * (N * z);
      // A cut where a cone's true margin falls short of the programme's t: the tangent plane there.
      const Eigen::Matrix<double, 3 * kContactSlots, 1> f = f0 + F * z;
      bool cut = false;
      for (int c = 0; c < kContactCount; ++c) {
        if (!gen::kContacts[at(c)].supports) continue;
        const Eigen::Vector2d tangential(f(3 * c), f(3 * c + 1));
        const double true_margin = settings_in_use.friction[at(c)] * f(3 * c + 2) - tangential.norm();
        if (true_margin < r.x(kK) - options.tolerance && tangential.norm() > 0) {
          cone_cut(c, tangential.normalized());
          cut = true;
        }
      }
      if (!cut) break;
    }
    out.tau = tau;
    ContactForces forces;
    contact_forces(model, d, s, terms, tau, forces);
    out.margin = smallest_contact_margin(model, forces);
    return out;
  }
}

WLX_MODEL_NAMESPACE_END
