// The tripod (tests/models/tripod.yaml): contact forces and tip-over against hand calculations.
// Its masses sit where statics finds them without the model: the body's and the payload's CoM at
// the body's frame plus (com_x, com_y) horizontally; the legs are massless. Three point contacts then carry the weight W in
// the proportions N with [1 1 1; x_a x_b x_c; y_a y_b y_c] N = W [1; X; Y], (X, Y) the CoM: whatever
// the torque distribution, which sets only the horizontal forces between the feet.
#include <Eigen/LU>
#include <doctest/doctest.h>
#include <wlx/contacts.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/simulation.hpp>

#include <cmath>
#include <string>

using namespace wlx;

namespace {

constexpr double kMassBody = 60 + 20, kG = 9.81, kComX = 0.05, kComY = 0.03;
const Eigen::Matrix<double, 2, 3> kFeet = (Eigen::Matrix<double, 2, 3>() << 0.62, -0.38, -0.26, 0.05, 0.52, -0.47).finished();

// The normal forces of the three feet for the body's frame at (x, y), level, at rest.
Eigen::Vector3d hand_normals(double x, double y) {
  Eigen::Matrix3d A;
  A << 1, 1, 1, kFeet.row(0), kFeet.row(1);
  return A.lu().solve(kMassBody * kG * Eigen::Vector3d(1, x + kComX, y + kComY));
}

}  // namespace

TEST_CASE("tripod: standing still, the feet carry the weight as statics says, under any torque distribution") {
  const Model model;
  Data d;
  DynamicsTerms t;
  ContactForces forces;
  Coordinates s = nominal_inputs();
  solve_ik_closed_form(model, s);
  inverse_dynamics(model, d, s, CommandVector::Zero(), CommandVector::Zero(), t);
  const Eigen::Vector3d expected = hand_normals(0, 0);
  const double weight = kMassBody * kG;
  TorqueVector diagonal;
  for (int i = 0; i < kActuatedCount; ++i) diagonal(i) = 1.0 + i;  // a third distribution, far from the others
  Eigen::Matrix<double, 2, 3> horizontal[3];
  int k = 0;
  for (const Weighting& w : {Weighting::model_weights(), Weighting::contribution(), Weighting::diagonal_of(diagonal)}) {
    const TorqueVector tau = distribute_torques(t.J_beta, t.Qstar, w);
    contact_forces(model, d, s, t, tau, forces);
    REQUIRE(kContactCount == 3);
    for (int c = 0; c < 3; ++c) {
      CHECK(forces.normal(c) == doctest::Approx(expected(c)).epsilon(1e-9));
      CHECK(forces.point.col(c).head<2>().isApprox(kFeet.col(c), 1e-12));
      CHECK(gen::kContactFriction[static_cast<std::size_t>(c)] == 0.7);  // the model file's, not the default
      CHECK(forces.friction_margin(c) == doctest::Approx(0.7 * expected(c) - forces.tangential(c)).epsilon(1e-9));
    }
    // At rest nothing pushes the machine sideways: the horizontal forces cancel.
    CHECK(forces.force.topRows<2>().rowwise().sum().norm() <= 1e-9 * weight);
    horizontal[k++] = forces.force.topRows<2>();
  }
  // ... but the distribution sets them: the feet pull against each other differently.
  MESSAGE("horizontal forces (N), weighting 1:\n" << horizontal[0] << "\nweighting 2:\n" << horizontal[1]);
  CHECK((horizontal[0] - horizontal[1]).cwiseAbs().maxCoeff() > 1e-3);
  CHECK((horizontal[0] - horizontal[2]).cwiseAbs().maxCoeff() > 1e-3);
}

