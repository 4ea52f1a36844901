// The IK patterns' planning: which pattern solves a limb, with the equations of each stage of its
// solve, as symbolic expressions and solver calls (emit_ik.cpp prints them into ik.hpp).
//
// Closed-form inverse kinematics, derived from the model's own chains (the way IKFast does it for
// arms, for the limb types of walking machines) and emitted as straight-line C++ with a few calls
// of two small solvers, with every branch.
//
// Patterns (each checks its preconditions on the chain's canonical form, below, so on geometry;
// a limb that matches none is reported by wlx-gen with what each pattern needs, and solved by
// Newton's method at run time):
//
// point3 (a leg): the limb's three rows put one frame's origin at three input targets (x, y, z);
//   three revolute joints drive it, the axes of the first two meet, and nothing input-driven
//   follows the first. With d the target seen from the meeting point P, |d|^2 depends on the third
//   joint alone: K + A cos q3 + B sin q3 = |d|^2 (bit 0 picks the root); then R_a(q1) R_b(q2) v(q3)
//   = d is two rotations about principal axes (bit 1 picks q2's root). Any fixed offsets and turns
//   before the first joint, between the second and third and after the third.
//
// wheel leg / plane leg: the rows place a wheel's derived contact point (or a frame's origin);
//   the second and third joints (and the axle) are parallel. The plane's offset along its normal
//   fixes q1 (bit 0), the axle then the rim point nearest the ground and so the hub, whose distance
//   from the second joint fixes q3 (bit 1), and one rotation q2.
//
// leveled lever (a wheel lever): one point row (a component of a frame's origin equals an input),
//   two level rows on that frame (two of its axes horizontal) and sum rows that each fix one joint
//   linearly from inputs (a parallel guidance). After the couplings, the frame's orientation from
//   the first dependent joint on reduces to R_pre R_a(q_p + q_q) R_b(q_b), R_pre known: the level
//   rows make the third axis vertical, two rotations again (bit 1: q_b's root, bit 2: the root of
//   q_p + q_q), and the point row is then a cos q_p + b sin q_p = c (bit 0).
//
// steering leg (ik_steering_leg.cpp): three point rows and a sum row; a first joint, three parallel
//   joints the sum row holds at a known total turn, then inputs' joints: the plane's offset fixes
//   q1 (bit 0), a planar two-link leg q3 (bit 1) and q2, the sum row q4.
//
// Roots: branch 0 takes, in every equation, the root nearest the joint's zero (largest cosine; on
// a tie the positive angle); a set bit takes the other root. Every solve ends by evaluating the
// limb's own closure rows at the solution: a residual above kIkTolerance is reported, never
// returned as a solution.
#include "ik_internal.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

namespace wlx::codegen::ik {

SolvedJoint joint_symbols(const Model& m, int coordinate) {
  const std::string n = m.coordinates[static_cast<std::size_t>(coordinate)].name;
  return {coordinate, realsymbol("ik_q_" + n), realsymbol("ik_c_" + n), realsymbol("ik_s_" + n)};
}

ex in_results(const Model& m, ex e, const Solve& solve) {
  for (const auto& [k, value] : solve.coupled) {
    // GiNaC keeps sin(-x) as it is: write it -sin(x), so that the sine comes from the batched pass.
    const ex q = m.coordinates[static_cast<std::size_t>(k)].q, negated = (-value).expand();
    e = e.subs(GiNaC::lst{GiNaC::sin(q) == -GiNaC::sin(negated), GiNaC::cos(q) == GiNaC::cos(negated)});
    e = e.subs(q == value);
  }
  GiNaC::lst trig, plain;
  for (const SolvedJoint& j : solve.joints) {
    const ex q = m.coordinates[static_cast<std::size_t>(j.coordinate)].q;
    trig.append(GiNaC::sin(q) == j.s);
    trig.append(GiNaC::cos(q) == j.c);
    trig.append(GiNaC::sin(-q) == -j.s);  // a step about a negative axis (`ry: -q`): GiNaC keeps sin(-q)
    trig.append(GiNaC::cos(-q) == j.c);
    plain.append(q == j.q);
  }
  return e.subs(trig).subs(plain);
}

Sinusoid sinusoid(const ex& e, const realsymbol& q, const std::string& what) {
  const realsymbol C("ik_cos"), S("ik_sin");
  const ex f = e.subs(GiNaC::lst{GiNaC::cos(q) == C, GiNaC::sin(q) == S});
  if (f.has(q)) throw Unsolvable{what + " depends on " + q.get_name() + " other than through its sine and cosine"};
  Sinusoid out;
  out.c = f.subs(GiNaC::lst{C == 0, S == 0});
  out.a = f.subs(GiNaC::lst{C == 1, S == 0}) - out.c;
  out.b = f.subs(GiNaC::lst{C == 0, S == 1}) - out.c;
  if (!(f - (out.a * C + out.b * S + out.c)).expand().is_zero())
    throw Unsolvable{what + " is not of the form a cos " + q.get_name() + " + b sin " + q.get_name() + " + c"};
  return out;
}

namespace {

std::string two_axis_call(Axis a, Axis b, const std::string& v, const std::string& d, const std::string& flip,
                          const SolvedJoint& first, const SolvedJoint& second) {
  return fmt::format(
      "  Scalar {0}, {1}, {2}, {3}, ik_beside(0), ik_room(0);\n"
      "  const bool ik_two_axis_ok = ik_solve_two_axis<{4}, {5}>({6}, {7}, {8}, {0}, {1}, {2}, {3}, ik_beside, ik_room);\n",
      first.c.get_name(), first.s.get_name(), second.c.get_name(), second.s.get_name(), static_cast<int>(a),
      static_cast<int>(b), v, d, flip);
}

// The limb's three point rows: the frame they place and the input targets of its x, y and z.
std::pair<std::string, std::array<int, 3>> point_rows(const Model& m, const Limb& limb, const std::string& pattern) {
  if (limb.rows.size() != 3) {
    // Say which rows the limb has: one with x, y and z and a fourth row (a joint sum, a level
    // row) has "those three", and the message must name what is extra.
    std::vector<std::string> rows;
    for (int r : limb.rows) rows.push_back(m.closure[static_cast<std::size_t>(r)].name);
    throw Unsolvable{fmt::format("{} solves exactly three point rows (x, y and z of one frame); this limb has {}: {}", pattern,
                                 limb.rows.size(), fmt::join(rows, ", "))};
  }
  std::string frame;
  std::array<int, 3> target{-1, -1, -1};
  for (int r : limb.rows) {
    const ClosureCondition& c = m.closure[static_cast<std::size_t>(r)];
    if (c.kind != ClosureCondition::Kind::PointEqualsCoordinate) throw Unsolvable{pattern + ": row " + c.name + " is not a point row"};
    add_point_row(c, pattern, frame, target);
  }
  return {frame, target};
}

// The three dependent revolute joints of a canonical chain, nothing input-driven after the first.
void require_three_joints(const Model& m, const CanonicalChain& c, const std::string& frame, const std::string& pattern) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  for (const ChainStep& j : c.joints) {
    if (j.coordinate < m.input_count)
      throw Unsolvable{pattern + ": input " + name(j.coordinate) + " moves the chain after the first dependent joint " +
                       name(c.joints[0].coordinate) + " (put the inputs' joints first, nearer the root)"};
    if (j.kind == ChainStep::Kind::Slide) throw Unsolvable{pattern + ": " + name(j.coordinate) + " is prismatic"};
  }
  if (c.joints.size() != 3) throw Unsolvable{fmt::format("{}: {} dependent joints drive {}; the pattern solves three", pattern, c.joints.size(), frame)};
}

}  // namespace

