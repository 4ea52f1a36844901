// The kinematic derivations: frames, the closure rows and their Jacobian, the wheels'
// non-holonomic rows, the convective terms, the bodies' kinematics and the clearance, and the list
// of every derivation (the dynamics' are in reduced_dynamics.cpp and generalized_forces.cpp).
#include "derivations_internal.hpp"

#include <fmt/format.h>

#include <cctype>
#include <stdexcept>

namespace wlx::codegen {

using namespace derivation;

namespace {

// A column-major Eigen matrix element: "(*{})(r, c)".
std::string at(int r, int c) { return fmt::format("(*{{}})({}, {})", r, c); }
std::string at(int r) { return fmt::format("(*{{}})({})", r); }
std::string at_array(int k, int r, int c) { return fmt::format("(*{{}})[{}]({}, {})", k, r, c); }

const char* kZeroArray = "for (auto& m : *{}) m.setZero();";

}  // namespace

namespace derivation {

ClosureRow closure_row(const Model& m, const ClosureCondition& c) {
  const int n = coordinate_count(m);
  ClosureRow row{0, std::vector<ex>(static_cast<std::size_t>(n), 0), 0};
  using K = ClosureCondition::Kind;
  switch (c.kind) {
    case K::PointEqualsCoordinate: {
      const Frame& f = m.frame(c.frame);
      const int k = static_cast<int>(c.axis);
      row.value = f.r[k] - m.coordinates[static_cast<std::size_t>(c.target)].q;
      const auto J = linear_jacobian(f, n);
      for (int j = 0; j < n; ++j) row.gradient[static_cast<std::size_t>(j)] = J[static_cast<std::size_t>(j)][k];
      row.gradient[static_cast<std::size_t>(c.target)] -= 1;
      row.convective = f.a_bias[k];
      break;
    }
    case K::AttachedDirectionLevel: {
      const Frame& f = m.frame(c.frame);
      const Vec3 u = f.R.col(static_cast<int>(c.axis));
      const Vec3 up = unit(Axis::Z);
      row.value = u[2];
      row.gradient = attached_direction_gradient(f, u, up, n);
      row.convective = attached_direction_convective(f, u, up);
      break;
    }
    case K::CoordinateSum:
      for (int k : c.coordinates) {
        row.value += m.coordinates[static_cast<std::size_t>(k)].q;
        row.gradient[static_cast<std::size_t>(k)] = 1;
      }
      break;
  }
  return row;
}

WheelRow wheel_row(const Model& m, const NonholonomicWheel& wheel) {
  const int n = coordinate_count(m);
  const Frame& f = m.frame(wheel.contact);
  const Vec3 lateral = f.R.col(static_cast<int>(wheel.lateral));
  const Vec3 forward = f.R.col(static_cast<int>(wheel.forward));
  const ex radius = m.parameter(wheel.radius).symbol;
  const auto J = linear_jacobian(f, n);
  WheelRow row;
  for (int j = 0; j < n; ++j) {
    row.C.push_back(dot(lateral, J[static_cast<std::size_t>(j)]));
    row.spin.push_back(dot(forward, J[static_cast<std::size_t>(j)]) / radius);
  }
  // d/dt(n . v) with zero accelerations: n turns with the contact frame.
  row.convective = dot(cross(f.omega, lateral), f.v) + dot(lateral, f.a_bias);
  return row;
}

}  // namespace derivation

ex closure_value(const Model& m, const ClosureCondition& c) { return closure_row(m, c).value; }

namespace {

// Each coordinate's joint as a twist in K0 (spatial_axis), in Pinocchio's world convention (its
// computeJointJacobians): column j = [v; omega], the motion a unit rate of coordinate j gives every
// body it moves: omega the angular velocity, v the velocity of the body's point at K0's origin. A
// body point p's velocity is then v + omega x p, summed over the joints between K0 and it: the
// bodies' Jacobians follow from these 6 numbers per joint instead of 3 per body and joint. The
// joints come from the chains of the frames and bodies; a coordinate no chain holds (the wheels'
// ground heights) has a zero column. A coordinate drives one joint (the model file's parser refuses
// a second, "already drives a joint"), which every chain through it records alike: two different
// records are wlx-gen's own error.
OutputSpec joint_twists(const Model& m) {
  OutputSpec J{"J", "JointJacobian", "the twists, one column per coordinate: rows 0-2 v, rows 3-5 omega", kZeroMatrix, {}};
  std::vector<const JointRecord*> joint(m.coordinates.size(), nullptr);
  const auto add = [&](const Frame& f) {
    for (const JointRecord& r : f.joints) {
      const JointRecord*& known = joint.at(static_cast<std::size_t>(r.coordinate));
      if (known == nullptr) known = &r;
      else if (!same_joint(*known, r))
        throw std::logic_error(fmt::format("joint_jacobian: coordinate {} has two different joint records",
                                           m.coordinates[static_cast<std::size_t>(r.coordinate)].name));
    }
  };
  for (const NamedFrame& f : m.frames) add(f.frame);
  for (const Body& b : m.bodies) add(b.com_frame);
  for (int j = 0; j < coordinate_count(m); ++j) {
    const JointRecord* r = joint[static_cast<std::size_t>(j)];
    if (r == nullptr) continue;
    const std::array<ex, 6> S = spatial_axis(*r);  // (omega; v)
    for (int i = 0; i < 3; ++i) {
      J.elements.emplace_back(at(i, j), S[static_cast<std::size_t>(i + 3)]);
      if (r->revolute) J.elements.emplace_back(at(3 + i, j), S[static_cast<std::size_t>(i)]);
    }
  }
  return J;
}

}  // namespace

FunctionSpec derive_joint_jacobian(const Model& m) {
  FunctionSpec fn{"joint_jacobian", "joint_jacobian.hpp",
                  "Each coordinate's joint as a twist in K0, 6 x n: column j is [v; omega] for a unit rate of "
                  "coordinate j, v the velocity of the point at K0's origin (Pinocchio's computeJointJacobians); a "
                  "point p moved by the joints of coordinates J moves at the sum over j in J of (v_j + omega_j x p) s'_j.",
                  false, {}};
  fn.outputs = {joint_twists(m)};
  return fn;
}

FunctionSpec derive_kinematics(const Model& m) {
  FunctionSpec fn{"kinematics", "kinematics.hpp",
                  "Forward kinematics: position and orientation in K0 of every frame of "
                  "interest (index with wlx::gen::frame::...).",
                  false, {}};
  OutputSpec pos{"positions", "FramePositions", "frame origins in K0, one column per frame", "", {}};
  OutputSpec rot{"rotations", "FrameRotations", "frame orientations in K0 (columns: frame axes)", "", {}};
  for (int k = 0; k < static_cast<int>(m.frames.size()); ++k) {
    const Frame& f = m.frames[static_cast<std::size_t>(k)].frame;
    for (int i = 0; i < 3; ++i) pos.elements.emplace_back(at(i, k), f.r[i]);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) rot.elements.emplace_back(at_array(k, i, j), f.R(i, j));
  }
  fn.outputs = {pos, rot};
  return fn;
}

