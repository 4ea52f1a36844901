// The steering leg pattern (one of the closed-form IK's patterns, ik_patterns.cpp lists the others):
// a leg whose first revolute joint swings the plane of three parallel revolute joints, which one
// sum row holds at a constant total turn, and after them any input-driven joints (a steering axle,
// a camber joint) and the placed point: a wheel's derived contact point, or a frame's origin.
//
// The sum row fixes the third parallel joint, q4 = -(q2 + q3 + the row's inputs), so the total turn
// about the parallel axis A from the second joint on, Phi = theta2 + theta3 + theta4 plus the fixed
// turns between them, is known from the inputs: everything after the fourth joint keeps a known
// pose relative to the frame after the first joint, E. In E's axes the placed point is
//   p1 + R1 (R_A(theta2) p2 + R_A(theta2 + beta + theta3) p3 + R_A(Phi) g) + k,
// with g the point from the fourth joint (through the inputs' joints) and k the contact point's
// offset from the hub (zero for a frame's origin). Along the leg plane's normal n = R1 e_A this is
// a constant Y (rotations about A keep A components), so the target fixes the first joint:
// (R_1(q1) n) . d = Y, two roots. What is left is a planar two-link leg: the distance of
// w = R1^T (d_E - p1 - k) - R_A(Phi) g from the second joint fixes the third (two roots), one
// rotation about A the second, and the sum row the fourth. Four branches.
//
// The contact offset k = o a - r u (the rim point nearest the ground: u = (z - a_z a) / |z - a_z a|,
// a the axle and z world up, both in E's axes) is known before the first joint is solved only when
// world up is fixed in E, that is when the first joint's axis is vertical whatever the inputs.
// When the base tilts that axis, u turns with the first joint's angle, out of the leg's plane as
// soon as the inputs steer the axle, and the equation for q1 is no longer a sinusoid (squared
// out, a polynomial of degree eight): the pattern refuses a wheel there and says why.
#include "ik_internal.hpp"

#include <fmt/format.h>

#include <cmath>
#include <set>
#include <string>