void add_point_row(const ClosureCondition& row, const std::string& pattern, std::string& frame, std::array<int, 3>& target) {
  if (!frame.empty() && row.frame != frame) throw Unsolvable{pattern + ": the rows place different frames (" + frame + ", " + row.frame + ")"};
  frame = row.frame;
  auto& t = target[static_cast<std::size_t>(row.axis)];
  if (t >= 0) throw Unsolvable{pattern + ": two rows fix the same component"};
  t = row.target;
}

const NonholonomicWheel* wheel_of_contact(const Model& m, const std::string& frame) {
  const NamedFrame& placed = m.frames[static_cast<std::size_t>(m.frame_index(frame))];
  return placed.derived_from_wheel >= 0 ? &m.wheels[static_cast<std::size_t>(placed.derived_from_wheel)] : nullptr;
}

bool parallel_at_defaults(const Model& m, const Vec3& a, const Vec3& b) {
  const Vec3 across = cross(a, b);
  return identically_zero(across) ||
         std::abs(at_defaults(m, across[0])) + std::abs(at_defaults(m, across[1])) + std::abs(at_defaults(m, across[2])) < 1e-9;
}

// sin and cos of the joint from those of theta = sign q that a solver computed.
std::string unsign(const ChainStep& j, const SolvedJoint& s) {
  return j.sign < 0 ? fmt::format("  {0} = -{0};  // the step turns about the negative axis: q = -theta\n", s.s.get_name()) : "";
}

// |p + M R_axis(sign q) t|^2 = K + A cos q + B sin q, for p, t and M free of q.
Sinusoid distance_squared(const Vec3& p, const Mat3& M, const ChainStep& joint, const Vec3& t) {
  const realsymbol angle("ik_angle");
  const Sinusoid cross = sinusoid(2 * dot(p, M * (signed_rot(joint.axis, joint.sign, angle) * t)), angle, "the distance");
  return {cross.a, cross.b, (dot(p, p) + dot(t, t) + cross.c).expand()};
}

// The targets seen from `base` (from its origin, in its axes): the stage's locals ik_d0, ik_d1, ik_d2.
Vec3 targets_from(const Model& m, const Frame& base, const std::array<int, 3>& target, Stage& stage) {
  const realsymbol d[3] = {realsymbol("ik_d0"), realsymbol("ik_d1"), realsymbol("ik_d2")};
  for (int i = 0; i < 3; ++i) {
    ex di = 0;
    for (int k = 0; k < 3; ++k)
      di += base.R(k, i) * (m.coordinates[static_cast<std::size_t>(target[static_cast<std::size_t>(k)])].q - base.r[k]);
    stage.locals.emplace_back(d[i], di);
  }
  return {d[0], d[1], d[2]};
}

// R^T v: v in the axes of a frame turned by R.
Vec3 in_axes(const Mat3& R, const Vec3& v) {
  Vec3 out;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) out[i] += R(k, i) * v[k];
  return out;
}

// ---- point3 -------------------------------------------------------------------------------------

namespace {

// A point3 leg's geometry, its preconditions checked.
struct Point3 {
  std::string frame;          // the frame the rows place
  std::array<int, 3> target;  // the inputs its x, y and z equal
  CanonicalChain chain;       // frame's
  Frame meeting;              // the frame before the first joint, moved to P, where the first two axes meet
  Mat3 M;                     // the turns from the second joint to the third
  Vec3 p, t;                  // P to the third joint (in the second joint's axes), the third joint to the point
};

Point3 point3(const Model& m, const Limb& limb) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const auto [frame, target] = point_rows(m, limb, "point3");
  if (wheel_of_contact(m, frame) != nullptr)
    throw Unsolvable{"point3: " + frame + " is a wheel's contact point (the wheel-leg pattern places it)"};
  const CanonicalChain c = canonical_chain(m, full_chain(m, frame));
  require_three_joints(m, c, frame, "point3");
  const ChainStep &j1 = c.joints[0], &j2 = c.joints[1], &j3 = c.joints[2];
  const std::string n1 = name(j1.coordinate), n2 = name(j2.coordinate), n3 = name(j3.coordinate);
  if (j1.axis == j2.axis)
    throw Unsolvable{"point3: " + n1 + " and " + n2 + " turn about parallel axes (both " + axis_name(j1.axis) + ")"};

