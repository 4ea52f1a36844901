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
#include "mjcf_export.hpp"
#include "mujoco_peer.hpp"

#include <wlx/atomic_file.hpp>
#include <wlx/contacts.hpp>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <mujoco/mujoco.h>

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
namespace peer = wlx::mujoco_peer;

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

int coordinate(const std::string& name) {
  const int c = peer::coordinate_index(name);
  if (c < 0) throw Error("coordinate", fmt::format("the model has no coordinate '{}'", name));
  return c;
}

// wlx's coordinates and rates of MuJoCo's state (the steps 1 of the header).
struct Measured {
  Coordinates s = Coordinates::Zero(), sdot = Coordinates::Zero();
};
Measured measure(const Model& model, Data& data, const mjModel* m, const mjData* d, const std::vector<peer::FreeBase>& bases) {
  Measured out;
  for (int j = 0; j < m->njnt; ++j) {
    const int qa = m->jnt_qposadr[j];
    if (m->jnt_type[j] == mjJNT_FREE) {
      const peer::FreeBase& b = bases.front();
      if (b.axis != std::array<int, 3>{2, 1, 0}) throw Error("frames", "this example reads a floating base of Z-Y-X angles only");
      for (int i = 0; i < 3; ++i) out.s(b.position[static_cast<std::size_t>(i)]) = d->qpos[qa + i];
      const Eigen::Matrix3d R = Eigen::Quaterniond(d->qpos[qa + 3], d->qpos[qa + 4], d->qpos[qa + 5], d->qpos[qa + 6]).toRotationMatrix();
      out.s(b.angle[0]) = std::atan2(R(1, 0), R(0, 0));
      out.s(b.angle[1]) = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
      out.s(b.angle[2]) = std::atan2(R(2, 1), R(2, 2));
      continue;
    }
    const int c = peer::coordinate_index(mj_id2name(m, mjOBJ_JOINT, j));
    if (c >= 0) out.s(c) = d->qpos[qa];
  }
  // The inputs the closure ties to a frame: where that frame is.
  forward_kinematics(model, data, out.s);
  for (const auto& row : gen::kClosureRows)
    if (row.kind == gen::RowKind::point) out.s(row.target) = data.frame_positions(row.axis, row.frame);
  // Rates: qvel = G s' on the tree's coordinates (least squares: the wheels' spins are no
  // coordinate), then each tied input's rate from its row, 0 = dPhi/ds s'.
  const peer::Mapping map = peer::map_state(m, bases, out.s, Coordinates::Zero());
  const Eigen::Map<const Eigen::VectorXd> qvel(d->qvel, m->nv);
  const Eigen::VectorXd tree_rates = map.G.colPivHouseholderQr().solve(qvel);
  out.sdot = tree_rates;
  closure(model, data, out.s, true);
  for (int r = 0; r < static_cast<int>(gen::kClosureRows.size()); ++r) {
    const auto& row = gen::kClosureRows[static_cast<std::size_t>(r)];
    if (row.kind != gen::RowKind::point) continue;
    double rate = 0;
    for (int k = 0; k < kCoordinateCount; ++k)
      if (k != row.target) rate += data.dPhi_ds(r, k) * out.sdot(k);
    out.sdot(row.target) = rate;  // dPhi/ds of the input itself is -1
  }
  return out;
}

