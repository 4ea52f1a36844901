// Contact forces and margins, for every model the tests build (compiled once per model, like
// test_any_model.cpp): the runtime's multipliers (the limbs' blocks and J_beta, contacts.cpp)
// against the whole machine's momentum balance by the bodies' accelerations, and against a dense
// least-squares solve of every multiplier of the equations of motion on all coordinates (the
// closure rows, the rolling rows and the held inputs at once); the affine map of the torques to
// the forces against the forces themselves; the margins against their definitions.
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <doctest/doctest.h>
#include <wlx/contacts.hpp>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>
#include <string>

using namespace wlx;

namespace {

const char* contact_titled(const char* what) {
  static std::deque<std::string> titles;
  return titles.emplace_back(std::string(gen::kModelName) + ": " + what).c_str();
}

// A reachable state near the nominal one, every input moved by up to `reach`.
[[maybe_unused]] Coordinates reachable_state(std::mt19937_64& rng, const Model& model, double reach) {
  std::uniform_real_distribution<double> u(-1, 1);
  for (int attempt = 0; attempt < 1000; ++attempt) {
    Coordinates s = nominal_inputs();
    for (int k = 0; k < kInputCount; ++k) s(k) += reach * u(rng);
    try {
      solve_ik_closed_form(model, s);
      return s;
    } catch (const Error&) {
    }
  }
  FAIL("no reachable state near the nominal one in 1000 draws");
  return {};
}

[[maybe_unused]] bool info_supports_loaded(int c, const ContactForces& f) {
  return gen::kContacts[static_cast<std::size_t>(c)].supports && f.normal(c) > 0;
}

[[maybe_unused]] bool is_held(int k) {
  if (k >= kInputCount) return false;
  for (int c : kCommandedSpeeds)
    if (c == k) return false;
  for (int c : dynamics_pair().index)
    if (c == k) return false;
  return true;
}

// Every multiplier at once: A^T nu = tau_bodies - B^T tau with A = [dPhi/ds; C; the held inputs'
// unit rows], by a column-pivoted QR of A^T (n x rows), not the runtime's block solves. Returns
// the relative residual of the solve (the system is consistent when tau produces Q*).
template <typename Nu>
double dense_multipliers(const Data& d, const DynamicsTerms& t, const TorqueVector& tau, Nu& nu) {
  constexpr int kRows = gen::kClosureCount + kWheelCount;
  int held = 0;
  for (int k = 0; k < kCoordinateCount; ++k) held += is_held(k);
  Eigen::MatrixXd At = Eigen::MatrixXd::Zero(kCoordinateCount, kRows + held);
  for (int i = 0; i < gen::kClosureCount; ++i) At.col(i) = d.dPhi_ds.row(i).transpose();
  // Dynamic-size copies: a model without wheels has 0-row matrices, whose rows do not compile.
  const Eigen::MatrixXd C = d.C, drive = d.drive;
  for (int w = 0; w < kWheelCount; ++w) At.col(gen::kClosureCount + w) = C.row(w).transpose();
  for (int k = 0, h = 0; k < kCoordinateCount; ++k)
    if (is_held(k)) At(k, kRows + h++) = 1;
  Eigen::VectorXd r = t.tau_bodies;
  for (int a = 0; a < kActuatedCount; ++a) {
    const int joint = kActuatedJoints[static_cast<std::size_t>(a)];
    if (joint >= 0)
      r(joint) -= tau(a);
    else
      r -= drive.row(kActuatedWheels[static_cast<std::size_t>(a)]).transpose() * tau(a);
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(At);
  REQUIRE(qr.rank() == kRows + held);  // independent rows: the multipliers are unique
  nu = qr.solve(r);
  return (At * nu - r).norm() / std::max(r.norm(), 1.0);
}

}  // namespace

TEST_CASE(contact_titled("contact forces balance the machine's momentum to 1e-9, equal a dense solve of every multiplier, "
                         "and follow the torques by their affine map")) {
  if constexpr (!gen::kHasDynamics || kContactCount == 0) {
    MESSAGE(gen::kModelName << ": no contacts with a dynamics section: nothing to balance");
    return;
  } else {
    const Model model;
    Data d;
    DynamicsTerms t;
    ContactForces forces;
    ContactForceMap map;
    std::mt19937_64 rng(307);
    std::uniform_real_distribution<double> half(-0.5, 0.5);
    double worst_force = 0, worst_moment = 0, worst_dense = 0, worst_solve = 0, worst_map = 0, worst_consistency = 0;
    int steps = 0;
    for (int trial = 0; trial < 8; ++trial) {
      const Coordinates s = reachable_state(rng, model, 0.03);
      CommandVector u, u_dot;
      for (int k = 0; k < kCommandedCount; ++k) u(k) = half(rng), u_dot(k) = half(rng);
      inverse_dynamics(model, d, s, u, u_dot, t);
      contact_force_map(model, d, s, t, map);
      for (const Weighting& w : {Weighting::model_weights(), Weighting::contribution()}) {
        const TorqueVector tau = distribute_torques(t.J_beta, t.Qstar, w);
        contact_forces(model, d, s, t, tau, forces);
        const MomentumBalance balance = momentum_balance(model, d, s, t.sdot, t.sddot, forces);
        worst_force = std::max(worst_force, balance.force);
        worst_moment = std::max(worst_moment, balance.moment);
        worst_consistency = std::max(worst_consistency, forces.consistency);
        Eigen::VectorXd nu;
        worst_solve = std::max(worst_solve, dense_multipliers(d, t, tau, nu));
        // The dense solve's forces: each contact's point rows are the K0 components, its rolling
        // row the lateral force along n_W; a drive adds tau / r along t_W.
        const double scale = std::max(forces.force.cwiseAbs().maxCoeff(), 1.0);
        for (int c = 0; c < kContactCount; ++c) {
          const gen::ContactInfo& info = gen::kContacts[static_cast<std::size_t>(c)];
          Eigen::Vector3d f = Eigen::Vector3d::Zero();
          for (int a = 0; a < 3; ++a)
            if (info.point_rows[static_cast<std::size_t>(a)] >= 0) f(a) = nu(info.point_rows[static_cast<std::size_t>(a)]);
          if (info.wheel >= 0) {
            const gen::WheelInfo& wheel = gen::kWheels[static_cast<std::size_t>(info.wheel)];
            const Eigen::Matrix3d& R = d.frame_rotations[static_cast<std::size_t>(info.frame)];
            f += nu(gen::kClosureCount + info.wheel) * R.col(wheel.lateral_axis);
            for (int a = 0; a < kActuatedCount; ++a)
              if (kActuatedWheels[static_cast<std::size_t>(a)] == info.wheel)
                f += tau(a) / (model.params().*wheel.radius) * R.col(wheel.forward_axis);
          }
          worst_dense = std::max(worst_dense, (f - forces.force.col(c)).cwiseAbs().maxCoeff() / scale);
          const Eigen::Vector3d mapped = map.offset.col(c) + Eigen::MatrixXd(map.gain).middleRows(3 * c, 3) * Eigen::VectorXd(tau);
          worst_map = std::max(worst_map, (mapped - forces.force.col(c)).cwiseAbs().maxCoeff() / scale);
        }
        ++steps;
      }
    }
    MESSAGE(gen::kModelName << ": " << steps << " steps; momentum balance, force " << worst_force << ", moment " << worst_moment
                            << "; vs dense multipliers " << worst_dense << " (solve residual " << worst_solve
                            << "); affine map " << worst_map << "; commanded equations " << worst_consistency);
    // Relative to the largest term of each sum; the terms are of the weight's order and the
    // multipliers come from blocks of condition up to ~1e4: 1e-9 leaves three digits of margin.
    CHECK(worst_force <= 1e-9);
    CHECK(worst_moment <= 1e-9);
    CHECK(worst_consistency <= 1e-9);
    CHECK(worst_solve <= 1e-9);
    CHECK(worst_dense <= 1e-9);
    CHECK(worst_map <= 1e-9);
  }
}

TEST_CASE(contact_titled("margins: the support polygon holds the loaded contacts, the static margin is the CoM's distance "
                         "to its nearest edge, the ZMP of a machine at rest is under its CoM, and friction margins are mu f_n - f_t")) {
  if constexpr (!gen::kHasDynamics || kContactCount == 0) {
    return;
  } else {
    const Model model;
    Data d;
    DynamicsTerms t;
    ContactForces forces;
    Stability st;
    std::mt19937_64 rng(311);
    int checked = 0;
    for (int trial = 0; trial < 6; ++trial) {
      const Coordinates s = reachable_state(rng, model, 0.03);
      // At rest: the net force on the CoM is its weight, so the ZMP is the CoM's projection and
      // the force-angle about each edge is the angle at which the CoM sees it.
      inverse_dynamics(model, d, s, CommandVector::Zero(), CommandVector::Zero(), t);
      TorqueVector tau;
      try {
        tau = distribute_torques(t.J_beta, t.Qstar, Weighting::model_weights());
      } catch (const Error&) {
        continue;  // a pose no actuator set can hold (its own test): no forces to check
      }
      contact_forces(model, d, s, t, tau, forces);
      stability(model, d, s, forces, st);
      const double weight = model.total_mass() * (model.params().*gen::kGravity);
      CHECK(std::abs(forces.normal.sum() - weight) <= 1e-9 * weight);
      CHECK((st.zmp.head<2>() - st.com.head<2>()).norm() <= 1e-9);
      CHECK(std::abs(st.zmp_margin - st.static_margin) <= 1e-9);
      for (int c = 0; c < kContactCount; ++c) {
        const gen::ContactInfo& info = gen::kContacts[static_cast<std::size_t>(c)];
        if (!info.supports) continue;
        CHECK(forces.friction_margin(c) ==
              doctest::Approx(gen::kContactFriction[static_cast<std::size_t>(c)] * forces.force(2, c) - forces.force.col(c).head<2>().norm()).epsilon(1e-12));
      }
      // Every loaded supporting contact is a vertex or inside; the CoM's margin is the smallest
      // distance to an edge's line, with the edges counter-clockwise.
      const int m = st.polygon_size;
      if (m >= 3) {
        double area = 0, nearest = 1e300;
        for (int i = 0; i < m; ++i) {
          const Eigen::Vector2d a = forces.point.col(st.polygon[static_cast<std::size_t>(i)]).head<2>();
          const Eigen::Vector2d b = forces.point.col(st.polygon[static_cast<std::size_t>((i + 1) % m)]).head<2>();
          area += a.x() * b.y() - a.y() * b.x();
          const Eigen::Vector2d e = (b - a).normalized(), p = st.com.head<2>() - a;
          nearest = std::min(nearest, e.x() * p.y() - e.y() * p.x());
          for (int c = 0; c < kContactCount; ++c)
            if (info_supports_loaded(c, forces)) {
              const Eigen::Vector2d q = forces.point.col(c).head<2>() - a;
              CHECK(e.x() * q.y() - e.y() * q.x() >= -1e-12);
            }
        }
        CHECK(area > 0);
        CHECK(st.static_margin == doctest::Approx(nearest).epsilon(1e-12));
        if (st.static_margin > 0) CHECK(st.tip_angle > 0);
      }
      ++checked;
    }
    CHECK(checked >= 3);
  }
}