  // Between the first two joints: turns about the first joint's axis move before it, turns about
  // the second's after it (both commute with their joint); anything else tilts the second axis.
  Rigid between = c.fixed[1];
  std::vector<Rot> before_first, after_second;
  while (!between.turns.empty() && between.turns.front().axis == j1.axis) {
    const Rot t = between.turns.front();
    between.offset = expanded(signed_rot(t.axis, -1, t.angle) * between.offset);  // T(o) R = R T(R^T o)
    before_first.push_back(t);
    between.turns.erase(between.turns.begin());
  }
  while (!between.turns.empty() && between.turns.back().axis == j2.axis) {
    after_second.insert(after_second.begin(), between.turns.back());
    between.turns.pop_back();
  }
  if (!between.turns.empty())
    throw Unsolvable{"point3: between " + n1 + " and " + n2 + " the chain turns (" + describe(between) +
                     ") about an axis of neither, so the axis of " + n2 + " is not a principal axis of " + n1 + "'s frame"};
  // The axes meet when the offset between the joints lies in the plane of the two axes.
  const int a1 = static_cast<int>(j1.axis), a2 = static_cast<int>(j2.axis), across = 3 - a1 - a2;
  if (!identically_zero(between.offset[across])) {
    // No value at the defaults in the reason: it reaches ik.hpp's comments, whose text must not
    // depend on the parameters' values (wlx-gen --data-at-run-time: numbers are data).
    throw Unsolvable{fmt::format("point3: the axes of {} and {} do not meet: the offset between the joints ({}) has a {} "
                                 "component across both axes; point3 needs it along the two axes (an offset "
                                 "across them that belongs further down the limb goes after the second joint)",
                                 n1, n2, describe(c.fixed[1]), axis_name(static_cast<Axis>(across)))};
  }
  // The meeting point P: on the first axis at the offset's component along it; from the second
  // joint's frame it lies back along the second axis by the offset's component along that one.
  Frame meeting = base_frame(m, c);
  for (const Rot& t : before_first) meeting = meeting.turned(t.axis, t.angle);
  if (!identically_zero(between.offset[a1])) meeting = meeting.translated(between.offset[a1] * unit(j1.axis));
  const Mat3 M = product(after_second) * product(c.fixed[2].turns);
  const Vec3 p = between.offset[a2] * unit(j2.axis) + product(after_second) * c.fixed[2].offset;  // P to the third joint
  const Vec3 t = c.fixed[3].offset;                                                                  // the third joint to the point
  return {frame, target, c, meeting, M, p, t};
}

// The solve's report line, documentation, branch bits and failure messages.
void describe_point3(const Model& m, const Point3& leg, Solve& solve) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const ChainStep &j1 = leg.chain.joints[0], &j2 = leg.chain.joints[1], &j3 = leg.chain.joints[2];
  const std::string n1 = name(j1.coordinate), n2 = name(j2.coordinate), n3 = name(j3.coordinate);
  const std::string& frame = leg.frame;
  const std::array<int, 3>& target = leg.target;
  solve.summary = fmt::format("point3: {} at (x, y, z) = ({}, {}, {}) by {} ({}), {} ({}) with meeting axes, then {} ({})", frame,
                              name(target[0]), name(target[1]), name(target[2]), n1, axis_name(j1.axis), n2, axis_name(j2.axis), n3,
                              axis_name(j3.axis));
  solve.doc = {
      fmt::format("Pattern point3: the origin of {} at the targets ({}, {}, {}), placed by the joints {} and {}", frame,
                  name(target[0]), name(target[1]), name(target[2]), n1, n2),
      fmt::format("(about {} and {}, with meeting axes) and {} (about {}). The distance from the", axis_name(j1.axis),
                  axis_name(j2.axis), n3, axis_name(j3.axis)),
      fmt::format("meeting point to the target fixes {}; then {} and {} turn the limb onto it.", n3, n2, n1)};
  solve.branches = 4;
  solve.bits = {fmt::format("bit 0: the other root of {} (branch 0: the root nearest zero; on a tie the positive one)", n3),
                fmt::format("bit 1: the other root of {} (branch 0: |{}| <= 90 deg where that solves)", n2, n2)};
  solve.failures = {
      fmt::format("{} out of reach: its target is {{value:.4f}} m from the meeting point of the axes of {} and {}, and "
                  "{} reaches [{{low:.4f}}, {{high:.4f}}] m from it",
                  frame, n1, n2, frame),
      fmt::format("{} out of reach: with {} at {{aux:.2f}} deg (set by the target's distance) it reaches at most "
                  "{{high:.4f}} m off the plane normal to the axis of {} (through the meeting point), but its target is "
                  "{{value:.4f}} m off it",
                  frame, n3, n1)};
}

}  // namespace