namespace wlx::codegen::ik {

namespace {

constexpr const char* kPattern = "steering leg";

// The limb's rows: three point rows on one frame and one sum row.
struct SteeringRows {
  std::string frame;                      // the frame the point rows place
  std::array<int, 3> target{-1, -1, -1};  // the inputs its x, y and z equal
  const ClosureCondition* sum = nullptr;
};

SteeringRows steering_rows(const Model& m, const Limb& limb) {
  SteeringRows rows;
  std::vector<std::string> names;
  int points = 0, sums = 0;
  for (int r : limb.rows) {
    const ClosureCondition& c = m.closure[static_cast<std::size_t>(r)];
    names.push_back(c.name);
    if (c.kind == ClosureCondition::Kind::CoordinateSum) {
      ++sums;
      rows.sum = &c;
    } else if (c.kind == ClosureCondition::Kind::PointEqualsCoordinate) {
      ++points;
      add_point_row(c, kPattern, rows.frame, rows.target);
    }
  }
  if (points != 3 || sums != 1 || limb.rows.size() != 4)
    throw Unsolvable{
        fmt::format("{} solves three point rows (x, y and z of one frame) and one sum row; this limb has {}: {}",
                    kPattern, limb.rows.size(), fmt::join(names, ", "))};
  return rows;
}

// Four dependent revolute joints, then only inputs' joints.
void require_four_joints(const Model& m, const CanonicalChain& c, const std::string& point) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  if (c.joints.size() < 4)
    throw Unsolvable{
        fmt::format("{}: {} joints drive {} from the first dependent one on; the pattern needs four dependent revolute "
                    "joints (then any inputs' joints)",
                    kPattern, c.joints.size(), point)};
  for (std::size_t k = 0; k < c.joints.size(); ++k) {
    const ChainStep& j = c.joints[k];
    const bool input = j.coordinate < m.input_count;
    if (k < 4 && input)
      throw Unsolvable{
          fmt::format("{}: input {} moves the chain between the first dependent joint {} and the fourth; the "
                      "pattern needs the inputs' joints before the first dependent joint or after the fourth",
                      kPattern, name(j.coordinate), name(c.joints[0].coordinate))};
    if (k < 4 && j.kind == ChainStep::Kind::Slide)
      throw Unsolvable{fmt::format("{}: {} is prismatic", kPattern, name(j.coordinate))};
    if (k >= 4 && !input)
      throw Unsolvable{
          fmt::format("{}: the dependent joint {} follows the fourth dependent joint {}; the pattern solves four",
                      kPattern, name(j.coordinate), name(c.joints[3].coordinate))};
  }
}

// A steering leg's geometry, its preconditions checked.
struct SteeringLeg {
  SteeringRows rows;
  const NonholonomicWheel* wheel = nullptr;  // whose contact point rows.frame is; nullptr: a frame's origin
  std::string point;                         // what the joints place: the wheel's hub, or rows.frame
  CanonicalChain chain;                      // point's
  ex coupled_value;                          // the fourth joint's value by the sum row
  Mat3 R1, R2;                               // the fixed turns after the first joint, and between the second and third
  Vec3 p1, p2, p3;                           // the fixed offsets after the first three joints
  Mat3 total_turn;                           // R_A(Phi), known from the inputs
  Vec3 tail;                                 // the point from the fourth joint, in its axes
  Mat3 tail_turns;                           // the point's frame's axes in the fourth joint's
  Vec3 up;                                   // world up in E's axes (a wheel: fixed by the precondition)
};

// The parallel joints (second to fourth): one axis, turns between them only about it, one sign.
void require_parallel(const Model& m, const CanonicalChain& c) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const ChainStep &j2 = c.joints[1], &j3 = c.joints[2], &j4 = c.joints[3];
  const std::string n2 = name(j2.coordinate), n3 = name(j3.coordinate), n4 = name(j4.coordinate);
  bool parallel = j3.axis == j2.axis && j4.axis == j2.axis;
  for (std::size_t k : {2, 3})
    for (const Rot& t : c.fixed[k].turns) parallel = parallel && t.axis == j2.axis;
  if (!parallel)
    throw Unsolvable{fmt::format(
        "{}: the axes of {}, {} and {} are not parallel ({} between the first two, {} between the last two); "
        "the pattern needs three joints about one axis, with turns between them only about that axis",
        kPattern, n2, n3, n4, describe(c.fixed[2]), describe(c.fixed[3]))};
  if (j3.sign != j2.sign || j4.sign != j2.sign)
    throw Unsolvable{
        fmt::format("{}: {}, {} and {} turn about opposite directions of their axis, so their sum row does not "
                    "fix their total turn",
                    kPattern, n2, n3, n4)};
}

// The sum row holds the three parallel joints (and any inputs): the fourth joint's value.
ex sum_row_value(const Model& m, const CanonicalChain& c, const ClosureCondition& sum) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  std::set<int> dependent;
  ex others = 0;
  for (int k : sum.coordinates) {
    if (k >= m.input_count) dependent.insert(k);
    if (k != c.joints[3].coordinate) others += m.coordinates[static_cast<std::size_t>(k)].q;
  }
  const std::set<int> parallel = {c.joints[1].coordinate, c.joints[2].coordinate, c.joints[3].coordinate};
  if (dependent != parallel)
    throw Unsolvable{fmt::format(
        "{}: the sum row {} holds other dependent joints than the three parallel ones ({}, {}, {})", kPattern, sum.name,
        name(c.joints[1].coordinate), name(c.joints[2].coordinate), name(c.joints[3].coordinate))};
  return (-others).expand();
}