FunctionSpec derive_closure(const Model& m) {
  FunctionSpec fn{"closure", "closure.hpp",
                  "Loop closure: Phi(s) and its Jacobian dPhi/ds.", false, {}};
  OutputSpec phi{"Phi", "ClosureVector", "closure residuals, zero on the constraint manifold", "", {}};
  OutputSpec jac{"dPhi_ds", "ClosureJacobian", fmt::format("dPhi/ds, {} x {}", m.closure.size(), coordinate_count(m)),
                 kZeroMatrix, {}};
  for (int i = 0; i < static_cast<int>(m.closure.size()); ++i) {
    const ClosureRow row = closure_row(m, m.closure[static_cast<std::size_t>(i)]);
    phi.elements.emplace_back(at(i), row.value);
    for (int j = 0; j < coordinate_count(m); ++j)
      jac.elements.emplace_back(at(i, j), row.gradient[static_cast<std::size_t>(j)]);
  }
  fn.outputs = {phi, jac};
  return fn;
}

FunctionSpec derive_nonholonomic(const Model& m) {
  FunctionSpec fn{"nonholonomic", "nonholonomic.hpp",
                  "Non-holonomic wheels: rows C(s) with v_W . n_W = C(s) s', and "
                  "the rolling rows with spin rate = (v_W . e_x,W) / w = spin(s) s'.",
                  false, {}};
  OutputSpec C{"C", "WheelRows", "cornering constraint rows, one per wheel", kZeroMatrix, {}};
  OutputSpec spin{"spin", "WheelRows", "wheel spin-rate rows, one per wheel", kZeroMatrix, {}};
  for (int i = 0; i < static_cast<int>(m.wheels.size()); ++i) {
    const WheelRow row = wheel_row(m, m.wheels[static_cast<std::size_t>(i)]);
    for (int j = 0; j < coordinate_count(m); ++j) {
      C.elements.emplace_back(at(i, j), row.C[static_cast<std::size_t>(j)]);
      spin.elements.emplace_back(at(i, j), row.spin[static_cast<std::size_t>(j)]);
    }
  }
  // A wheel's drive turns it against its hub: its rate is the spin relative to the hub. The
  // wheel's material point at the contact has zero velocity, v_hub + (w_hub + drive a) x rho = 0
  // with rho = -r u the rim offset; along the forward direction t (a x u = t, u x t = a) this gives
  // drive = (v_hub . t) / r - w_hub . a. Rows only for the wheels the dynamics section drives.
  OutputSpec drive{"drive", "WheelRows",
                   "wheel drive-rate rows: the spin relative to the hub, drive rate = drive(s) s' (zero rows for a "
                   "wheel without a drive)",
                   kZeroMatrix, {}};
  if (m.dynamics)
    for (const Actuator& a : m.dynamics->actuated) {
      if (a.wheel < 0) continue;
      const NonholonomicWheel& wheel = m.wheels[static_cast<std::size_t>(a.wheel)];
      const Frame& hub = m.frame(wheel.hub);
      const Vec3 t = m.frame(wheel.contact).R.col(static_cast<int>(wheel.forward));
      const Vec3 axle = hub.R.col(static_cast<int>(wheel.axle));
      const ex radius = m.parameter(wheel.radius).symbol;
      const auto Jv = linear_jacobian(hub, coordinate_count(m));
      const auto Jw = angular_jacobian(hub, coordinate_count(m));
      for (int j = 0; j < coordinate_count(m); ++j)
        drive.elements.emplace_back(at(a.wheel, j), dot(t, Jv[static_cast<std::size_t>(j)]) / radius -
                                                        dot(axle, Jw[static_cast<std::size_t>(j)]));
    }
  fn.outputs = {C, spin, drive};
  return fn;
}