Solve plan_point3(const Model& m, const Limb& limb) {
  const Point3 leg = point3(m, limb);
  const ChainStep &j1 = leg.chain.joints[0], &j2 = leg.chain.joints[1], &j3 = leg.chain.joints[2];
  const Vec3 &p = leg.p, &t = leg.t;
  const Mat3& M = leg.M;
  Solve solve;
  solve.pattern = "point3";
  const SolvedJoint q1 = joint_symbols(m, j1.coordinate), q2 = joint_symbols(m, j2.coordinate), q3 = joint_symbols(m, j3.coordinate);
  solve.joints = {q1, q2, q3};
  describe_point3(m, leg, solve);

  // Stage 0: the target seen from the meeting point; |d|^2 = K + A cos q3 + B sin q3.
  Stage s0;
  targets_from(m, leg.meeting, leg.target, s0);
  const Sinusoid distance = distance_squared(p, M, j3, t);
  const realsymbol K_("ik_K"), A_("ik_A"), B_("ik_B");
  s0.locals.emplace_back(K_, distance.c);
  s0.locals.emplace_back(A_, distance.a);
  s0.locals.emplace_back(B_, distance.b);
  s0.code = distance_solve_code("d", 1, 1, q3);
  s0.defines = {q3.c.get_name(), q3.s.get_name()};
  solve.stages.push_back(s0);

  // Stage 1: v = p + M R_c(q3) t in the frame after q2, from P; two rotations take it onto d.
  Stage s1;
  const Vec3 v = p + M * (signed_rot(j3.axis, j3.sign, m.coordinates[static_cast<std::size_t>(j3.coordinate)].q) * t);
  const realsymbol vs[3] = {realsymbol("ik_v0"), realsymbol("ik_v1"), realsymbol("ik_v2")};
  for (int i = 0; i < 3; ++i) s1.locals.emplace_back(vs[i], in_results(m, v[i], solve));
  s1.code = "  const Scalar ik_v[3] = {ik_v0, ik_v1, ik_v2};\n  const Scalar ik_d[3] = {ik_d0, ik_d1, ik_d2};\n" +
            two_axis_call(j1.axis, j2.axis, "ik_v", "ik_d", "(branch & 2) != 0", q1, q2) +
            fmt::format("  if (!ik_two_axis_ok) {{\n    why = {{2, ik_beside, 0.0, ik_room, double(std::atan2({}, {})) * 57.29577951308232}};\n"
                        "    return IkStatus::out_of_reach;\n  }}\n",
                        q3.s.get_name(), q3.c.get_name()) +
            unsign(j1, q1) + unsign(j2, q2);
  s1.defines = {q1.c.get_name(), q1.s.get_name(), q2.c.get_name(), q2.s.get_name()};
  solve.stages.push_back(s1);
  return solve;
}

// ---- wheel leg (and plane leg) ------------------------------------------------------------------
//
// Three revolute joints, the last two (and, for a wheel, its axle) parallel: a hip that swings the
// leg's plane, then a planar two-link leg in it. Every point of the leg beyond the first joint,
// the wheel's contact point included (it lies in the wheel's plane, which the axle is normal to),
// keeps one distance Y along the leg plane's normal n from the first joint's origin, so the target
// d fixes the first joint: (R_1(q1) n) . d = Y. The axle a then follows from q1 and the inputs
// alone, hence the contact's offset from the hub, -r u with u = (e_z - a_z a) / |e_z - a_z a| (the
// derived contact frame's), and the hub's place h = target + r u. The distance from the second
// joint's origin to h fixes the third joint (K + A cos q3 + B sin q3 = |w|^2) and one rotation
// about the plane's normal the second. Without a wheel (r = 0) the same for a point.

namespace {

// A wheel leg's (or plane leg's) geometry, its preconditions checked.
struct WheelLeg {
  std::string frame;                         // the frame the rows place
  std::array<int, 3> target;                 // the inputs its x, y and z equal
  const NonholonomicWheel* wheel = nullptr;  // whose contact point frame is; nullptr: a plane leg
  std::string pattern;                       // "wheel leg" or "plane leg", for messages
  std::string point;                         // what the joints place: the wheel's hub, or frame
  CanonicalChain chain;                      // point's
  Mat3 R1, R2;                               // the fixed turns after the first and the second joint
  Vec3 p1, p2, p3;                           // the fixed offsets after the three joints
  Vec3 normal;                               // the leg plane's normal in the frame after q1
  ex plane;                                  // Y: the leg plane's offset along the normal, of the rows' point
  ex rim;                                    // a wheel: its rolling plane's offset along the normal from the hub (0: none)
};

WheelLeg wheel_leg(const Model& m, const Limb& limb) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const auto [frame, target] = point_rows(m, limb, "wheel leg");
  const NonholonomicWheel* wheel = wheel_of_contact(m, frame);
  const std::string pattern = wheel ? "wheel leg" : "plane leg";
  const std::string point = wheel ? wheel->hub : frame;
  const CanonicalChain c = canonical_chain(m, full_chain(m, point));
  require_three_joints(m, c, point, pattern);
  const ChainStep &j1 = c.joints[0], &j2 = c.joints[1], &j3 = c.joints[2];
  const std::string n1 = name(j1.coordinate), n2 = name(j2.coordinate), n3 = name(j3.coordinate);
  const auto parallel = [](const Vec3& a, const Vec3& b) { return identically_zero(cross(a, b)); };
  if (!parallel(product(c.fixed[2].turns) * unit(j3.axis), unit(j2.axis)))
    throw Unsolvable{pattern + ": the axes of " + n2 + " and " + n3 + " are not parallel (" + describe(c.fixed[2]) +
                     " between them); the pattern needs the last two joints about parallel axes (a leg's flexion and knee), "
                     "with turns between them only about that axis"};
  if (wheel && !parallel(product(c.fixed[3].turns) * unit(wheel->axle), unit(j3.axis)))
    throw Unsolvable{pattern + ": the axle of wheel " + wheel->name + " (" + axis_name(wheel->axle) + " of " + wheel->hub +
                     ") is not parallel to the axis of " + n3 + "; the pattern needs the wheel turning in the leg's plane"};
  const Mat3 R1 = product(c.fixed[1].turns);
  const Vec3 normal = R1 * unit(j2.axis);  // the leg plane's normal in the frame after q1
  if (parallel_at_defaults(m, unit(j1.axis), normal))
    throw Unsolvable{pattern + ": the axis of " + n1 + " is parallel to those of " + n2 + " and " + n3 + " (a planar leg: " + n1 +
                     " cannot move the leg's plane)"};
  const ex& q2 = m.coordinates[static_cast<std::size_t>(j2.coordinate)].q;
  const ex& q3 = m.coordinates[static_cast<std::size_t>(j3.coordinate)].q;
  const Vec3 p1 = c.fixed[1].offset, p2 = c.fixed[2].offset, p3 = c.fixed[3].offset;
  const Mat3 R2 = product(c.fixed[2].turns);
  const Vec3 hub = p1 + R1 * (signed_rot(j2.axis, j2.sign, q2) * (p2 + R2 * (signed_rot(j3.axis, j3.sign, q3) * p3)));
  const ex plane = dot(normal, hub).expand();
  if (plane.has(q2) || plane.has(q3))
    throw std::logic_error("wlx-gen: the leg plane's offset depends on the planar joints");  // parallel axes exclude it
  // A wheel's rolling plane sits `offset` along the axle from the hub (c = h + o a - r u): the axle
  // is the plane's normal up to its sign, so the contact point's plane lies o (a . n) beyond the hub's.
  // Its sign, a . n, is structural (R1 turns both alike; q2 and q3 and the turns the checks above
  // allow keep the axis): exact when those turns are about the axis itself, else read at the defaults.
  ex rim = 0;
  if (wheel && !wheel->offset.empty()) {
    ex sign = dot(R2 * (product(c.fixed[3].turns) * unit(wheel->axle)), unit(j2.axis)).expand();
    if (!sign.is_equal(1) && !sign.is_equal(-1)) sign = at_defaults(m, sign) > 0 ? 1 : -1;
    rim = m.parameter(wheel->offset).symbol * sign;
  }
  return {frame, target, wheel, pattern, point, c, R1, R2, p1, p2, p3, normal, plane + rim, rim};
}