// A wheel: world up must stay along the first joint's axis (docs at the top of the file).
Vec3 world_up(const Model& m, const CanonicalChain& c, const SteeringLeg& leg) {
  const Frame base = base_frame(m, c);
  const Vec3 up(base.R(2, 0), base.R(2, 1), base.R(2, 2));  // R_B^T e_z; the first joint turns about it
  if (!leg.wheel || identically_zero(cross(up, unit(c.joints[0].axis)))) return up;
  std::vector<std::string> tilting;
  for (int k = 0; k < m.input_count; ++k)
    for (int i = 0; i < 3; ++i)
      if (up[i].has(m.coordinates[static_cast<std::size_t>(k)].q)) {
        tilting.push_back(m.coordinates[static_cast<std::size_t>(k)].name);
        break;
      }
  const std::string n1 = m.coordinates[static_cast<std::size_t>(c.joints[0].coordinate)].name;
  throw Unsolvable{
      fmt::format("{}: the axis of {} is not vertical whatever the inputs ({} tilt it); with the axle steered out of "
                  "the leg's plane the rim point nearest the ground then moves with {}'s angle in a way no closed form "
                  "here solves: for a wheel the pattern needs that axis vertical (a frame's origin may tilt)",
                  kPattern, n1,
                  tilting.empty() ? std::string("the fixed turns") : fmt::format("{}", fmt::join(tilting, ", ")), n1)};
}

SteeringLeg steering_leg(const Model& m, const Limb& limb) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  SteeringLeg leg;
  leg.rows = steering_rows(m, limb);
  leg.wheel = wheel_of_contact(m, leg.rows.frame);
  leg.point = leg.wheel ? leg.wheel->hub : leg.rows.frame;
  const CanonicalChain c = leg.chain = canonical_chain(m, full_chain(m, leg.point));
  require_four_joints(m, c, leg.point);
  require_parallel(m, c);
  leg.coupled_value = sum_row_value(m, c, *leg.rows.sum);
  const ChainStep &j1 = c.joints[0], &j2 = c.joints[1];
  const Axis A = j2.axis;
  leg.R1 = product(c.fixed[1].turns);
  leg.R2 = product(c.fixed[2].turns);
  leg.p1 = c.fixed[1].offset;
  leg.p2 = c.fixed[2].offset;
  leg.p3 = c.fixed[3].offset;
  if (parallel_at_defaults(m, unit(j1.axis), leg.R1 * unit(A)))
    throw Unsolvable{fmt::format(
        "{}: the axis of {} is parallel to those of {}, {} and {} (a planar leg: {} cannot move the leg's plane)",
        kPattern, name(j1.coordinate), name(j2.coordinate), name(c.joints[2].coordinate), name(c.joints[3].coordinate),
        name(j1.coordinate))};
  // Phi: the parallel joints' turns (sign (q2 + q3 + q4), the sum row's value) and the fixed turns between them.
  ex phi = j2.sign * (m.coordinates[static_cast<std::size_t>(j2.coordinate)].q +
                      m.coordinates[static_cast<std::size_t>(c.joints[2].coordinate)].q + leg.coupled_value);
  for (std::size_t k : {2, 3})
    for (const Rot& t : c.fixed[k].turns) phi += t.angle;
  phi = phi.expand();
  if (phi.has(m.coordinates[static_cast<std::size_t>(j2.coordinate)].q))
    throw std::logic_error(
        "wlx-gen: the steering leg's total turn depends on a parallel joint");  // the sum row excludes it
  leg.total_turn = rot(A, phi);
  // The point's pose from the fourth joint: its fixed transform, then the inputs' joints and theirs.
  Frame tail = Frame::ground();
  for (std::size_t k = 4; k <= c.joints.size(); ++k) {
    if (k > 4) tail = apply(m, tail, c.joints[k - 1]);
    const Rigid& r = c.fixed[k];
    if (!identically_zero(r.offset)) tail = tail.translated(r.offset);
    for (const Rot& t : r.turns) tail = tail.turned(t.axis, t.angle);
  }
  leg.tail = expanded(tail.r);
  leg.tail_turns = tail.R;
  leg.up = world_up(m, c, leg);
  return leg;
}