TEST_CASE("tripod: backing up at constant speed, it tips over the rear feet's edge when its CoM crosses it, and the run says so") {
  // Pure translation of the one mass at constant speed: no inertial force, so the run is statics
  // at every sample and the CoM crosses the edge b-c at a time found by hand. The foot ahead then
  // unloads, and beyond it would pull on the ground.
  constexpr double kSpeed = -0.5;
  const double total = kMassBody;
  const Eigen::Vector2d com0(kComX, kComY), velocity(kSpeed, 0);
  // (com0 + velocity t - b) x (c - b) = 0.
  const Eigen::Vector2d b = kFeet.col(1), c = kFeet.col(2), e = c - b;
  const auto cross = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q) { return p.x() * q.y() - p.y() * q.x(); };
  const double t_cross = -cross(com0 - b, e) / cross(velocity, e);
  REQUIRE(t_cross > 0.1);
  REQUIRE(t_cross < 1.5);

  Scenario sc;
  sc.id = "tip";
  sc.weighting = Weighting::model_weights();
  sc.rates(coordinate_index("x_B")) = kSpeed;
  sc.duration = 1.2;
  sc.dt = 1e-3;
  sc.stop_on_contact_loss = true;
  const Trajectory run = simulate(sc);
  REQUIRE_FALSE(run.complete);
  MESSAGE(run.error);
  CHECK((run.error.find("tips over the edge footb-footc") != std::string::npos ||
         run.error.find("tips over the edge footc-footb") != std::string::npos));
  const double t_stop = run.samples.size() * sc.dt;  // the first sample not kept
  CHECK(t_stop >= t_cross);
  CHECK(t_stop <= t_cross + sc.dt);
  // Until then the normal forces are the hand calculation's along the way, and the margins positive.
  for (const Sample& smp : run.samples) {
    const Eigen::Vector3d expected = hand_normals(smp.s(coordinate_index("x_B")), 0);
    for (int k = 0; k < 3; ++k) CHECK(smp.forces.normal(k) == doctest::Approx(expected(k)).epsilon(1e-8).scale(total * kG));
    CHECK(smp.stability.tip_angle > 0);
    CHECK(smp.momentum_residual <= 1e-9);
  }
  // The same run told to go on reports the lift instead of stopping.
  sc.stop_on_contact_loss = false;
  const Trajectory on = simulate(sc);
  CHECK(on.complete);
  CHECK(on.samples.back().forces.normal(0) < 0);
  CHECK(on.samples.back().stability.tip_angle < 0);
}

TEST_CASE("tripod: weighting 3 keeps every torque within the model file's limits, and says so where none can carry the load") {
  static_assert(gen::kHasTorqueLimits, "tripod.yaml gives dynamics.torque_limits");
  for (double limit : gen::kTorqueLimits) CHECK(limit == 300.0);
  Coordinates s = nominal_inputs();
  const Model standing;
  solve_ik_closed_form(standing, s);
  // Carried within the limits: the torques respect them, the feet stay loaded and inside their
  // cones, and the margin is at least weighting 1's (the programme could have chosen those).
  Data d;
  DynamicsTerms t;
  inverse_dynamics(standing, d, s, CommandVector::Zero(), CommandVector::Zero(), t);
  const ContactDistribution w3 = distribute_torques_on_contacts(standing, d, s, t);
  CHECK(w3.tau.cwiseAbs().maxCoeff() <= 300.0 * (1 + 1e-9));
  CHECK(w3.margin > 0);
  const TorqueVector tau_1 = distribute_torques(t.J_beta, t.Qstar, Weighting::model_weights());
  ContactForces forces;
  contact_forces(standing, d, s, t, tau_1, forces);
  REQUIRE(tau_1.cwiseAbs().maxCoeff() <= 300.0);  // the limits are not what sets the margins here
  if (tau_1.cwiseAbs().maxCoeff() <= 300.0) CHECK(w3.margin >= smallest_contact_margin(standing, forces) - 1e-9);
  // The torques produce the generalized forces: J_beta^T tau = Q*.
  CHECK((t.J_beta.transpose() * w3.tau - t.Qstar).norm() <= 1e-9 * t.Qstar.norm());
  // Twenty times the payload (the machine 5.75 times as heavy): every distribution needs more than
  // 300 N m somewhere.
  gen::Params heavy_params = standing.params();
  heavy_params.m_payload *= 20;
  const Model heavy(heavy_params);
  Data dh;
  DynamicsTerms th;
  inverse_dynamics(heavy, dh, s, CommandVector::Zero(), CommandVector::Zero(), th);
  const TorqueVector least = distribute_torques(th.J_beta, th.Qstar, Weighting::model_weights());
  INFO("weighting 1 needs ", least.cwiseAbs().maxCoeff(), " N m");
  CHECK_THROWS_WITH_AS(distribute_torques_on_contacts(heavy, dh, s, th),
                       doctest::Contains("no torques within the actuators' limits (dynamics.torque_limits)"), Error);
}