// The solve's report line, documentation, branch bits and failure messages.
void describe_wheel_leg(const Model& m, const WheelLeg& leg, Solve& solve) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const ChainStep &j1 = leg.chain.joints[0], &j2 = leg.chain.joints[1];
  const std::string n1 = name(j1.coordinate), n2 = name(j2.coordinate), n3 = name(leg.chain.joints[2].coordinate);
  const std::string &pattern = leg.pattern, &frame = leg.frame, &point = leg.point;
  const std::array<int, 3>& target = leg.target;
  const NonholonomicWheel* wheel = leg.wheel;
  const std::string what = wheel ? "the contact point of wheel " + wheel->name + " (" + frame + ")" : frame;
  solve.summary = fmt::format("{}: {} at (x, y, z) = ({}, {}, {}) by {} ({}), then {} and {} (parallel, about {}){}", pattern, what,
                              name(target[0]), name(target[1]), name(target[2]), n1, axis_name(j1.axis), n2, n3, axis_name(j2.axis),
                              wheel ? ", the hub " + point + " from the radius and the ground" : "");
  solve.doc = {
      fmt::format("Pattern {}: {} at the targets ({}, {}, {}).", pattern, what, name(target[0]), name(target[1]), name(target[2])),
      fmt::format("{} (about {}) turns the plane of {} and {} (parallel axes) through the target;", n1, axis_name(j1.axis), n2, n3),
      wheel ? fmt::format("the axle then fixes the rim point nearest the ground, so the hub {} sits at the target plus the", point)
            : std::string("the distance from the axis of " + n2 + " fixes " + n3 + ", one rotation " + n2 + "."),
  };
  if (wheel)
    solve.doc.push_back(fmt::format("radius along the rim's upward direction; its distance from the axis of {} fixes {}, then {}.", n2, n3, n2));
  solve.branches = 4;
  solve.bits = {fmt::format("bit 0: the other root of {} (branch 0: the root nearest zero; on a tie the positive one)", n1),
                fmt::format("bit 1: the other root of {} (branch 0: the root nearest zero; on a tie the positive one)", n3)};
  solve.failures = {
      fmt::format("{} out of reach: the plane of {} and {} lies {{value:.4f}} m from the axis of {}, and the target only "
                  "{{high:.4f}} m{}",
                  frame, n2, n3, n1, wheel ? " (or the wheel's axle would be vertical: a wheel lying flat touches no single point)" : ""),
      fmt::format("{} out of reach: it would be {{value:.4f}} m from the axis of {} (the origin of its frame), and the leg "
                  "reaches [{{low:.4f}}, {{high:.4f}}] m from it",
                  point, n2)};
}

// Stage 1 (a wheel): from the axle in K0, the rim's upward direction u (ik_u0, ik_u1, ik_u2).
Stage rim_stage(const Model& m, const Solve& solve, const Vec3& axle) {
  Stage st1;
  const realsymbol a[3] = {realsymbol("ik_a0"), realsymbol("ik_a1"), realsymbol("ik_a2")};
  for (int i = 0; i < 3; ++i) st1.locals.emplace_back(a[i], in_results(m, axle[i], solve));
  st1.code =
      "  const Scalar ik_tilt2 = (1 - ik_a2) * (1 + ik_a2);  // |e_z - a_z a|^2\n"
      "  if (!(ik_tilt2 > std::numeric_limits<Scalar>::epsilon())) {\n"
      "    why = {1, 0.0, 0.0, 0.0, 0.0};\n"
      "    return IkStatus::out_of_reach;\n"
      "  }\n"
      "  const Scalar ik_tilt = detail::square_root(ik_tilt2);\n"
      "  const Scalar ik_u0 = -ik_a2 * ik_a0 / ik_tilt, ik_u1 = -ik_a2 * ik_a1 / ik_tilt, ik_u2 = ik_tilt;\n";
  st1.defines = {"ik_u0", "ik_u1", "ik_u2"};
  return st1;
}

// Stage 2: the hub (point) from the second joint's origin, in the frame before q2; its distance
// fixes q3.
Stage hub_distance_stage(const Model& m, const Solve& solve, const WheelLeg& leg, const Vec3& hub_target, const SolvedJoint& s3) {
  const ChainStep& j1 = leg.chain.joints[0];
  const realsymbol& q1 = m.coordinates[static_cast<std::size_t>(j1.coordinate)].q;
  const Vec3 w = in_axes(leg.R1, signed_rot(j1.axis, -j1.sign, q1) * hub_target - leg.p1);
  return two_link_distance_stage(m, solve, w, leg.p2, leg.R2, leg.chain.joints[2], leg.p3, s3);
}

}  // namespace