// Each wheel's MuJoCo body (spin_<wheel>), geom (its contact frame's name) and radius.
struct Wheel {
  int body = -1, geom = -1;
  double radius = 0;
};

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
  const auto mj = peer::load(cli::mjcf_of_description(description).xml);
  mjModel* m = mj.get();
  const std::unique_ptr<mjData, peer::MjDataDeleter> data_mj(mj_makeData(m));
  mjData* d = data_mj.get();
  const std::vector<peer::FreeBase> bases = peer::free_bases(description);
  if (bases.size() != 1) throw Error("frames", "this example drives a machine with one floating base");

  const Model model;
  Data data;
  DynamicsTerms terms;

  // The start: the nominal pose, its limbs solved in closed form on the model's branches (within
  // the joints' ranges, which MuJoCo's joint limits enforce), at rest.
  Coordinates s0 = nominal_inputs();
  solve_ik_closed_form(model, s0);
  const peer::Mapping start = peer::map_state(m, bases, s0, Coordinates::Zero());
  for (int i = 0; i < m->nq; ++i) d->qpos[i] = start.qpos(i);
  mj_forward(m, d);

  std::vector<int> motor(kActuatedCount);
  for (int k = 0; k < kActuatedCount; ++k) {
    motor[static_cast<std::size_t>(k)] = mj_name2id(m, mjOBJ_ACTUATOR, std::string(kActuatorNames[static_cast<std::size_t>(k)]).c_str());
    if (motor[static_cast<std::size_t>(k)] < 0) throw Error("actuators", fmt::format("MuJoCo has no motor {}", kActuatorNames[static_cast<std::size_t>(k)]));
  }
  std::vector<Wheel> wheels;
  for (int w = 0; w < kWheelCount; ++w) {
    const std::string name(gen::kWheels[static_cast<std::size_t>(w)].name);
    Wheel wheel;
    wheel.body = mj_name2id(m, mjOBJ_BODY, ("spin_" + name).c_str());
    wheel.geom = mj_name2id(m, mjOBJ_GEOM, std::string(gen::kFrameNames[static_cast<std::size_t>(gen::kWheels[static_cast<std::size_t>(w)].contact_frame)]).c_str());
    if (wheel.body < 0 || wheel.geom < 0) throw Error("wheels", fmt::format("wheel {} has no spinning body in MuJoCo (a wheel on a hub)", name));
    wheel.radius = m->geom_size[3 * wheel.geom];
    wheels.push_back(wheel);
  }
  // The contact of each wheel among wlx's contacts.
  std::vector<int> contact_of_wheel(kWheelCount, -1);
  for (int c = 0; c < kContactCount; ++c)
    if (gen::kContacts[static_cast<std::size_t>(c)].wheel >= 0) contact_of_wheel[static_cast<std::size_t>(gen::kContacts[static_cast<std::size_t>(c)].wheel)] = c;

  // The reference: the base's x, y and yaw, and each wheel's contact point carried with the base
  // (its x commanded, its y following by rolling). Every other commanded coordinate stays.
  const double V = kSpeed, Omega = kYawRate;
  const auto commanded = [&](const std::string& name) {
    const int c = coordinate(name);
    const auto it = std::find(kCommandedSpeeds.begin(), kCommandedSpeeds.end(), c);
    if (it == kCommandedSpeeds.end()) throw Error("speeds", fmt::format("{} is no commanded speed of the model", name));
    return static_cast<int>(it - kCommandedSpeeds.begin());
  };
  const peer::FreeBase& base = bases.front();
  const int kx = commanded(std::string(gen::kCoordinateNames[static_cast<std::size_t>(base.position[0])])),
            ky = commanded(std::string(gen::kCoordinateNames[static_cast<std::size_t>(base.position[1])])),
            kyaw = commanded(std::string(gen::kCoordinateNames[static_cast<std::size_t>(base.angle[0])]));
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
  for (long n = 0; n <= steps; ++n) {
    const double t = static_cast<double>(n) * kStep;
    const Measured x = measure(model, data, m, d, bases);
    if (!x.s.allFinite() || !x.sdot.allFinite()) throw Error("simulation", fmt::format("MuJoCo's state is not finite at t = {:.3f} s", t));
    CommandVector u, q, q_ref, u_ref, a_ref;
    reference(t, q_ref, u_ref, a_ref);
    for (int k = 0; k < kCommandedCount; ++k) {
      u(k) = x.sdot(kCommandedSpeeds[static_cast<std::size_t>(k)]);
      q(k) = x.s(kCommandedSpeeds[static_cast<std::size_t>(k)]);
    }
    // The controller: computed torque on wlx's reduced equations, the model's torque split.
    const CommandVector u_dot = a_ref + kKd * (u_ref - u) + kKp * (q_ref - q);
    inverse_dynamics(model, data, x.s, u, u_dot, terms);
    const TorqueVector tau = distribute_torques(terms.J_beta, terms.Qstar, Weighting::model_weights());
    ContactForces predicted;
    contact_forces(model, data, x.s, terms, tau, predicted);
    for (int k = 0; k < kActuatedCount; ++k) d->ctrl[motor[static_cast<std::size_t>(k)]] = tau(k);

    // MuJoCo's normal force on each wheel (its contacts on the wheel's geom, from the last step).
    std::vector<double> normal(kWheelCount, 0.0);
    for (int c = 0; c < d->ncon; ++c) {
      const mjContact& con = d->contact[c];
      for (int w = 0; w < kWheelCount; ++w)
        if (con.geom1 == wheels[static_cast<std::size_t>(w)].geom || con.geom2 == wheels[static_cast<std::size_t>(w)].geom) {
          mjtNum f[6];
          mj_contactForce(m, d, c, f);
          normal[static_cast<std::size_t>(w)] += f[0];
        }
    }
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
      const Wheel& wheel = wheels[static_cast<std::size_t>(w)];
      // The wheel's material point at the contact: its centre's velocity and the wheel's angular
      // velocity (world axes, at the spinning body's origin, the centre), the point a radius below.
      mjtNum v[6];
      mj_objectVelocity(m, d, mjOBJ_XBODY, wheel.body, v, 0);
      const Eigen::Vector3d omega(v[0], v[1], v[2]), centre_velocity(v[3], v[4], v[5]);
      const Eigen::Vector3d material = centre_velocity + omega.cross(Eigen::Vector3d(0, 0, -wheel.radius));
      const double slip = std::hypot(material.x(), material.y());
      const int contact = contact_of_wheel[static_cast<std::size_t>(w)];
      const double wlx_normal = contact >= 0 ? predicted.normal(contact) : 0.0;
      if (t >= kSettle) {
        worst_slip = std::max(worst_slip, slip);
        slip_sum += slip;
        const double diff = std::abs(normal[static_cast<std::size_t>(w)] - wlx_normal) / weight;
        force_diff_worst = std::max(force_diff_worst, diff);
        force_diff_sum += diff;
        ++samples;
      }
      csv += fmt::format(",{:.6e},{:.6e},{:.6e}", slip, normal[static_cast<std::size_t>(w)], wlx_normal);
    }
    csv += "\n";
    if (n < steps) {
      mj_step(m, d);
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