// The solve's report line, documentation, branch bits and failure messages.
void describe_steering_leg(const Model& m, const SteeringLeg& leg, Solve& solve) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const CanonicalChain& c = leg.chain;
  const std::string n1 = name(c.joints[0].coordinate), n2 = name(c.joints[1].coordinate),
                    n3 = name(c.joints[2].coordinate), n4 = name(c.joints[3].coordinate);
  const std::array<int, 3>& target = leg.rows.target;
  const std::string what =
      leg.wheel ? "the contact point of wheel " + leg.wheel->name + " (" + leg.rows.frame + ")" : leg.rows.frame;
  std::vector<std::string> inputs;
  for (std::size_t k = 4; k < c.joints.size(); ++k) inputs.push_back(name(c.joints[k].coordinate));
  const std::string after = inputs.empty() ? "" : fmt::format("; inputs after it: {}", fmt::join(inputs, ", "));
  solve.summary = fmt::format(
      "{}: {} at (x, y, z) = ({}, {}, {}) by {} ({}), then {} and {} (parallel, about {}), {} by the sum row {}{}",
      kPattern, what, name(target[0]), name(target[1]), name(target[2]), n1, axis_name(c.joints[0].axis), n2, n3,
      axis_name(c.joints[1].axis), n4, leg.rows.sum->name, after);
  solve.doc = {
      fmt::format("Pattern {}: {} at the targets ({}, {}, {}).", kPattern, what, name(target[0]), name(target[1]),
                  name(target[2])),
      fmt::format("The sum row {} fixes the total turn of {}, {} and {} (parallel axes), so what follows",
                  leg.rows.sum->name, n2, n3, n4),
      fmt::format("{} keeps a known pose in the frame after {}; {} turns their plane through the target,", n4, n1, n1),
      fmt::format("the distance from the axis of {} to that of {} fixes {}, one rotation {}, the sum row {}.", n2, n4,
                  n3, n2, n4)};
  solve.branches = 4;
  solve.bits = {
      fmt::format("bit 0: the other root of {} (branch 0: the root nearest zero; on a tie the positive one)", n1),
      fmt::format("bit 1: the other root of {} (branch 0: the root nearest zero; on a tie the positive one)", n3)};
  solve.failures = {
      fmt::format(
          "{} out of reach: the plane of {}, {} and {} lies {{value:.4f}} m from the axis of {}, and the "
          "target only {{high:.4f}} m{}",
          leg.rows.frame, n2, n3, n4, n1,
          leg.wheel ? " (or the wheel's axle would be vertical: a wheel lying flat touches no single point)" : ""),
      fmt::format("{} out of reach: the axis of {} would be {{value:.4f}} m from that of {}, and {} and {} reach "
                  "[{{low:.4f}}, {{high:.4f}}] m from it",
                  leg.rows.frame, n4, n2, n2, n3)};
}

// Stage (a wheel): the axle a and world up z in E's axes, and from them the contact point's
// offset from the hub, k = o a - r u (ik_k0, ik_k1, ik_k2).
Stage contact_offset_stage(const Model& m, const SteeringLeg& leg) {
  const Vec3 axle = leg.R1 * (leg.total_turn * (leg.tail_turns * unit(leg.wheel->axle)));
  Stage st;
  for (int i = 0; i < 3; ++i) st.locals.emplace_back(realsymbol(fmt::format("ik_a{}", i)), axle[i].expand());
  for (int i = 0; i < 3; ++i) st.locals.emplace_back(realsymbol(fmt::format("ik_z{}", i)), leg.up[i].expand());
  st.locals.emplace_back(realsymbol("ik_radius"), m.parameter(leg.wheel->radius).symbol);
  st.locals.emplace_back(realsymbol("ik_offset"),
                         leg.wheel->offset.empty() ? ex(0) : ex(m.parameter(leg.wheel->offset).symbol));
  st.code =
      "  const Scalar ik_az = ik_a0 * ik_z0 + ik_a1 * ik_z1 + ik_a2 * ik_z2;  // the axle's upward component\n"
      "  const Scalar ik_tilt2 = (1 - ik_az) * (1 + ik_az);                   // |z - a_z a|^2\n"
      "  if (!(ik_tilt2 > std::numeric_limits<Scalar>::epsilon())) {\n"
      "    why = {1, 0.0, 0.0, 0.0, 0.0};\n"
      "    return IkStatus::out_of_reach;\n"
      "  }\n"
      "  const Scalar ik_rim = ik_radius / detail::square_root(ik_tilt2);\n"
      "  const Scalar ik_k0 = ik_offset * ik_a0 - ik_rim * (ik_z0 - ik_az * ik_a0);\n"
      "  const Scalar ik_k1 = ik_offset * ik_a1 - ik_rim * (ik_z1 - ik_az * ik_a1);\n"
      "  const Scalar ik_k2 = ik_offset * ik_a2 - ik_rim * (ik_z2 - ik_az * ik_a2);\n";
  st.defines = {"ik_k0", "ik_k1", "ik_k2"};
  return st;
}