Solve plan_wheel_leg(const Model& m, const Limb& limb) {
  const WheelLeg leg = wheel_leg(m, limb);
  const ChainStep &j1 = leg.chain.joints[0], &j2 = leg.chain.joints[1], &j3 = leg.chain.joints[2];
  Solve solve;
  solve.pattern = leg.wheel ? "wheel-leg" : "plane-leg";
  const SolvedJoint s1 = joint_symbols(m, j1.coordinate), s2 = joint_symbols(m, j2.coordinate), s3 = joint_symbols(m, j3.coordinate);
  solve.joints = {s1, s2, s3};
  describe_wheel_leg(m, leg, solve);

  // Stage 0: the target in the frame before q1; (R_1(q1) n) . d = Y.
  const Frame base = base_frame(m, leg.chain);
  Stage st0;
  const Vec3 d = targets_from(m, base, leg.target, st0);
  const realsymbol& q1 = m.coordinates[static_cast<std::size_t>(j1.coordinate)].q;
  const Mat3 turn1 = signed_rot(j1.axis, j1.sign, q1);
  const Sinusoid first = sinusoid(dot(turn1 * leg.normal, d).expand(), q1, "the leg plane's offset");
  add_plane_offset_solve(st0, first, leg.plane, s1);
  solve.stages.push_back(st0);

  // The hub at the target - o a + r u (a wheel; u from stage 1), in the frame before q1: o a = rim n.
  Vec3 hub_target = d;
  if (leg.wheel) {
    solve.stages.push_back(rim_stage(m, solve, base.R * (turn1 * leg.normal)));
    const ex r = m.parameter(leg.wheel->radius).symbol;
    const Vec3 up(realsymbol("ik_u0"), realsymbol("ik_u1"), realsymbol("ik_u2"));
    hub_target = hub_target - leg.rim * (turn1 * leg.normal) + r * in_axes(base.R, up);
  }
  solve.stages.push_back(hub_distance_stage(m, solve, leg, hub_target, s3));
  solve.stages.push_back(two_link_rotation_stage(m, solve, leg.p2, leg.R2, j2, j3, leg.p3, s2));
  return solve;
}

// ---- leveled lever ------------------------------------------------------------------------------