FunctionSpec derive_convective(const Model& m) {
  FunctionSpec fn{"convective", "convective.hpp",
                  "Convective terms: (d/dt dPhi/ds) s' and (d/dt C) s', i.e. the "
                  "second time derivatives of Phi and of v_W . n_W with all accelerations zero.",
                  true, {}};
  OutputSpec phi{"dPhi_ds_dot_sdot", "ClosureVector", "(d/dt dPhi/ds) s'", "", {}};
  OutputSpec C{"C_dot_sdot", "WheelVector", "(d/dt C) s', one per wheel (kWheels' order)", "", {}};
  for (int i = 0; i < static_cast<int>(m.closure.size()); ++i)
    phi.elements.emplace_back(at(i), closure_row(m, m.closure[static_cast<std::size_t>(i)]).convective);
  for (int i = 0; i < static_cast<int>(m.wheels.size()); ++i)
    C.elements.emplace_back(at(i), wheel_row(m, m.wheels[static_cast<std::size_t>(i)]).convective);
  fn.outputs = {phi, C};
  return fn;
}

FunctionSpec derive_bodies(const Model& m) {
  FunctionSpec fn{"bodies", "bodies.hpp",
                  "Body kinematics for the dynamics: per body (index with "
                  "wlx::gen::body::...) the CoM position and orientation in K0, the Jacobians of the CoM "
                  "velocity and of the angular velocity (both in K0), and their convective terms Jdot s'.",
                  true, {}};
  OutputSpec com{"com", "BodyVectors", "CoM positions in K0, one column per body", "", {}};
  OutputSpec rot{"rotations", "BodyRotations", "body orientations in K0", "", {}};
  OutputSpec Jv{"Jv", "BodyJacobians", "CoM velocity Jacobians, v = Jv s'", kZeroArray, {}};
  OutputSpec Jw{"Jw", "BodyJacobians", "angular velocity Jacobians, omega = Jw s'", kZeroArray, {}};
  OutputSpec Jv_dot{"Jv_dot_sdot", "BodyVectors", "CoM convective accelerations (d/dt Jv) s'", "", {}};
  OutputSpec Jw_dot{"Jw_dot_sdot", "BodyVectors", "convective angular accelerations (d/dt Jw) s'", "", {}};
  const int n = coordinate_count(m);
  for (int k = 0; k < static_cast<int>(m.bodies.size()); ++k) {
    const Frame& f = m.bodies[static_cast<std::size_t>(k)].com_frame;
    const auto Lv = linear_jacobian(f, n);
    const auto Lw = angular_jacobian(f, n);
    for (int i = 0; i < 3; ++i) {
      com.elements.emplace_back(at(i, k), f.r[i]);
      for (int j = 0; j < 3; ++j) rot.elements.emplace_back(at_array(k, i, j), f.R(i, j));
      for (int j = 0; j < n; ++j) {
        Jv.elements.emplace_back(at_array(k, i, j), Lv[static_cast<std::size_t>(j)][i]);
        Jw.elements.emplace_back(at_array(k, i, j), Lw[static_cast<std::size_t>(j)][i]);
      }
      Jv_dot.elements.emplace_back(at(i, k), f.a_bias[i]);
      Jw_dot.elements.emplace_back(at(i, k), f.alpha_bias[i]);
    }
  }
  fn.outputs = {com, rot, Jv, Jw, Jv_dot, Jw_dot};
  return fn;
}

