// A controller designed on wlx's equations, tested in a physics engine: the computed-torque loop of
// examples/controller (wlx's reduced inverse dynamics on the commanded speeds, the torques split
// over the actuators by the model's weights) drives MuJoCo's simulation of the same machine,
// exported by `wlx export mjcf`, at 1 kHz. MuJoCo's wheels roll by friction on soft contacts and
// may slip or lift; wlx's model holds them exactly. The run drives and turns as a rigid body: the
// base forward along its heading at 0.5 m/s while it yaws at 10 deg/s (a circle of 2.9 m radius),
// the wheels' contact points carried along with it, the speeds ramped up smoothly over 1 s.
//
// Every millisecond:
//   1. MuJoCo's state as wlx's coordinates: the free base's position and Z-Y-X angles, the joints,
//      and the inputs the closure rows tie to a frame (a contact point's x, y and ground height)
//      from wlx's forward kinematics; their rates likewise (the closure's rows differentiated);
//   2. u'_cmd = u'_ref + Kd (u_ref - u) + Kp (q_ref - q) on the commanded coordinates;
//   3. tau from wlx's inverse dynamics at the measured state and the torque split, applied to
//      MuJoCo's motors of the same names; then one MuJoCo step of 1 ms.
// It reports, over the run: the tracking error of the commanded coordinates, each wheel's slip (the
// speed of the wheel's material point at the contact, which wlx's rolling holds at zero) and each
// wheel's normal force, MuJoCo's against wlx's prediction for the same torques (contact_forces).
//
// Usage: wlx_mujoco_cosim DESCRIPTION.json [OUT.csv] (one row per millisecond: the tracking errors,
// and per wheel its slip and both normal forces). Exits 1 when the run misses the bounds it states
// at the end (docs/export.md gives the figures), 2 on bad input.
#include "physics_engine.hpp"

#include <wlx/support/atomic_file.hpp>
#include <wlx/contacts.hpp>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

using namespace wlx;