namespace {

// A leveled lever's rows, sorted and checked: the point row, the two level rows on its frame, and
// the joints the sum rows fix.
struct LeverRows {
  const ClosureCondition* point = nullptr;
  Axis vertical;                            // the frame's axis the level rows make vertical
  std::vector<std::pair<int, ex>> coupled;  // as Solve::coupled
  std::set<int> remaining;                  // the limb's joints the couplings leave (three)
};

LeverRows lever_rows(const Model& m, const Limb& limb) {
  using K = ClosureCondition::Kind;
  const ClosureCondition* point = nullptr;
  std::vector<const ClosureCondition*> level;
  LeverRows rows;
  rows.remaining.insert(limb.joints.begin(), limb.joints.end());
  for (int r : limb.rows) {
    const ClosureCondition& c = m.closure[static_cast<std::size_t>(r)];
    if (c.kind == K::PointEqualsCoordinate) {
      if (point != nullptr) throw Unsolvable{"leveled lever: more than one point row"};
      point = &c;
    } else if (c.kind == K::AttachedDirectionLevel) {
      level.push_back(&c);
    } else {
      int unknown = -1;
      ex others = 0;
      for (int k : c.coordinates) {
        if (k >= m.input_count) {
          if (unknown >= 0) throw Unsolvable{"leveled lever: sum row " + c.name + " has more than one dependent joint"};
          unknown = k;
        } else {
          others += m.coordinates[static_cast<std::size_t>(k)].q;
        }
      }
      if (unknown < 0) throw Unsolvable{"leveled lever: sum row " + c.name + " has no dependent joint"};
      rows.coupled.emplace_back(unknown, -others);
      rows.remaining.erase(unknown);
    }
  }
  if (point == nullptr || level.size() != 2) throw Unsolvable{"leveled lever needs one point row and two level rows"};
  for (const auto* l : level)
    if (l->frame != point->frame) throw Unsolvable{"leveled lever: the level rows and the point row are on different frames"};
  if (level[0]->axis == level[1]->axis) throw Unsolvable{"leveled lever: both level rows keep the same axis level"};
  if (rows.remaining.size() != 3) throw Unsolvable{"leveled lever: three joints must remain after the couplings"};
  rows.point = point;
  rows.vertical = static_cast<Axis>(3 - static_cast<int>(level[0]->axis) - static_cast<int>(level[1]->axis));
  return rows;
}

// The angle of a rotation step: a fixed turn's, a coupled joint's value, or the joint itself.
ex coupled_angle(const Model& m, const std::vector<std::pair<int, ex>>& coupled, const ChainStep& st) {
  if (st.kind == ChainStep::Kind::Turn) return st.angle;
  for (const auto& [k, value] : coupled)
    if (k == st.coordinate) return value;
  return m.coordinates[static_cast<std::size_t>(st.coordinate)].q;
}

// The lever frame's chain, whose orientation from the first dependent joint on reduces (couplings
// substituted) to R_pre R_a(q_p + q_q) R_b(q_b), R_pre known.
struct LeverChain {
  std::vector<ChainStep> steps;  // K0 to the frame
  std::size_t first = 0;         // the first dependent joint's step
  Frame base;                    // the frame before it
  std::vector<Rot> merged;       // the rotations from it on: R_pre's, then R_a and R_b
  int qp = -1, qq = -1, qb = -1;
  const Rot& ra() const { return merged[merged.size() - 2]; }
  const Rot& rb() const { return merged.back(); }
};

LeverChain lever_chain(const Model& m, const LeverRows& rows) {
  const std::string& frame = rows.point->frame;
  require_plain_chain(m, frame, {}, "leveled lever");
  LeverChain lever;
  const std::vector<ChainStep>& chain = lever.steps = full_chain(m, frame);
  require_plain_chain(m, frame, chain, "leveled lever");
  std::size_t first = chain.size();
  for (std::size_t i = 0; i < chain.size(); ++i)
    if (driven(chain[i]) && chain[i].coordinate >= m.input_count) {
      first = i;
      break;
    }
  if (first == chain.size()) throw Unsolvable{"leveled lever: no dependent joint moves " + frame};
  for (std::size_t i = first; i < chain.size(); ++i)
    if (chain[i].kind == ChainStep::Kind::Slide) throw Unsolvable{"leveled lever: a prismatic joint after the first dependent one"};
  lever.first = first;
  lever.base = Frame::ground();
  for (std::size_t i = 0; i < first; ++i) lever.base = apply(m, lever.base, chain[i]);

  // Orientation from the first dependent joint on, couplings substituted.
  std::vector<Rot> rotations;
  for (std::size_t i = first; i < chain.size(); ++i)
    if (chain[i].kind == ChainStep::Kind::Rotate || chain[i].kind == ChainStep::Kind::Turn)
      rotations.push_back({chain[i].axis, coupled_angle(m, rows.coupled, chain[i])});
  const std::vector<Rot>& merged = lever.merged = merge(rotations);
  const auto unknowns_in = [&](const ex& e) {
    std::vector<int> out;
    for (int k : rows.remaining)
      if (e.has(m.coordinates[static_cast<std::size_t>(k)].q)) out.push_back(k);
    return out;
  };
  if (merged.size() < 2) throw Unsolvable{"leveled lever: the orientation does not reduce to two rotations"};
  const Rot &ra = lever.ra(), &rb = lever.rb();
  const std::vector<int> in_a = unknowns_in(ra.angle), in_b = unknowns_in(rb.angle);
  for (std::size_t i = 0; i + 2 < merged.size(); ++i)
    if (!unknowns_in(merged[i].angle).empty())
      throw Unsolvable{"leveled lever: the orientation does not reduce to R_pre R_a(q_p + q_q) R_b(q_b)"};
  if (in_b.size() != 1 || !(rb.angle - m.coordinates[static_cast<std::size_t>(in_b[0])].q).is_zero())
    throw Unsolvable{"leveled lever: the last rotation is not one joint alone"};
  if (in_a.size() != 2) throw Unsolvable{"leveled lever: the second-to-last rotation is not the sum of two joints"};
  if (!(ra.angle - m.coordinates[static_cast<std::size_t>(in_a[0])].q - m.coordinates[static_cast<std::size_t>(in_a[1])].q).expand().is_zero())
    throw Unsolvable{"leveled lever: the second-to-last rotation is not exactly the sum of two joints"};
  if (ra.axis == rows.vertical || rb.axis == rows.vertical)
    throw Unsolvable{"leveled lever: the two rotations must turn about the axes that the level rows keep level"};
  // q_p: the one of the two whose step comes first along the chain (it moves the lever's point).
  lever.qp = in_a[0];
  lever.qq = in_a[1];
  for (std::size_t i = first; i < chain.size(); ++i)
    if (driven(chain[i]) && (chain[i].coordinate == in_a[0] || chain[i].coordinate == in_a[1])) {
      lever.qp = chain[i].coordinate;
      lever.qq = lever.qp == in_a[0] ? in_a[1] : in_a[0];
      break;
    }
  lever.qb = in_b[0];
  return lever;
}

// The solve's joints: q_p, q_q and q_b, and the sum q_p + q_q (its cosine and sine; q unused).
struct LeverJoints {
  SolvedJoint p, q, b, sum;
};

// The solve's report line, documentation, branch bits and failure message.
void describe_lever(const Model& m, const LeverRows& rows, const LeverChain& lever, Solve& solve) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const ClosureCondition& point = *rows.point;
  const std::string& frame = point.frame;
  const Axis a = lever.ra().axis, b = lever.rb().axis;
  const std::string np = name(lever.qp), nq = name(lever.qq), nb = name(lever.qb), target = name(point.target);
  std::string coupled_names;
  for (const auto& [k, value] : solve.coupled) coupled_names += (coupled_names.empty() ? "" : ", ") + name(k);
  solve.summary = fmt::format("leveled lever: {} level by {} + {} ({}) and {} ({}), {}_{} = {} by {}; coupled: {}", frame, np, nq,
                              axis_name(a), nb, axis_name(b), frame, axis_name(point.axis), target, np,
                              coupled_names.empty() ? "none" : coupled_names);
  solve.doc = {
      fmt::format("Pattern leveled lever: {} fixed by the sum rows; {}'s {} axis vertical (its other axes level)", coupled_names,
                  frame, axis_name(rows.vertical)),
      fmt::format("through the rotations about {} by {} + {} and about {} by {}; then {}'s {} = {} by {}.", axis_name(a), np,
                  nq, axis_name(b), nb, frame, axis_name(point.axis), target, np)};
  solve.branches = 8;
  solve.bits = {fmt::format("bit 0: the other root of {} (branch 0: the root nearest zero)", np),
                fmt::format("bit 1: the other root of {} (branch 0: |{}| <= 90 deg)", nb, nb),
                fmt::format("bit 2: the other root of {} + {} (branch 0: nearest zero)", np, nq)};
  std::string inputs;
  {
    std::set<int> in;
    for (const auto& st : lever.steps)
      if (driven(st) && st.coordinate < m.input_count) in.insert(st.coordinate);
    for (const auto& [k, value] : solve.coupled)
      for (const auto& kv : m.coordinates)
        if (value.has(kv.q)) in.insert(kv.index);
    for (int k : in) inputs += (inputs.empty() ? "" : ", ") + name(k);
  }
  solve.failures = {fmt::format("{} = {{value:.4f}} m is out of reach: with {} as given, the {} of {} reaches [{{low:.4f}}, "
                                "{{high:.4f}}] m",
                                target, inputs, axis_name(point.axis), frame)};
}