FunctionSpec derive_kinematic_update(const Model& m) {
  FunctionSpec fn{"kinematic_update", "kinematic_update.hpp",
                  "The per-step kinematic update in one pass: frame positions and orientations, Phi, dPhi/ds and "
                  "the non-holonomic rows C(s) (the outputs of kinematics, closure and nonholonomic, sharing "
                  "their common subexpressions).",
                  false, {}};
  const FunctionSpec k = derive_kinematics(m), c = derive_closure(m), n = derive_nonholonomic(m);
  fn.outputs = {k.outputs[0], k.outputs[1], c.outputs[0], c.outputs[1], n.outputs[0]};
  return fn;
}

std::vector<std::string> identifiers(const std::string& code) {
  const auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  std::vector<std::string> out;
  for (std::size_t at = 0; at < code.size();) {
    if (!word(code[at])) {
      ++at;
      continue;
    }
    std::size_t end = at;
    while (end < code.size() && word(code[end])) ++end;
    out.push_back(code.substr(at, end - at));
    at = end;
  }
  return out;
}

FunctionSpec derive_dynamics_update(const Model& m) {
  FunctionSpec fn{"dynamics_update", "dynamics_update.hpp",
                  "The position-level part of an inverse-dynamics step in one pass: dPhi/ds and the "
                  "non-holonomic rows C(s), which give the rate basis T (the outputs of closure and "
                  "nonholonomic that an inverse-dynamics step needs, sharing their common subexpressions).",
                  false, {}};
  const FunctionSpec c = derive_closure(m), n = derive_nonholonomic(m);
  fn.outputs = {c.outputs[1], n.outputs[0], n.outputs[2]};
  return fn;
}

FunctionSpec derive_clearance(const Model& m) {
  FunctionSpec fn{"clearance", "clearance.hpp",
                  "Ground clearance: the height above z = 0 of the lowest corner of the box attached to frame " +
                      m.clearance->frame + " (centred on its origin, along its axes).",
                  false, {}};
  OutputSpec low{"lowest", "double", "height of the lowest corner above the ground, m", "", {}};
  const Frame& f = m.frame(m.clearance->frame);
  // Corner offsets +-size/2 along each axis: the lowest corner takes the sign that points down.
  ex depth = 0;
  for (int j = 0; j < 3; ++j) depth += GiNaC::abs(f.R(2, j)) * m.clearance->size[static_cast<std::size_t>(j)] / 2;
  low.elements.emplace_back("*{}", f.r[2] - depth);
  // The box itself (its frame is kClearanceFrame, structure.hpp): what a drawing of it needs.
  OutputSpec half{"half_extents", "Vector3", "the box's half sizes along the frame's x, y, z axes, m (parameters only)", "", {}};
  for (int j = 0; j < 3; ++j)
    half.elements.emplace_back(at(j), m.clearance->size[static_cast<std::size_t>(j)] / 2);
  fn.outputs = {low, half};
  return fn;
}

std::vector<Derivation> derivations(const Model& m) {
  std::vector<Derivation> all{{"kinematics", derive_kinematics},
                              {"closure", derive_closure},
                              {"nonholonomic", derive_nonholonomic},
                              {"convective", derive_convective},
                              {"bodies", derive_bodies},
                              {"joint_jacobian", derive_joint_jacobian},
                              {"kinematic_update", derive_kinematic_update},
                              {"dynamics_update", derive_dynamics_update}};
  if (m.dynamics) {
    all.push_back({"reduced_dynamics", derive_reduced_dynamics});
    all.push_back({"generalized_forces", derive_generalized_forces});
  }
  if (m.clearance) all.push_back({"clearance", derive_clearance});
  return all;
}

std::vector<FunctionSpec> derive_all(const Model& m) {
  std::vector<FunctionSpec> out;
  for (const auto& d : derivations(m)) out.push_back(d.derive(m));
  return out;
}

}  // namespace wlx::codegen