namespace {

constexpr double kStep = 0.001;        // s: the controller's period and MuJoCo's step
constexpr double kDuration = 3.0;      // s
constexpr double kRamp = 1.0;          // s: every speed ramps from 0 to its value
constexpr double kKp = 400, kKd = 40;  // 1/s^2, 1/s: critically damped at 20 rad/s (the report's closed loop)

constexpr double kSpeed = 0.5;                                // m/s, forward along the heading
constexpr double kYawRate = 10 * std::numbers::pi / 180;      // rad/s

// r(t): 0 to 1 over kRamp with zero slope at both ends, and its derivative.
double ramp(double t) { return t < kRamp ? 0.5 * (1 - std::cos(std::numbers::pi * t / kRamp)) : 1.0; }
double ramp_rate(double t) { return t < kRamp ? 0.5 * std::numbers::pi / kRamp * std::sin(std::numbers::pi * t / kRamp) : 0.0; }

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: wlx_mujoco_cosim DESCRIPTION.json [OUT.csv]\n");
    return 2;
  }
  std::ifstream in(argv[1]);
  if (!in) throw Error("DESCRIPTION", fmt::format("cannot read {}", argv[1]));
  std::stringstream text;
  text << in.rdbuf();
  const std::string description = text.str();
  cli::PhysicsEngine engine(description, std::vector<std::string>(gen::kCoordinateNames.begin(), gen::kCoordinateNames.end()));
  const std::vector<cli::EngineFreeBase>& bases = engine.free_bases();
  if (bases.size() != 1) throw Error("frames", "this example drives a machine with one floating base");

  const Model model;
  Data data;
  DynamicsTerms terms;

  // The start: the nominal pose, its limbs solved in closed form on the model's branches (within
  // the joints' ranges, which MuJoCo's joint limits enforce), at rest.
  Coordinates s0 = nominal_inputs();
  solve_ik_closed_form(model, s0);
  engine.set_state(s0, Coordinates::Zero());
  // The contact of each wheel among the model's (the engine's contacts are in the same order).
  std::vector<int> contact_of_wheel(kWheelCount, -1);
  for (int c = 0; c < kContactCount; ++c)
    if (gen::kContacts[static_cast<std::size_t>(c)].wheel >= 0) contact_of_wheel[static_cast<std::size_t>(gen::kContacts[static_cast<std::size_t>(c)].wheel)] = c;
  if (std::count(contact_of_wheel.begin(), contact_of_wheel.end(), -1) > 0) throw Error("contacts", "this example needs a contact on every wheel");

  // The reference: the base's x, y and yaw, and each wheel's contact point carried with the base
  // (its x commanded, its y following by rolling). Every other commanded coordinate stays.
  const double V = kSpeed, Omega = kYawRate;
  // A coordinate's place among the commanded speeds.
  const auto commanded = [&](int c) {
    const auto it = std::find(kCommandedSpeeds.begin(), kCommandedSpeeds.end(), c);
    if (it == kCommandedSpeeds.end())
      throw Error("speeds", fmt::format("{} is no commanded speed of the model", gen::kCoordinateNames[static_cast<std::size_t>(c)]));
    return static_cast<int>(it - kCommandedSpeeds.begin());
  };
  const cli::EngineFreeBase& base = bases.front();
  const int kx = commanded(base.position[0]), ky = commanded(base.position[1]), kyaw = commanded(base.angle[0]);
  struct CarriedPoint {
    int k = -1;           // its x among the commanded speeds
    double along, across;  // its place in the base's heading frame
  };
  std::vector<CarriedPoint> carried;
  forward_kinematics(model, data, s0);
  const double psi0 = s0(base.angle[0]), xB0 = s0(base.position[0]), yB0 = s0(base.position[1]);
  for (const auto& row : gen::kClosureRows) {
    if (row.kind != gen::RowKind::point || row.axis != 0) continue;
    const auto it = std::find(kCommandedSpeeds.begin(), kCommandedSpeeds.end(), row.target);
    if (it == kCommandedSpeeds.end()) continue;
    const double dx = data.frame_positions(0, row.frame) - xB0, dy = data.frame_positions(1, row.frame) - yB0;
    carried.push_back({static_cast<int>(it - kCommandedSpeeds.begin()), std::cos(psi0) * dx + std::sin(psi0) * dy,
                       -std::sin(psi0) * dx + std::cos(psi0) * dy});
  }
  CommandVector q_start;
  for (int k = 0; k < kCommandedCount; ++k) q_start(k) = s0(kCommandedSpeeds[static_cast<std::size_t>(k)]);
  // The base's path, x' = V r cos(psi), y' = V r sin(psi), by RK4 at the control step.
  double xB = xB0, yB = yB0;
  // The yaw rate: Omega sin(2 pi t / T), a left turn and back to the start's heading over the run
  // (fixed wheels turn a machine by its legs: a turn held on would splay them to their limits).
  const double T = kDuration, nu = 2 * std::numbers::pi / T;
  const auto heading = [&](double t) { return psi0 + Omega / nu * (1 - std::cos(nu * t)); };
  const auto reference = [&](double t, CommandVector& q, CommandVector& u, CommandVector& a) {
    const double psi = heading(t), r = ramp(t), rdot = ramp_rate(t), w = Omega * std::sin(nu * t), wdot = Omega * nu * std::cos(nu * t);
    q = q_start;
    u.setZero();
    a.setZero();
    q(kx) = xB, q(ky) = yB, q(kyaw) = psi;
    u(kx) = V * r * std::cos(psi), u(ky) = V * r * std::sin(psi), u(kyaw) = w;
    a(kx) = V * rdot * std::cos(psi) - V * r * w * std::sin(psi);
    a(ky) = V * rdot * std::sin(psi) + V * r * w * std::cos(psi);
    a(kyaw) = wdot;
    for (const auto& p : carried) {
      const double dx = std::cos(psi) * p.along - std::sin(psi) * p.across, dy = std::sin(psi) * p.along + std::cos(psi) * p.across;
      q(p.k) = xB + dx;
      u(p.k) = u(kx) - w * dy;
      a(p.k) = a(kx) - wdot * dy - w * w * dx;
    }
  };
  const auto advance_base = [&](double t) {
    const auto f = [&](double tt) { return Eigen::Vector2d(V * ramp(tt) * std::cos(heading(tt)), V * ramp(tt) * std::sin(heading(tt))); };
    const Eigen::Vector2d k1 = f(t), k2 = f(t + kStep / 2), k3 = k2, k4 = f(t + kStep);
    const Eigen::Vector2d step = kStep / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    xB += step.x();
    yB += step.y();
  };

  std::string csv = "t,tracking_error_m,tracking_error_rad";
  for (int w = 0; w < kWheelCount; ++w) csv += fmt::format(",slip_{0},normal_mujoco_{0},normal_wlx_{0}", gen::kWheels[static_cast<std::size_t>(w)].name);
  csv += "\n";
  // The figures: tracking (lengths and angles apart), over the run and over its second half (the
  // speeds constant, the turn reversing); slip and normal forces after the contacts settle (the
  // first 50 ms: the machine starts with its wheels touching the ground, not yet pressed in).
  constexpr double kSettle = 0.05;
  double length_error = 0, angle_error = 0, late_length_error = 0, late_angle_error = 0;
  double worst_slip = 0, slip_sum = 0, force_diff_worst = 0, force_diff_sum = 0;
  long samples = 0;
  const double weight = model.total_mass() * (model.params().*gen::kGravity);
  const long steps = std::lround(kDuration / kStep);
  Coordinates last = s0;
  for (long n = 0; n <= steps; ++n) {
    const double t = static_cast<double>(n) * kStep;
    // MuJoCo's state as the model's coordinates: the tree's from MuJoCo, the inputs the closure
    // ties to a contact from where that contact is.
    Coordinates s = last, sdot = Coordinates::Zero();
    engine.read_state(s, sdot);
    complete_tied_inputs(model, data, s, sdot);
    if (!s.allFinite() || !sdot.allFinite()) throw Error("simulation", fmt::format("MuJoCo's state is not finite at t = {:.3f} s", t));
    last = s;  // the angles read next are unwrapped near these
    CommandVector u, q, q_ref, u_ref, a_ref;
    reference(t, q_ref, u_ref, a_ref);
    for (int k = 0; k < kCommandedCount; ++k) {
      u(k) = sdot(kCommandedSpeeds[static_cast<std::size_t>(k)]);
      q(k) = s(kCommandedSpeeds[static_cast<std::size_t>(k)]);
    }
    // The controller: computed torque on wlx's reduced equations, the model's torque split.
    const CommandVector u_dot = a_ref + kKd * (u_ref - u) + kKp * (q_ref - q);
    inverse_dynamics(model, data, s, u, u_dot, terms);
    const TorqueVector tau = distribute_torques(terms.J_beta, terms.Qstar, Weighting::model_weights());
    ContactForces predicted;
    contact_forces(model, data, s, terms, tau, predicted);
    engine.set_torques(tau);

    // Each contact as MuJoCo has it (the forces of the last step).
    const std::vector<cli::EngineContact> contacts = engine.contacts();
    double length = 0, angle = 0;
    for (int k = 0; k < kCommandedCount; ++k) {
      double& worst = gen::kCoordinateUnits[static_cast<std::size_t>(kCommandedSpeeds[static_cast<std::size_t>(k)])] == std::string_view("rad") ? angle : length;
      worst = std::max(worst, std::abs(q_ref(k) - q(k)));
    }
    length_error = std::max(length_error, length);
    angle_error = std::max(angle_error, angle);
    if (t >= kDuration / 2) {
      late_length_error = std::max(late_length_error, length);
      late_angle_error = std::max(late_angle_error, angle);
    }
    csv += fmt::format("{:.3f},{:.6e},{:.6e}", t, length, angle);
    for (int w = 0; w < kWheelCount; ++w) {
      const int contact = contact_of_wheel[static_cast<std::size_t>(w)];
      const double slip = contacts[static_cast<std::size_t>(contact)].slip, normal = contacts[static_cast<std::size_t>(contact)].normal;
      const double wlx_normal = predicted.normal(contact);
      if (t >= kSettle) {
        worst_slip = std::max(worst_slip, slip);
        slip_sum += slip;
        const double diff = std::abs(normal - wlx_normal) / weight;
        force_diff_worst = std::max(force_diff_worst, diff);
        force_diff_sum += diff;
        ++samples;
      }
      csv += fmt::format(",{:.6e},{:.6e},{:.6e}", slip, normal, wlx_normal);
    }
    csv += "\n";
    if (n < steps) {
      engine.step();
      advance_base(t);
    }
  }
  const double mean_slip = slip_sum / static_cast<double>(samples), mean_force_diff = force_diff_sum / static_cast<double>(samples);
  if (argc == 3) write_file_atomically(argv[2], csv);

  fmt::print("wlx in MuJoCo: {} drives at {} m/s and turns (yaw rate {} deg/s sin(2 pi t / {} s)) for {} s; computed torque at {} Hz\n",
             gen::kModelName, V, Omega * 180 / std::numbers::pi, T, kDuration, std::lround(1 / kStep));
  fmt::print("  tracking error: {:.2f} mm and {:.3f} deg over the run; {:.2f} mm and {:.3f} deg over its second half\n", 1e3 * length_error,
             angle_error * 180 / std::numbers::pi, 1e3 * late_length_error, late_angle_error * 180 / std::numbers::pi);
  fmt::print("  wheel slip (the material point at the contact; wlx's rolling holds it at 0): mean {:.1f} mm/s, max {:.1f} mm/s\n",
             1e3 * mean_slip, 1e3 * worst_slip);
  fmt::print("  normal force per wheel, MuJoCo against wlx's for the same torques: mean difference {:.2f}% of the weight, max {:.2f}%\n",
             100 * mean_force_diff, 100 * force_diff_worst);
  // The bounds (docs/export.md): twice the figures measured when this example was written; a
  // controller or an export that stops working misses them by far (unstable runs reach metres).
  struct Bound {
    const char* what;
    double value, limit;
  };
  bool ok = true;
  for (const Bound& b : {Bound{"tracking error (m)", length_error, 0.0015}, Bound{"tracking error (rad)", angle_error, 0.0105},
                         Bound{"mean slip (m/s)", mean_slip, 0.065}, Bound{"mean normal-force difference (of the weight)", mean_force_diff, 0.002},
                         Bound{"largest normal-force difference (of the weight)", force_diff_worst, 0.005}})
    if (!(b.value <= b.limit)) {
      fmt::print(stderr, "wlx_mujoco_cosim: {} = {:.4g}, beyond its bound {}\n", b.what, b.value, b.limit);
      ok = false;
    }
  return ok ? 0 : 1;
} catch (const Error& e) {
  std::fprintf(stderr, "wlx_mujoco_cosim: error: %s\n", e.what());
  return 2;
} catch (const std::exception& e) {
  std::fprintf(stderr, "wlx_mujoco_cosim: error: %s\n", e.what());
  return 2;
}