// Stage: the first joint from the plane's offset, (R_1(q1) n) . d = Y.
Stage first_joint_stage(const Model& m, const SteeringLeg& leg, const Vec3& k, const SolvedJoint& s1, Vec3& d) {
  const ChainStep& j1 = leg.chain.joints[0];
  const Axis A = leg.chain.joints[1].axis;
  const Vec3 normal = leg.R1 * unit(A);
  Stage st;
  d = targets_from(m, base_frame(m, leg.chain), leg.rows.target, st);
  const realsymbol& q1 = m.coordinates[static_cast<std::size_t>(j1.coordinate)].q;
  const Sinusoid first =
      sinusoid(dot(signed_rot(j1.axis, j1.sign, q1) * normal, d).expand(), q1, "the leg plane's offset");
  const ex plane = dot(normal, leg.p1) + dot(unit(A), leg.p2 + leg.p3 + leg.total_turn * leg.tail) + dot(normal, k);
  add_plane_offset_solve(st, first, plane, s1);
  return st;
}

// Stage: w, the fourth joint from the second in the frame before the second; its distance fixes
// the third joint.
Stage two_link_stage(const Model& m, const Solve& solve, const SteeringLeg& leg, const Vec3& d, const Vec3& k,
                     const SolvedJoint& s3) {
  const ChainStep& j1 = leg.chain.joints[0];
  const realsymbol& q1 = m.coordinates[static_cast<std::size_t>(j1.coordinate)].q;
  const Vec3 w = in_axes(leg.R1, signed_rot(j1.axis, -j1.sign, q1) * d - leg.p1 - k) - leg.total_turn * leg.tail;
  return two_link_distance_stage(m, solve, w, leg.p2, leg.R2, leg.chain.joints[2], leg.p3, s3);
}

}  // namespace

Solve plan_steering_leg(const Model& m, const Limb& limb) {
  const SteeringLeg leg = steering_leg(m, limb);
  const CanonicalChain& c = leg.chain;
  Solve solve;
  solve.pattern = "steering-leg";
  const SolvedJoint s1 = joint_symbols(m, c.joints[0].coordinate), s2 = joint_symbols(m, c.joints[1].coordinate),
                    s3 = joint_symbols(m, c.joints[2].coordinate);
  solve.joints = {s1, s2, s3};
  solve.coupled = {{c.joints[3].coordinate, leg.coupled_value}};
  describe_steering_leg(m, leg, solve);
  Vec3 k;  // the contact point from the hub, in E's axes (zero for a frame's origin)
  if (leg.wheel) {
    solve.stages.push_back(contact_offset_stage(m, leg));
    k = Vec3(realsymbol("ik_k0"), realsymbol("ik_k1"), realsymbol("ik_k2"));
  }
  Vec3 d;
  solve.stages.push_back(first_joint_stage(m, leg, k, s1, d));
  solve.stages.push_back(two_link_stage(m, solve, leg, d, k, s3));
  solve.stages.push_back(two_link_rotation_stage(m, solve, leg.p2, leg.R2, c.joints[1], c.joints[2], leg.p3, s2));
  return solve;
}

}  // namespace wlx::codegen::ik
