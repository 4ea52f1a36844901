// The torques that keep the machine on its contacts: the largest smallest margin of normal forces
// and friction within the torque limits, by a cutting-plane loop of small QPs (contacts.hpp).
#include "wlx/contacts.hpp"

#include "wlx/error.hpp"
#include "wlx/numerics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

WLX_MODEL_NAMESPACE_BEGIN

using contacts_detail::at;

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