// Stage 0: the coupled joints; world up seen from the frame before the two rotations; solve them.
Stage level_stage(const Model& m, const LeverRows& rows, const LeverChain& lever, const LeverJoints& joints) {
  const std::vector<Rot> pre(lever.merged.begin(), lever.merged.end() - 2);
  const Mat3 up_frame = lever.base.R * product(pre);
  const Axis vertical = rows.vertical;
  Stage s0;
  for (const auto& [k, value] : rows.coupled) s0.locals.emplace_back(joint_symbols(m, k).q, value);
  const realsymbol g[3] = {realsymbol("ik_g0"), realsymbol("ik_g1"), realsymbol("ik_g2")};
  for (int i = 0; i < 3; ++i) s0.locals.emplace_back(g[i], up_frame(2, i));
  const std::string unit = fmt::format("{{{}, {}, {}}}", vertical == Axis::X ? "Scalar(1)" : "Scalar(0)",
                                       vertical == Axis::Y ? "Scalar(1)" : "Scalar(0)", vertical == Axis::Z ? "Scalar(1)" : "Scalar(0)");
  s0.code = "  const Scalar ik_axis[3] = " + unit + ";\n  const Scalar ik_g[3] = {ik_g0, ik_g1, ik_g2};\n" +
            two_axis_call(lever.ra().axis, lever.rb().axis, "ik_axis", "ik_g", "(branch & 2) != 0", joints.sum, joints.b) +
            fmt::format(
                "  static_cast<void>(ik_two_axis_ok);  // cannot fail: the axis is perpendicular to both rotations\n"
                "  // The sum's other root: a half turn, with the last joint mirrored (the vertical axis flips).\n"
                "  if ((ik_c_sum < 0) != ((branch & 4) != 0)) {{\n"
                "    ik_c_sum = -ik_c_sum;\n    ik_s_sum = -ik_s_sum;\n"
                "    {0} = -{0};\n  }}\n",
                joints.b.s.get_name());
  s0.defines = {"ik_c_sum", "ik_s_sum", joints.b.c.get_name(), joints.b.s.get_name()};
  return s0;
}

// Stage 1: the point row, with q_q = sum - q_p: a cos q_p + b sin q_p + c.
Stage point_row_stage(const Model& m, const Solve& solve, const LeverRows& rows, const LeverChain& lever, const LeverJoints& joints) {
  const ClosureCondition& point = *rows.point;
  const std::string target = m.coordinates[static_cast<std::size_t>(point.target)].name;
  const ex qp_sym = m.coordinates[static_cast<std::size_t>(lever.qp)].q, qq_sym = m.coordinates[static_cast<std::size_t>(lever.qq)].q;
  const realsymbol sum_sym("ik_sum");
  Vec3 pos;
  std::vector<Rot> prefix;
  for (std::size_t i = lever.first; i < lever.steps.size(); ++i) {
    const ChainStep& st = lever.steps[i];
    if (st.kind == ChainStep::Kind::Translate) {
      pos = pos + product(merge(prefix)) * st.offset;
    } else {
      ex a = coupled_angle(m, solve.coupled, st);
      a = a.subs(qq_sym == sum_sym - qp_sym);
      prefix.push_back({st.axis, a});
    }
  }
  const int k = static_cast<int>(point.axis);
  ex height = lever.base.r[k];
  for (int j = 0; j < 3; ++j) height += lever.base.R(k, j) * pos[j];
  const Sinusoid row = sinusoid(height, GiNaC::ex_to<realsymbol>(qp_sym), "the point row");
  Solve with_sum = solve;  // sin, cos of the sum and of q_b by their computed values
  with_sum.joints = {joints.b};
  const auto results = [&](const ex& e) {
    return in_results(m, e, with_sum).subs(GiNaC::lst{GiNaC::sin(sum_sym) == joints.sum.s, GiNaC::cos(sum_sym) == joints.sum.c});
  };
  Stage s1;
  s1.locals = {{realsymbol("ik_alpha"), results(row.a)}, {realsymbol("ik_beta"), results(row.b)}, {realsymbol("ik_gamma"), results(row.c)}};
  const SolvedJoint &Jp = joints.p, &Jq = joints.q;
  s1.code = fmt::format(
      "  Scalar {0}, {1};\n"
      "  if (!ik_solve_cos_sin(ik_alpha, ik_beta, {2} - ik_gamma, (branch & 1) != 0, {0}, {1})) {{\n"
      "    const Scalar ik_R = detail::square_root(ik_alpha * ik_alpha + ik_beta * ik_beta);\n"
      "    why = {{1, {2}, ik_gamma - ik_R, ik_gamma + ik_R, 0.0}};\n"
      "    return IkStatus::out_of_reach;\n"
      "  }}\n"
      "  const Scalar {3} = ik_c_sum * {0} + ik_s_sum * {1};\n"
      "  const Scalar {4} = ik_s_sum * {0} - ik_c_sum * {1};\n",
      Jp.c.get_name(), Jp.s.get_name(), target, Jq.c.get_name(), Jq.s.get_name());
  s1.defines = {Jp.c.get_name(), Jp.s.get_name(), Jq.c.get_name(), Jq.s.get_name()};
  return s1;
}

}  // namespace

Solve plan_lever(const Model& m, const Limb& limb) {
  const LeverRows rows = lever_rows(m, limb);
  const LeverChain lever = lever_chain(m, rows);
  Solve solve;
  solve.pattern = "leveled-lever";
  solve.coupled = rows.coupled;
  const LeverJoints joints{joint_symbols(m, lever.qp), joint_symbols(m, lever.qq), joint_symbols(m, lever.qb),
                           {-1, realsymbol("ik_q_sum"), realsymbol("ik_c_sum"), realsymbol("ik_s_sum")}};
  describe_lever(m, rows, lever, solve);
  solve.stages.push_back(level_stage(m, rows, lever, joints));
  solve.stages.push_back(point_row_stage(m, solve, rows, lever, joints));
  solve.joints = {joints.p, joints.q, joints.b};
  return solve;
}

}  // namespace wlx::codegen::ik
