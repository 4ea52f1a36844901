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
// Roots: branch 0 takes, in every equation, the root nearest the joint's zero (largest cosine; on
// a tie the positive angle); a set bit takes the other root. Every solve ends by evaluating the
// limb's own closure rows at the solution: a residual above kIkTolerance is reported, never
// returned as a solution.
#include "derivations.hpp"
#include "emit.hpp"
#include "model_file.hpp"
#include "printer.hpp"

#include <fmt/format.h>

#include <cmath>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>

namespace wlx::codegen {

namespace {

using GiNaC::realsymbol;
using namespace detail;

struct Unsolvable {
  std::string reason;
};

const char* axis_name(Axis a) { return a == Axis::X ? "x" : a == Axis::Y ? "y" : "z"; }

// Every step from K0 to the frame, parents first.
std::vector<ChainStep> full_chain(const Model& m, const std::string& frame) {
  std::vector<const NamedFrame*> path;
  for (std::string f = frame; f != "K0";) {
    const NamedFrame& nf = m.frames[static_cast<std::size_t>(m.frame_index(f))];
    path.push_back(&nf);
    f = nf.parent;
  }
  std::vector<ChainStep> out;
  for (auto it = path.rbegin(); it != path.rend(); ++it) out.insert(out.end(), (*it)->chain.begin(), (*it)->chain.end());
  return out;
}

Frame apply(const Model& m, const Frame& f, const ChainStep& st) {
  switch (st.kind) {
    case ChainStep::Kind::Translate: return f.translated(st.offset);
    case ChainStep::Kind::Rotate: return f.rotated(st.axis, m.coordinates[static_cast<std::size_t>(st.coordinate)], st.sign);
    case ChainStep::Kind::Slide: return f.slid(st.axis, m.coordinates[static_cast<std::size_t>(st.coordinate)], st.sign);
    case ChainStep::Kind::Turn: return f.turned(st.axis, st.angle);
  }
  return f;
}

bool driven(const ChainStep& st) { return st.kind == ChainStep::Kind::Rotate || st.kind == ChainStep::Kind::Slide; }

// The patterns below read joint steps as turns about +x, +y or +z; a chain with a negated joint
// (`ry: -q`) or a wheel's derived contact frame is not theirs.
void require_plain_chain(const Model& m, const std::string& frame, const std::vector<ChainStep>& chain, const char* pattern) {
  if (m.frames[static_cast<std::size_t>(m.frame_index(frame))].derived_from_wheel >= 0)
    throw Unsolvable{std::string(pattern) + ": " + frame + " is a wheel's derived contact point"};
  for (const ChainStep& st : chain)
    if (driven(st) && st.sign < 0)
      throw Unsolvable{std::string(pattern) + ": " + m.coordinates[static_cast<std::size_t>(st.coordinate)].name +
                       " turns about a negative axis"};
}

// A rotation whose angle is an expression, for reducing orientation chains.
struct Rot {
  Axis axis;
  ex angle;
};

// Adjacent rotations about the same axis add up; zero angles vanish (so a coupling q4 = -q5 between
// Rz(q5) Rz(q4) leaves nothing, and the rotations on both sides may then merge).
std::vector<Rot> merge(const std::vector<Rot>& seq) {
  std::vector<Rot> out;
  for (const Rot& r : seq) {
    if (!out.empty() && out.back().axis == r.axis) out.back().angle = (out.back().angle + r.angle).expand();
    else out.push_back({r.axis, r.angle.expand()});
    if (out.back().angle.is_zero()) out.pop_back();
  }
  return out;
}

Mat3 product(const std::vector<Rot>& seq) {
  Mat3 R = Mat3::identity();
  for (const Rot& r : seq) R = R * rot(r.axis, r.angle);
  return R;
}

// a cos q + b sin q + c = e, for e linear in cos q and sin q; throws otherwise.
struct Sinusoid {
  ex a, b, c;
};
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

// The generated code of one limb's solve: stages of named values (expressions of the inputs, the
// parameters and earlier stages' results) each followed by code calling a solver.
struct Stage {
  std::vector<std::pair<realsymbol, ex>> locals;
  std::string code;
  std::vector<std::string> defines;  // the variables its code computes (usable from the next stage on)
};

struct SolvedJoint {
  int coordinate;
  realsymbol q, c, s;  // value, cosine, sine in the generated code
};

struct Solve {
  std::string pattern;
  std::string summary;  // one line for wlx-gen's report
  std::vector<std::string> doc;
  int branches = 1;
  std::vector<std::string> bits;  // meaning of each branch bit
  std::vector<std::string> failures;  // message template of each failing stage (1-based in IkDiagnostics)
  std::vector<Stage> stages;
  std::vector<SolvedJoint> joints;
  std::vector<std::pair<int, ex>> coupled;  // joints fixed by a sum row: coordinate, value
};

SolvedJoint joint_symbols(const Model& m, int coordinate) {
  const std::string n = m.coordinates[static_cast<std::size_t>(coordinate)].name;
  return {coordinate, realsymbol("ik_q_" + n), realsymbol("ik_c_" + n), realsymbol("ik_s_" + n)};
}

// An expression in the model's symbols, rewritten in the solve's results: sines and cosines of the
// solved joints by their computed values, the joints themselves by theirs, coupled joints by
// their expressions.
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

std::string two_axis_call(Axis a, Axis b, const std::string& v, const std::string& d, const std::string& flip,
                          const SolvedJoint& first, const SolvedJoint& second) {
  return fmt::format(
      "  Scalar {0}, {1}, {2}, {3}, ik_beside(0), ik_room(0);\n"
      "  const bool ik_two_axis_ok = ik_solve_two_axis<{4}, {5}>({6}, {7}, {8}, {0}, {1}, {2}, {3}, ik_beside, ik_room);\n",
      first.c.get_name(), first.s.get_name(), second.c.get_name(), second.s.get_name(), static_cast<int>(a),
      static_cast<int>(b), v, d, flip);
}

// ---- canonical chains ---------------------------------------------------------------------------
//
// The patterns test geometry (do two axes meet, are they parallel), not the wording of the file:
// before matching, a chain is brought to a canonical form. From the first dependent joint on, the
// fixed steps between consecutive joints become one rigid transform (an offset, then the turns),
// with consecutive translations added up, consecutive turns about one axis merged and zero offsets
// and zero turns dropped. Then every offset's component along the axis of the joint just before it
// slides to before that joint (a translation along a joint's axis commutes with the joint), from
// the last joint to the first, so that offsets gather as near the root as they can; and turns about
// that joint's axis right after it (with no offset left in front of them) slide before it too.
// `translate: [0, 0, 0]` between two joints, a translation split over two steps, a hub offset
// written along the knee axis after the knee: all give the same canonical chain.

// A rigid transform that depends on parameters only: T(offset), then the turns in order.
struct Rigid {
  Vec3 offset;
  std::vector<Rot> turns;
};

bool identically_zero(const ex& e) { return e.expand().is_zero(); }
bool identically_zero(const Vec3& v) { return identically_zero(v[0]) && identically_zero(v[1]) && identically_zero(v[2]); }

// e at the parameters' defaults (for messages and for telling "not identically" from "not at all").
double at_defaults(const Model& m, const ex& e) {
  GiNaC::lst values;
  for (const Parameter& p : m.parameters) values.append(p.symbol == p.default_value);
  const ex v = GiNaC::evalf(e.subs(values));
  return GiNaC::is_a<GiNaC::numeric>(v) ? GiNaC::ex_to<GiNaC::numeric>(v).to_double() : std::nan("");
}

struct CanonicalChain {
  std::vector<ChainStep> prefix;  // the steps before the first dependent joint, as written
  std::vector<ChainStep> joints;  // every joint step from the first dependent one on
  std::vector<Rigid> fixed;       // fixed[k] before joints[k]; fixed[joints.size()] after the last
};

Vec3 expanded(const Vec3& v) { return {v[0].expand(), v[1].expand(), v[2].expand()}; }

CanonicalChain canonical_chain(const Model& m, const std::vector<ChainStep>& chain) {
  CanonicalChain c;
  std::size_t first = 0;
  while (first < chain.size() && !(driven(chain[first]) && chain[first].coordinate >= m.input_count)) ++first;
  c.prefix.assign(chain.begin(), chain.begin() + static_cast<std::ptrdiff_t>(first));
  c.fixed.emplace_back();
  for (std::size_t i = first; i < chain.size(); ++i) {
    const ChainStep& st = chain[i];
    Rigid& r = c.fixed.back();
    if (driven(st)) {
      c.joints.push_back(st);
      c.fixed.emplace_back();
    } else if (st.kind == ChainStep::Kind::Translate) {
      r.offset = expanded(r.offset + product(r.turns) * st.offset);  // T(o) R T(v) = T(o + R v) R
    } else {
      r.turns.push_back({st.axis, st.angle});
      r.turns = merge(r.turns);
    }
  }
  for (std::size_t k = c.joints.size(); k-- > 0;) {
    const ChainStep& j = c.joints[k];
    if (j.coordinate < m.input_count) continue;  // the base's own steps stay as written
    const int a = static_cast<int>(j.axis);
    Rigid &before = c.fixed[k], &after = c.fixed[k + 1];
    if (!identically_zero(after.offset[a])) {
      before.offset = expanded(before.offset + product(before.turns) * (after.offset[a] * unit(j.axis)));
      after.offset[a] = 0;
    }
    if (j.kind == ChainStep::Kind::Rotate && identically_zero(after.offset))
      while (!after.turns.empty() && after.turns.front().axis == j.axis) {
        before.turns.push_back(after.turns.front());
        before.turns = merge(before.turns);
        after.turns.erase(after.turns.begin());
      }
  }
  return c;
}

Frame apply(const Frame& f, const Rigid& r) {
  Frame out = identically_zero(r.offset) ? f : f.translated(r.offset);
  for (const Rot& t : r.turns) out = out.turned(t.axis, t.angle);
  return out;
}

// The frame before the first dependent joint: the prefix and the fixed transform after it.
Frame base_frame(const Model& m, const CanonicalChain& c) {
  Frame base = Frame::ground();
  for (const ChainStep& st : c.prefix) base = apply(m, base, st);
  return apply(base, c.fixed[0]);
}

std::string describe(const Model& m, const Rigid& r) {
  std::vector<std::string> parts;
  if (!identically_zero(r.offset)) {
    std::ostringstream o;
    o << "translate [" << r.offset[0] << ", " << r.offset[1] << ", " << r.offset[2] << "]";
    parts.push_back(o.str());
  }
  for (const Rot& t : r.turns) {
    std::ostringstream o;
    o << "r" << axis_name(t.axis) << ": " << t.angle;
    parts.push_back(o.str());
  }
  static_cast<void>(m);
  return parts.empty() ? "nothing" : fmt::format("{}", fmt::join(parts, ", "));
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
    if (!frame.empty() && c.frame != frame) throw Unsolvable{pattern + ": the rows place different frames (" + frame + ", " + c.frame + ")"};
    frame = c.frame;
    auto& t = target[static_cast<std::size_t>(c.axis)];
    if (t >= 0) throw Unsolvable{pattern + ": two rows fix the same component"};
    t = c.target;
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

// ---- point3 -------------------------------------------------------------------------------------

Solve plan_point3(const Model& m, const Limb& limb) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const auto [frame, target] = point_rows(m, limb, "point3");
  if (m.frames[static_cast<std::size_t>(m.frame_index(frame))].derived_from_wheel >= 0)
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
    throw Unsolvable{"point3: between " + n1 + " and " + n2 + " the chain turns (" + describe(m, between) +
                     ") about an axis of neither, so the axis of " + n2 + " is not a principal axis of " + n1 + "'s frame"};
  // The axes meet when the offset between the joints lies in the plane of the two axes.
  const int a1 = static_cast<int>(j1.axis), a2 = static_cast<int>(j2.axis), across = 3 - a1 - a2;
  if (!identically_zero(between.offset[across])) {
    // No value at the defaults in the reason: it reaches ik.hpp's comments, whose text must not
    // depend on the parameters' values (wlx-gen --data-at-run-time: numbers are data).
    throw Unsolvable{fmt::format("point3: the axes of {} and {} do not meet: the offset between the joints ({}) has a {} "
                                 "component across both axes; point3 needs it along the two axes (an offset "
                                 "across them that belongs further down the limb goes after the second joint)",
                                 n1, n2, describe(m, c.fixed[1]), axis_name(static_cast<Axis>(across)))};
  }
  // The meeting point P: on the first axis at the offset's component along it; from the second
  // joint's frame it lies back along the second axis by the offset's component along that one.
  Frame base = base_frame(m, c);
  for (const Rot& t : before_first) base = base.turned(t.axis, t.angle);
  if (!identically_zero(between.offset[a1])) base = base.translated(between.offset[a1] * unit(j1.axis));
  const Mat3 M = product(after_second) * product(c.fixed[2].turns);
  const Vec3 p = between.offset[a2] * unit(j2.axis) + product(after_second) * c.fixed[2].offset;  // P to the third joint
  const Vec3 t = c.fixed[3].offset;                                                                  // the third joint to the point

  Solve solve;
  solve.pattern = "point3";
  const SolvedJoint q1 = joint_symbols(m, j1.coordinate), q2 = joint_symbols(m, j2.coordinate), q3 = joint_symbols(m, j3.coordinate);
  solve.joints = {q1, q2, q3};
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

  // Stage 0: the target seen from the meeting point; |d|^2 = K + A cos q3 + B sin q3.
  Stage s0;
  const realsymbol d[3] = {realsymbol("ik_d0"), realsymbol("ik_d1"), realsymbol("ik_d2")};
  for (int i = 0; i < 3; ++i) {
    ex di = 0;
    for (int k = 0; k < 3; ++k)
      di += base.R(k, i) * (m.coordinates[static_cast<std::size_t>(target[static_cast<std::size_t>(k)])].q - base.r[k]);
    s0.locals.emplace_back(d[i], di);
  }
  const Sinusoid distance = distance_squared(p, M, j3, t);
  const realsymbol K_("ik_K"), A_("ik_A"), B_("ik_B");
  s0.locals.emplace_back(K_, distance.c);
  s0.locals.emplace_back(A_, distance.a);
  s0.locals.emplace_back(B_, distance.b);
  s0.code = fmt::format(
      "  const Scalar ik_dd = ik_d0 * ik_d0 + ik_d1 * ik_d1 + ik_d2 * ik_d2;\n"
      "  Scalar {0}, {1};\n"
      "  if (!ik_solve_cos_sin(ik_A, ik_B, ik_dd - ik_K, (branch & 1) != 0, {0}, {1})) {{\n"
      "    const Scalar ik_R = std::sqrt(ik_A * ik_A + ik_B * ik_B);\n"
      "    why = {{1, std::sqrt(ik_dd), std::sqrt(std::max(Scalar(0), ik_K - ik_R)), std::sqrt(ik_K + ik_R), 0.0}};\n"
      "    return IkStatus::out_of_reach;\n"
      "  }}\n",
      q3.c.get_name(), q3.s.get_name());
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

Solve plan_wheel_leg(const Model& m, const Limb& limb) {
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const auto [frame, target] = point_rows(m, limb, "wheel leg");
  const NamedFrame& placed = m.frames[static_cast<std::size_t>(m.frame_index(frame))];
  const NonholonomicWheel* wheel = placed.derived_from_wheel >= 0 ? &m.wheels[static_cast<std::size_t>(placed.derived_from_wheel)] : nullptr;
  const std::string pattern = wheel ? "wheel leg" : "plane leg";
  const std::string point = wheel ? wheel->hub : frame;
  const CanonicalChain c = canonical_chain(m, full_chain(m, point));
  require_three_joints(m, c, point, pattern);
  const ChainStep &j1 = c.joints[0], &j2 = c.joints[1], &j3 = c.joints[2];
  const std::string n1 = name(j1.coordinate), n2 = name(j2.coordinate), n3 = name(j3.coordinate);
  const auto parallel = [](const Vec3& a, const Vec3& b) { return identically_zero(cross(a, b)); };
  if (!parallel(product(c.fixed[2].turns) * unit(j3.axis), unit(j2.axis)))
    throw Unsolvable{pattern + ": the axes of " + n2 + " and " + n3 + " are not parallel (" + describe(m, c.fixed[2]) +
                     " between them); the pattern needs the last two joints about parallel axes (a leg's flexion and knee), "
                     "with turns between them only about that axis"};
  if (wheel && !parallel(product(c.fixed[3].turns) * unit(wheel->axle), unit(j3.axis)))
    throw Unsolvable{pattern + ": the axle of wheel " + wheel->name + " (" + axis_name(wheel->axle) + " of " + wheel->hub +
                     ") is not parallel to the axis of " + n3 + "; the pattern needs the wheel turning in the leg's plane"};
  const Mat3 R1 = product(c.fixed[1].turns);
  const Vec3 normal = R1 * unit(j2.axis);  // the leg plane's normal in the frame after q1
  if (parallel(unit(j1.axis), normal) || std::abs(at_defaults(m, cross(unit(j1.axis), normal)[0])) +
                                                 std::abs(at_defaults(m, cross(unit(j1.axis), normal)[1])) +
                                                 std::abs(at_defaults(m, cross(unit(j1.axis), normal)[2])) < 1e-9)
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

  Solve solve;
  solve.pattern = wheel ? "wheel-leg" : "plane-leg";
  const SolvedJoint s1 = joint_symbols(m, j1.coordinate), s2 = joint_symbols(m, j2.coordinate), s3 = joint_symbols(m, j3.coordinate);
  solve.joints = {s1, s2, s3};
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

  // Stage 0: the target in the frame before q1; (R_1(q1) n) . d = Y.
  const Frame base = base_frame(m, c);
  Stage st0;
  const realsymbol d[3] = {realsymbol("ik_d0"), realsymbol("ik_d1"), realsymbol("ik_d2")};
  for (int i = 0; i < 3; ++i) {
    ex di = 0;
    for (int k = 0; k < 3; ++k)
      di += base.R(k, i) * (m.coordinates[static_cast<std::size_t>(target[static_cast<std::size_t>(k)])].q - base.r[k]);
    st0.locals.emplace_back(d[i], di);
  }
  const realsymbol& q1 = m.coordinates[static_cast<std::size_t>(j1.coordinate)].q;
  const Mat3 turn1 = signed_rot(j1.axis, j1.sign, q1);
  const Sinusoid first = sinusoid(dot(turn1 * normal, Vec3(d[0], d[1], d[2])).expand(), q1, "the leg plane's offset");
  st0.locals.emplace_back(realsymbol("ik_alpha"), first.a);
  st0.locals.emplace_back(realsymbol("ik_beta"), first.b);
  st0.locals.emplace_back(realsymbol("ik_gamma"), (plane - first.c).expand());
  st0.code = fmt::format(
      "  Scalar {0}, {1};\n"
      "  if (!ik_solve_cos_sin(ik_alpha, ik_beta, ik_gamma, (branch & 1) != 0, {0}, {1})) {{\n"
      "    why = {{1, double(std::abs(ik_gamma)), 0.0, double(std::sqrt(ik_alpha * ik_alpha + ik_beta * ik_beta)), 0.0}};\n"
      "    return IkStatus::out_of_reach;\n"
      "  }}\n",
      s1.c.get_name(), s1.s.get_name());
  st0.defines = {s1.c.get_name(), s1.s.get_name()};
  solve.stages.push_back(st0);

  // Stage 1 (a wheel): the axle in K0, the rim's upward direction u, the hub at the target + r u.
  Vec3 hub_target(d[0], d[1], d[2]);
  if (wheel) {
    Stage st1;
    const Vec3 axle = base.R * (turn1 * normal);
    const realsymbol a[3] = {realsymbol("ik_a0"), realsymbol("ik_a1"), realsymbol("ik_a2")};
    for (int i = 0; i < 3; ++i) st1.locals.emplace_back(a[i], in_results(m, axle[i], solve));
    st1.code =
        "  const Scalar ik_tilt2 = (1 - ik_a2) * (1 + ik_a2);  // |e_z - a_z a|^2\n"
        "  if (!(ik_tilt2 > std::numeric_limits<Scalar>::epsilon())) {\n"
        "    why = {1, 0.0, 0.0, 0.0, 0.0};\n"
        "    return IkStatus::out_of_reach;\n"
        "  }\n"
        "  const Scalar ik_tilt = std::sqrt(ik_tilt2);\n"
        "  const Scalar ik_u0 = -ik_a2 * ik_a0 / ik_tilt, ik_u1 = -ik_a2 * ik_a1 / ik_tilt, ik_u2 = ik_tilt;\n";
    st1.defines = {"ik_u0", "ik_u1", "ik_u2"};
    solve.stages.push_back(st1);
    const ex r = m.parameter(wheel->radius).symbol;
    const Vec3 up(realsymbol("ik_u0"), realsymbol("ik_u1"), realsymbol("ik_u2"));
    Vec3 up_base;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) up_base[i] += base.R(k, i) * up[k];
    hub_target = hub_target + r * up_base;
  }

  // Stage 2: the hub (point) from the second joint's origin, in the frame before q2; its distance
  // fixes q3: |p2 + R2 R_3(q3) p3|^2 = |w|^2.
  Stage st2;
  Vec3 w_expr = signed_rot(j1.axis, -j1.sign, q1) * hub_target - p1;
  Vec3 w_local;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) w_local[i] += R1(k, i) * w_expr[k];
  const realsymbol w[3] = {realsymbol("ik_w0"), realsymbol("ik_w1"), realsymbol("ik_w2")};
  for (int i = 0; i < 3; ++i) st2.locals.emplace_back(w[i], in_results(m, w_local[i], solve));
  const Sinusoid distance = distance_squared(p2, R2, j3, p3);
  st2.locals.emplace_back(realsymbol("ik_K"), distance.c);
  st2.locals.emplace_back(realsymbol("ik_A"), distance.a);
  st2.locals.emplace_back(realsymbol("ik_B"), distance.b);
  st2.code = fmt::format(
      "  const Scalar ik_ww = ik_w0 * ik_w0 + ik_w1 * ik_w1 + ik_w2 * ik_w2;\n"
      "  Scalar {0}, {1};\n"
      "  if (!ik_solve_cos_sin(ik_A, ik_B, ik_ww - ik_K, (branch & 2) != 0, {0}, {1})) {{\n"
      "    const Scalar ik_R = std::sqrt(ik_A * ik_A + ik_B * ik_B);\n"
      "    why = {{2, std::sqrt(ik_ww), std::sqrt(std::max(Scalar(0), ik_K - ik_R)), std::sqrt(ik_K + ik_R), 0.0}};\n"
      "    return IkStatus::out_of_reach;\n"
      "  }}\n",
      s3.c.get_name(), s3.s.get_name());
  st2.defines = {s3.c.get_name(), s3.s.get_name()};
  solve.stages.push_back(st2);

  // Stage 3: v = p2 + R2 R_3(q3) p3; the rotation about the plane's normal that takes v onto w.
  Stage st3;
  const Vec3 v = p2 + R2 * (signed_rot(j3.axis, j3.sign, q3) * p3);
  const int b = static_cast<int>(j2.axis), i = (b + 1) % 3, j = (b + 2) % 3;  // R_b turns i towards j
  for (int k : {i, j}) st3.locals.emplace_back(realsymbol(fmt::format("ik_v{}", k)), in_results(m, v[k], solve));  // v_b = w_b
  st3.code = fmt::format(
      "  const Scalar ik_x = ik_v{0} * ik_w{0} + ik_v{1} * ik_w{1}, ik_y = ik_v{0} * ik_w{1} - ik_v{1} * ik_w{0};\n"
      "  const Scalar ik_r = std::sqrt(ik_x * ik_x + ik_y * ik_y);\n"
      "  Scalar {2} = ik_r > 0 ? ik_x / ik_r : Scalar(1), {3} = ik_r > 0 ? ik_y / ik_r : Scalar(0);\n",
      i, j, s2.c.get_name(), s2.s.get_name()) +
      unsign(j2, s2);
  st3.defines = {s2.c.get_name(), s2.s.get_name()};
  solve.stages.push_back(st3);
  return solve;
}

// ---- leveled lever ------------------------------------------------------------------------------

Solve plan_lever(const Model& m, const Limb& limb) {
  using K = ClosureCondition::Kind;
  const auto name = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  const ClosureCondition* point = nullptr;
  std::vector<const ClosureCondition*> level;
  Solve solve;
  solve.pattern = "leveled-lever";
  std::set<int> remaining(limb.joints.begin(), limb.joints.end());
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
      solve.coupled.emplace_back(unknown, -others);
      remaining.erase(unknown);
    }
  }
  if (point == nullptr || level.size() != 2) throw Unsolvable{"leveled lever needs one point row and two level rows"};
  const std::string frame = point->frame;
  for (const auto* l : level)
    if (l->frame != frame) throw Unsolvable{"leveled lever: the level rows and the point row are on different frames"};
  if (level[0]->axis == level[1]->axis) throw Unsolvable{"leveled lever: both level rows keep the same axis level"};
  if (remaining.size() != 3) throw Unsolvable{"leveled lever: three joints must remain after the couplings"};
  const Axis vertical = static_cast<Axis>(3 - static_cast<int>(level[0]->axis) - static_cast<int>(level[1]->axis));

  require_plain_chain(m, frame, {}, "leveled lever");
  const std::vector<ChainStep> chain = full_chain(m, frame);
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
  Frame base = Frame::ground();
  for (std::size_t i = 0; i < first; ++i) base = apply(m, base, chain[i]);

  // Orientation from the first dependent joint on, couplings substituted.
  const auto angle_of = [&](const ChainStep& st) -> ex {
    if (st.kind == ChainStep::Kind::Turn) return st.angle;
    for (const auto& [k, value] : solve.coupled)
      if (k == st.coordinate) return value;
    return m.coordinates[static_cast<std::size_t>(st.coordinate)].q;
  };
  std::vector<Rot> rotations;
  for (std::size_t i = first; i < chain.size(); ++i)
    if (chain[i].kind == ChainStep::Kind::Rotate || chain[i].kind == ChainStep::Kind::Turn) rotations.push_back({chain[i].axis, angle_of(chain[i])});
  const std::vector<Rot> merged = merge(rotations);
  const auto unknowns_in = [&](const ex& e) {
    std::vector<int> out;
    for (int k : remaining)
      if (e.has(m.coordinates[static_cast<std::size_t>(k)].q)) out.push_back(k);
    return out;
  };
  if (merged.size() < 2) throw Unsolvable{"leveled lever: the orientation does not reduce to two rotations"};
  const Rot& ra = merged[merged.size() - 2];
  const Rot& rb = merged.back();
  const std::vector<int> in_a = unknowns_in(ra.angle), in_b = unknowns_in(rb.angle);
  for (std::size_t i = 0; i + 2 < merged.size(); ++i)
    if (!unknowns_in(merged[i].angle).empty())
      throw Unsolvable{"leveled lever: the orientation does not reduce to R_pre R_a(q_p + q_q) R_b(q_b)"};
  if (in_b.size() != 1 || !(rb.angle - m.coordinates[static_cast<std::size_t>(in_b[0])].q).is_zero())
    throw Unsolvable{"leveled lever: the last rotation is not one joint alone"};
  if (in_a.size() != 2) throw Unsolvable{"leveled lever: the second-to-last rotation is not the sum of two joints"};
  if (!(ra.angle - m.coordinates[static_cast<std::size_t>(in_a[0])].q - m.coordinates[static_cast<std::size_t>(in_a[1])].q).expand().is_zero())
    throw Unsolvable{"leveled lever: the second-to-last rotation is not exactly the sum of two joints"};
  if (ra.axis == vertical || rb.axis == vertical)
    throw Unsolvable{"leveled lever: the two rotations must turn about the axes that the level rows keep level"};
  // q_p: the one of the two whose step comes first along the chain (it moves the lever's point).
  int qp = in_a[0], qq = in_a[1];
  for (std::size_t i = first; i < chain.size(); ++i)
    if (driven(chain[i]) && (chain[i].coordinate == in_a[0] || chain[i].coordinate == in_a[1])) {
      qp = chain[i].coordinate;
      qq = qp == in_a[0] ? in_a[1] : in_a[0];
      break;
    }
  const int qb = in_b[0];
  const ex qp_sym = m.coordinates[static_cast<std::size_t>(qp)].q, qq_sym = m.coordinates[static_cast<std::size_t>(qq)].q;
  const SolvedJoint Jp = joint_symbols(m, qp), Jq = joint_symbols(m, qq), Jb = joint_symbols(m, qb);
  const SolvedJoint sigma{-1, realsymbol("ik_q_sum"), realsymbol("ik_c_sum"), realsymbol("ik_s_sum")};  // q unused
  std::vector<Rot> pre(merged.begin(), merged.end() - 2);
  const Mat3 up_frame = base.R * product(pre);

  const std::string np = name(qp), nq = name(qq), nb = name(qb), target = name(point->target);
  std::string coupled_names;
  for (const auto& [k, value] : solve.coupled) coupled_names += (coupled_names.empty() ? "" : ", ") + name(k);
  solve.summary = fmt::format("leveled lever: {} level by {} + {} ({}) and {} ({}), {}_{} = {} by {}; coupled: {}", frame, np, nq,
                              axis_name(ra.axis), nb, axis_name(rb.axis), frame, axis_name(point->axis), target, np,
                              coupled_names.empty() ? "none" : coupled_names);
  solve.doc = {
      fmt::format("Pattern leveled lever: {} fixed by the sum rows; {}'s {} axis vertical (its other axes level)", coupled_names,
                  frame, axis_name(vertical)),
      fmt::format("through the rotations about {} by {} + {} and about {} by {}; then {}'s {} = {} by {}.", axis_name(ra.axis), np,
                  nq, axis_name(rb.axis), nb, frame, axis_name(point->axis), target, np)};
  solve.branches = 8;
  solve.bits = {fmt::format("bit 0: the other root of {} (branch 0: the root nearest zero)", np),
                fmt::format("bit 1: the other root of {} (branch 0: |{}| <= 90 deg)", nb, nb),
                fmt::format("bit 2: the other root of {} + {} (branch 0: nearest zero)", np, nq)};
  std::string inputs;
  {
    std::set<int> in;
    for (const auto& st : chain)
      if (driven(st) && st.coordinate < m.input_count) in.insert(st.coordinate);
    for (const auto& [k, value] : solve.coupled)
      for (const auto& kv : m.coordinates)
        if (value.has(kv.q)) in.insert(kv.index);
    for (int k : in) inputs += (inputs.empty() ? "" : ", ") + name(k);
  }
  solve.failures = {fmt::format("{} = {{value:.4f}} m is out of reach: with {} as given, the {} of {} reaches [{{low:.4f}}, "
                                "{{high:.4f}}] m",
                                target, inputs, axis_name(point->axis), frame)};

  // Stage 0: the coupled joints; world up seen from the frame before the two rotations; solve them.
  Stage s0;
  for (const auto& [k, value] : solve.coupled) s0.locals.emplace_back(joint_symbols(m, k).q, value);
  const realsymbol g[3] = {realsymbol("ik_g0"), realsymbol("ik_g1"), realsymbol("ik_g2")};
  for (int i = 0; i < 3; ++i) s0.locals.emplace_back(g[i], up_frame(2, i));
  const std::string unit = fmt::format("{{{}, {}, {}}}", vertical == Axis::X ? "Scalar(1)" : "Scalar(0)",
                                       vertical == Axis::Y ? "Scalar(1)" : "Scalar(0)", vertical == Axis::Z ? "Scalar(1)" : "Scalar(0)");
  s0.code = "  const Scalar ik_axis[3] = " + unit + ";\n  const Scalar ik_g[3] = {ik_g0, ik_g1, ik_g2};\n" +
            two_axis_call(ra.axis, rb.axis, "ik_axis", "ik_g", "(branch & 2) != 0", sigma, Jb) +
            fmt::format(
                "  static_cast<void>(ik_two_axis_ok);  // cannot fail: the axis is perpendicular to both rotations\n"
                "  // The sum's other root: a half turn, with the last joint mirrored (the vertical axis flips).\n"
                "  if ((ik_c_sum < 0) != ((branch & 4) != 0)) {{\n"
                "    ik_c_sum = -ik_c_sum;\n    ik_s_sum = -ik_s_sum;\n"
                "    {0} = -{0};\n  }}\n",
                Jb.s.get_name());
  s0.defines = {"ik_c_sum", "ik_s_sum", Jb.c.get_name(), Jb.s.get_name()};
  solve.stages.push_back(s0);

  // Stage 1: the point row, with q_q = sum - q_p: a cos q_p + b sin q_p + c.
  const realsymbol sum_sym("ik_sum");
  Vec3 pos;
  std::vector<Rot> prefix;
  for (std::size_t i = first; i < chain.size(); ++i) {
    const ChainStep& st = chain[i];
    if (st.kind == ChainStep::Kind::Translate) {
      pos = pos + product(merge(prefix)) * st.offset;
    } else {
      ex a = angle_of(st);
      a = a.subs(qq_sym == sum_sym - qp_sym);
      prefix.push_back({st.axis, a});
    }
  }
  const int k = static_cast<int>(point->axis);
  ex height = base.r[k];
  for (int j = 0; j < 3; ++j) height += base.R(k, j) * pos[j];
  const Sinusoid row = sinusoid(height, GiNaC::ex_to<realsymbol>(qp_sym), "the point row");
  Solve with_sum = solve;  // sin, cos of the sum and of q_b by their computed values
  with_sum.joints = {Jb};
  const auto results = [&](const ex& e) {
    return in_results(m, e, with_sum).subs(GiNaC::lst{GiNaC::sin(sum_sym) == sigma.s, GiNaC::cos(sum_sym) == sigma.c});
  };
  Stage s1;
  s1.locals = {{realsymbol("ik_alpha"), results(row.a)}, {realsymbol("ik_beta"), results(row.b)}, {realsymbol("ik_gamma"), results(row.c)}};
  s1.code = fmt::format(
      "  Scalar {0}, {1};\n"
      "  if (!ik_solve_cos_sin(ik_alpha, ik_beta, {2} - ik_gamma, (branch & 1) != 0, {0}, {1})) {{\n"
      "    const Scalar ik_R = std::sqrt(ik_alpha * ik_alpha + ik_beta * ik_beta);\n"
      "    why = {{1, {2}, ik_gamma - ik_R, ik_gamma + ik_R, 0.0}};\n"
      "    return IkStatus::out_of_reach;\n"
      "  }}\n"
      "  const Scalar {3} = ik_c_sum * {0} + ik_s_sum * {1};\n"
      "  const Scalar {4} = ik_s_sum * {0} - ik_c_sum * {1};\n",
      Jp.c.get_name(), Jp.s.get_name(), target, Jq.c.get_name(), Jq.s.get_name());
  s1.defines = {Jp.c.get_name(), Jp.s.get_name(), Jq.c.get_name(), Jq.s.get_name()};
  solve.stages.push_back(s1);
  solve.joints = {Jp, Jq, Jb};
  return solve;
}

// ---- emission -----------------------------------------------------------------------------------

struct EmittedSolve {
  std::string text;
  OpCount ops;
};

// The joint angles from their cosines and sines in one batched atan2 pass (trig.hpp), after every
// solver stage: the stages themselves work with cosines and sines only (libm's atan2, one call per
// joint, was over half of a four-limb solve).
Stage angle_stage(const std::vector<Stage>& before, const std::vector<SolvedJoint>& joints) {
  for (const Stage& st : before)
    for (const auto& [sym, value] : st.locals)
      for (const SolvedJoint& j : joints)
        if (value.has(j.q))
          throw std::logic_error("wlx-gen: " + sym.get_name() + " uses the angle " + j.q.get_name() +
                                 " before the batched atan2 computes it");
  std::vector<std::string> sines, cosines;
  for (const SolvedJoint& j : joints) {
    sines.push_back(j.s.get_name());
    cosines.push_back(j.c.get_name());
  }
  Stage st;
  st.code = fmt::format("  const std::array<Scalar, {0}> ik_sines{{{{{1}}}}}, ik_cosines{{{{{2}}}}};\n"
                        "  std::array<Scalar, {0}> ik_angles;\n"
                        "  atan2(ik_sines, ik_cosines, ik_angles);\n",
                        joints.size(), fmt::join(sines, ", "), fmt::join(cosines, ", "));
  for (std::size_t i = 0; i < joints.size(); ++i) {
    st.code += fmt::format("  const Scalar {} = ik_angles[{}];\n", joints[i].q.get_name(), i);
    st.defines.push_back(joints[i].q.get_name());
  }
  return st;
}

// The last stage of a limb's solve: its own closure rows at the solution, and the check.
Stage check_stage(const Model& m, const Limb& limb, const Solve& solve) {
  Stage check;
  std::vector<std::string> rows;
  for (std::size_t i = 0; i < limb.rows.size(); ++i) {
    const realsymbol r(fmt::format("ik_row{}", i));
    check.locals.emplace_back(r, in_results(m, closure_value(m, m.closure[static_cast<std::size_t>(limb.rows[i])]), solve));
    rows.push_back(fmt::format("std::abs({})", r.get_name()));
  }
  check.code = fmt::format(
      "  const Scalar ik_residual = std::max({{{}}});\n"
      "  if (!(ik_residual <= ik_tolerance<Scalar>())) {{\n"
      "    why = {{0, ik_residual, 0.0, ik_tolerance<Scalar>(), 0.0}};\n"
      "    return IkStatus::residual;\n"
      "  }}\n",
      fmt::join(rows, ", "));
  return check;
}

// The statements of a solve: input aliases, the batched sines and cosines, then every stage's
// temporaries, values and solver calls, then the outputs. One graph for all stages, so that
// temporaries are shared (across limbs, too, when several are fused) and placed in the first stage
// where everything they use exists.
std::string emit_body(const Model& m, const std::vector<Stage>& stages, const std::vector<std::pair<int, std::string>>& outputs,
                      const EmitOptions& opt, OpCount& ops) {
  ExprGraph g;
  std::map<std::string, int> symbol_stage;
  std::vector<std::vector<std::pair<std::string, int>>> locals(stages.size());
  std::vector<int> roots;
  for (std::size_t k = 0; k < stages.size(); ++k)
    for (const auto& [sym, value] : stages[k].locals) {
      const int id = g.add(value);
      locals[k].emplace_back(sym.get_name(), id);
      roots.push_back(id);
    }
  // What a stage defines (its locals, its solvers' results) is usable from the next stage on.
  for (std::size_t k = 0; k < stages.size(); ++k) {
    for (const auto& [sym, value] : stages[k].locals) symbol_stage[sym.get_name()] = static_cast<int>(k) + 1;
    for (const auto& n : stages[k].defines) symbol_stage[n] = static_cast<int>(k) + 1;
  }
  const CsePlan plan = eliminate_common_subexpressions(g, roots);
  const TrigBatch trig = batch_trig(m, g, roots);
  std::map<int, int> node_stage;
  std::function<int(int)> stage_of = [&](int id) -> int {
    if (auto it = node_stage.find(id); it != node_stage.end()) return it->second;
    const Node& n = g.node(id);
    int st = 0;
    if (n.kind == NodeKind::Symbol) {
      if (auto it = symbol_stage.find(n.text); it != symbol_stage.end()) st = it->second;
    }
    for (int a : n.args) st = std::max(st, stage_of(a));
    node_stage[id] = st;
    return st;
  };
  Printer pr(g, plan, trig.names, "ik_t");
  ops.calls += trig.calls;
  std::set<std::string> symbols;
  std::function<void(int)> collect = [&](int id) {
    const Node& n = g.node(id);
    if (n.kind == NodeKind::Symbol) symbols.insert(n.text);
    for (int a : n.args) collect(a);
  };
  for (int r : roots) collect(r);

  std::string body;
  body += coordinate_aliases(m, symbols) + parameter_aliases(m, symbols, opt);
  body += trig.prologue;
  const auto batched = [&](std::size_t k) { return trig.names.count(plan.temporaries[k]) != 0; };
  for (std::size_t k = 0; k < stages.size(); ++k) {
    for (std::size_t t = 0; t < plan.temporaries.size(); ++t)
      if (!batched(t) && stage_of(plan.temporaries[t]) == static_cast<int>(k))
        body += fmt::format("  const Scalar ik_t{} = {};\n", t, pr.define(plan.temporaries[t], ops));
    for (const auto& [n, id] : locals[k]) body += fmt::format("  const Scalar {} = {};\n", n, pr.value(id, ops));
    body += stages[k].code;
  }
  for (const auto& [k, name] : outputs) body += fmt::format("  out({}) = {};\n", k, name);
  return using_declarations(pr.calls()) + body + "  return IkStatus::ok;\n";
}

std::vector<std::pair<int, std::string>> solve_outputs(const Model& m, const Solve& solve) {
  std::vector<std::pair<int, std::string>> out;
  for (const SolvedJoint& j : solve.joints) out.emplace_back(j.coordinate, j.q.get_name());
  for (const auto& [k, value] : solve.coupled) out.emplace_back(k, joint_symbols(m, k).q.get_name());
  return out;
}

// One limb's stages (check included) with their local names made the limb's own (ik_<tag>_...),
// its branch read from `ik_<tag>_branch`, and a failure reporting `failed = index`: for fusing
// several limbs into one function. The solved joints keep their names (they are distinct already).
std::vector<Stage> fused_stages(const Model& m, const std::vector<Stage>& stages, const std::string& tag, int index) {
  std::set<std::string> keep = {"ik_solve_cos_sin", "ik_solve_two_axis", "ik_tolerance", "ik_reach_slack"};
  for (const auto& c : m.coordinates)
    for (const char* k : {"ik_q_", "ik_c_", "ik_s_"}) keep.insert(k + c.name);
  const auto renamed = [&](const std::string& name) { return keep.count(name) ? name : "ik_" + tag + "_" + name.substr(3); };
  const std::regex local(R"(\bik_[A-Za-z0-9_]+)"), branch(R"(\bbranch\b)");
  GiNaC::exmap symbols;
  const auto rename_symbols = [&](const ex& e) {
    for (GiNaC::const_preorder_iterator it = e.preorder_begin(); it != e.preorder_end(); ++it)
      if (GiNaC::is_a<GiNaC::symbol>(*it)) {
        const std::string n = GiNaC::ex_to<GiNaC::symbol>(*it).get_name();
        if (n.rfind("ik_", 0) == 0 && renamed(n) != n && !symbols.count(*it)) symbols[*it] = realsymbol(renamed(n));
      }
  };
  for (const Stage& st : stages)
    for (const auto& [sym, value] : st.locals) {
      rename_symbols(sym);
      rename_symbols(value);
    }
  std::vector<Stage> out;
  for (const Stage& st : stages) {
    Stage r;
    for (const auto& [sym, value] : st.locals)
      r.locals.emplace_back(GiNaC::ex_to<realsymbol>(symbols.count(sym) ? symbols[sym] : ex(sym)), value.subs(symbols));
    std::string code;
    std::sregex_iterator it(st.code.begin(), st.code.end(), local), end;
    std::size_t at = 0;
    for (; it != end; ++it) {
      code += st.code.substr(at, static_cast<std::size_t>(it->position()) - at) + renamed(it->str());
      at = static_cast<std::size_t>(it->position() + it->length());
    }
    code += st.code.substr(at);
    code = std::regex_replace(code, branch, "ik_" + tag + "_branch");
    r.code = std::regex_replace(code, std::regex(R"(return IkStatus::)"), fmt::format("failed = {};\n    return IkStatus::", index));
    for (const auto& n : st.defines) r.defines.push_back(renamed(n));
    out.push_back(std::move(r));
  }
  return out;
}

EmittedSolve emit_solve(const Model& m, const Limb& limb, Solve solve, const EmitOptions& opt) {
  std::vector<Stage> stages = solve.stages;
  stages.push_back(angle_stage(stages, solve.joints));
  stages.push_back(check_stage(m, limb, solve));
  OpCount ops;
  const std::string body = emit_body(m, stages, solve_outputs(m, solve), opt, ops);

  std::string t = fmt::format("// Closed-form inverse kinematics of limb {} ({}).\n//\n", limb.name, comment(limb.title));
  for (const auto& line : solve.doc) t += "// " + line + "\n";
  t += fmt::format("// Branches 0 to {}:\n", solve.branches - 1);
  for (const auto& b : solve.bits) t += "//   " + b + "\n";
  t += "// Writes the limb's joints (";
  std::vector<std::string> outs;
  for (int j : limb.joints) outs.push_back(m.coordinates[static_cast<std::size_t>(j)].name);
  t += fmt::format("{}) into out, which may be s itself; reads only the limb's inputs.\n", fmt::join(outs, ", "));
  t += "// On failure returns why, with the numbers in `why` (stage 1.. as in kClosedForm's failure texts;\n"
       "// stage 0: residual, the solution does not satisfy the closure rows).\n";
  t += fmt::format("// Operations: {} (adds {}, muls {}, divs {}, calls {}), plus the solver calls.\n", ops.total(), ops.adds,
                   ops.muls, ops.divs, ops.calls);
  t += "// Scalar: float or double (the branch choices and the reach diagnostics need real numbers).\n";
  t += fmt::format("template <typename Scalar>\n"
                   "inline IkStatus ik_{}(const CoordinatesOf<Scalar>& s, const Params& p, int branch, "
                   "detail::NonDeduced<CoordinatesOf<Scalar>>& out, IkDiagnostics& why) noexcept {{\n"
                   "  static_assert(std::is_floating_point_v<Scalar>, \"the closed-form IK is for float and double\");\n",
                   limb.name);
  t += fmt::format("  static_cast<void>(p);\n  if (branch < 0 || branch >= {}) return IkStatus::bad_branch;\n", solve.branches);
  t += body + "}\n\n";
  return {t, ops};
}

const char* kSupport = R"(// Why a closed-form solve gave no solution.
enum class IkStatus {
  ok = 0,
  out_of_reach,  // the target cannot be reached (why: stage, the target's value, the reachable range)
  bad_branch,    // no such branch
  residual,      // the solution does not satisfy the limb's closure rows (why.value: the residual)
};

struct IkDiagnostics {
  int stage = 0;      // which equation failed (the limb's failure texts, 1-based); 0: the residual check
  double value = 0;   // what the target asks for
  double low = 0;     // the reachable range
  double high = 0;
  double aux = 0;     // a joint angle that the range depends on, in degrees
};

// Targets this close outside the reach (relative) are rounding, not user error: they are clamped
// onto the boundary. For double; ik_reach_slack<Scalar>() scales it with the type's epsilon.
inline constexpr double kIkReachSlack = 1e-12;
// A closed-form solution must satisfy the limb's closure rows to this (m or rad); rounding leaves
// about 1e-15. For double; see ik_tolerance<Scalar>() for float.
inline constexpr double kIkTolerance = 1e-9;

// The two for scalar type Scalar. The slack is about 4500 rounding units, so it scales with the
// type's epsilon (float: 5.4e-4). The tolerance has to stay clear of rounding (n eps times the
// chain's length) and far below what a wrong solution leaves (millimetres and more); it scales
// with the square root of the epsilon ratio (float: 2.3e-5 m, where rounding leaves about 1e-6).
template <typename Scalar>
inline Scalar ik_reach_slack() noexcept {
  return Scalar(kIkReachSlack * (double(std::numeric_limits<Scalar>::epsilon()) / std::numeric_limits<double>::epsilon()));
}
template <typename Scalar>
inline Scalar ik_tolerance() noexcept {
  return Scalar(kIkTolerance * std::sqrt(double(std::numeric_limits<Scalar>::epsilon()) / std::numeric_limits<double>::epsilon()));
}

// cos x and sin x of the x with a cos x + b sin x = c: the root nearest zero (largest cos x; on a tie
// the positive one), or the other root with `other`. False when |c| exceeds sqrt(a^2 + b^2). The
// angles themselves come from one batched atan2 pass at the end of a solve.
template <typename Scalar>
inline bool ik_solve_cos_sin(Scalar a, Scalar b, Scalar c, bool other, Scalar& cos_x, Scalar& sin_x) noexcept {
  // sqrt, not std::hypot (several times slower): a and b are lengths or products of unit vectors
  // and lengths, nowhere near overflow.
  const Scalar r = std::sqrt(a * a + b * b);
  if (!(r > 0)) {
    // The joint does not move what it solves for: the reachable range is the one value c = 0
    // (reported as [v, v]), where every x solves; x = 0 is the root nearest zero.
    if (!(std::abs(c) <= ik_reach_slack<Scalar>())) return false;
    cos_x = 1;
    sin_x = 0;
    return true;
  }
  Scalar ratio = c / r;
  if (!(std::abs(ratio) <= 1)) {
    if (!(std::abs(ratio) <= 1 + ik_reach_slack<Scalar>())) return false;
    ratio = std::copysign(Scalar(1), ratio);
  }
  const Scalar cos_psi = a / r, sin_psi = b / r;  // x = psi +- delta
  const Scalar sin_delta = std::sqrt((1 - ratio) * (1 + ratio));
  Scalar sign = sin_psi > 0 ? Scalar(-1) : sin_psi < 0 ? Scalar(1) : (cos_psi >= 0 ? Scalar(1) : Scalar(-1));
  if (other) sign = -sign;
  cos_x = cos_psi * ratio - sign * sin_psi * sin_delta;
  sin_x = sin_psi * ratio + sign * cos_psi * sin_delta;
  return true;
}

// cos and sin of q1, q2 with R_A(q1) R_B(q2) v = d, for principal axes A != B (0 x, 1 y, 2 z) and |v| = |d|:
// the component of d along A fixes q2 (two roots: `flip` takes the one with cos q2 of the other sign
// than branch 0's), then q1 turns R_B(q2) v onto d. False (with how far d is off the plane normal to
// A, and how far it could be) when no q2 reaches d's component along A.
template <int A, int B, typename Scalar>
inline bool ik_solve_two_axis(const Scalar (&v)[3], const Scalar (&d)[3], bool flip, Scalar& c1, Scalar& s1, Scalar& c2,
                              Scalar& s2, Scalar& beside, Scalar& room) noexcept {
  static_assert(A != B && A >= 0 && A < 3 && B >= 0 && B < 3, "two different principal axes");
  constexpr int C = 3 - A - B;
  constexpr int i = (B + 1) % 3, j = (B + 2) % 3;    // R_B turns i towards j
  constexpr int i1 = (A + 1) % 3, j1 = (A + 2) % 3;  // R_A turns i1 towards j1
  const Scalar across = d[i1] * d[i1] + d[j1] * d[j1];  // |d|^2 off the axis A
  Scalar k2 = across - v[B] * v[B];
  if (k2 < 0) {
    if (-k2 > ik_reach_slack<Scalar>() * (across + v[B] * v[B])) {
      beside = std::abs(d[A]);
      room = std::sqrt(v[A] * v[A] + v[C] * v[C]);
      return false;
    }
    k2 = 0;
  }
  Scalar k = std::sqrt(k2);
  if ((v[C] < 0) != flip) k = -k;
  Scalar t[3] = {0, 0, 0};
  t[A] = d[A];
  t[C] = k;
  const Scalar y = v[i] * t[j] - v[j] * t[i], x = v[i] * t[i] + v[j] * t[j];
  const Scalar r = std::sqrt(x * x + y * y);
  c2 = r > 0 ? x / r : Scalar(1);
  s2 = r > 0 ? y / r : Scalar(0);
  Scalar w[3];
  w[B] = v[B];
  w[i] = c2 * v[i] - s2 * v[j];
  w[j] = s2 * v[i] + c2 * v[j];
  const Scalar y1 = w[i1] * d[j1] - w[j1] * d[i1], x1 = w[i1] * d[i1] + w[j1] * d[j1];
  const Scalar r1 = std::sqrt(x1 * x1 + y1 * y1);
  c1 = r1 > 0 ? x1 / r1 : Scalar(1);
  s1 = r1 > 0 ? y1 / r1 : Scalar(0);
  return true;
}

)";

}  // namespace

std::vector<ChainStep> canonical_ik_chain(const Model& m, const std::string& frame) {
  const CanonicalChain c = canonical_chain(m, full_chain(m, frame));
  std::vector<ChainStep> out;
  const auto fixed = [&](const Rigid& r) {
    if (!identically_zero(r.offset)) {
      ChainStep st;
      st.kind = ChainStep::Kind::Translate;
      st.offset = r.offset;
      out.push_back(st);
    }
    for (const Rot& t : r.turns) {
      ChainStep st;
      st.kind = ChainStep::Kind::Turn;
      st.axis = t.axis;
      st.angle = t.angle;
      out.push_back(st);
    }
  };
  for (std::size_t k = 0; k < c.joints.size(); ++k) {
    fixed(c.fixed[k]);
    out.push_back(c.joints[k]);
  }
  fixed(c.fixed.back());
  return out;
}

EmittedFile emit_ik_header(const Model& m, const EmitOptions& opt, std::vector<std::string>& report) {
  std::string t = banner(m, opt, "Closed-form inverse kinematics of the limbs, derived from the model's chains.");
  t += "//\n// Each limb whose chain matches a solvable pattern gets a function ik_<limb>() with all its\n"
       "// branches; kClosedForm lists them (solve == nullptr: no pattern applies, use Newton's method).\n";
  t += "#pragma once\n\n#include <algorithm>\n#include <array>\n#include <cmath>\n#include <limits>\n#include <string_view>\n#include <type_traits>\n\n"
       "#include \"params.hpp\"\n#include \"structure.hpp\"\n#include \"trig.hpp\"\n#include \"types.hpp\"\n\n" +
       namespace_open(opt) + "\n" + kSupport;
  std::vector<std::string> entries;
  std::vector<std::pair<const Limb*, Solve>> solved;
  for (const Limb& limb : m.limbs) {
    std::optional<Solve> solve;
    std::vector<std::string> reasons;
    for (auto plan : {plan_point3, plan_wheel_leg, plan_lever}) {
      try {
        solve = plan(m, limb);
        break;
      } catch (const Unsolvable& u) {
        reasons.push_back(u.reason);
      }
    }
    // A default branch the closed form does not have is the model file's mistake, named there.
    const int branches = solve ? solve->branches : 1;
    if (limb.branch >= branches)
      throw ModelFileError(fmt::format("{}: limb '{}' has {} (0 to {}), not {}{}", limb.branch_place, limb.name,
                                       branches == 1 ? "one branch" : fmt::format("{} branches", branches), branches - 1, limb.branch,
                                       solve ? "" : ": wlx-gen found no closed form for it, and Newton's method has no branches"));
    if (!solve) {
      report.push_back(fmt::format("{}: no closed form ({}); Newton's method at run time", limb.name, fmt::join(reasons, "; ")));
      entries.push_back(fmt::format("    {{nullptr, 0, \"none\", {{}}, {{}}}},  // {}: {}", limb.name, comment(fmt::format("{}", fmt::join(reasons, "; ")))));
      continue;
    }
    const EmittedSolve e = emit_solve(m, limb, *solve, opt);
    t += e.text;
    solved.emplace_back(&limb, *solve);
    report.push_back(fmt::format("{}: {} ({} branches, {} operations)", limb.name, solve->summary, solve->branches, e.ops.total()));
    std::vector<std::string> bits, failures;
    for (const auto& b : solve->bits) bits.push_back("\"" + b + "\"");
    for (const auto& f : solve->failures) failures.push_back("\"" + f + "\"");
    entries.push_back(fmt::format("    {{&ik_{}<double>, {}, \"{}\", {{{{{}}}}}, {{{{{}}}}}}},", limb.name, solve->branches, solve->pattern,
                                  fmt::join(bits, ", "), fmt::join(failures, ", ")));
  }
  t += "using IkFunction = IkStatus (*)(const Coordinates& s, const Params& p, int branch, Coordinates& out,\n"
       "                                IkDiagnostics& why) noexcept;\n\n"
       "struct ClosedFormInfo {\n"
       "  IkFunction solve;  // nullptr: no closed form\n"
       "  int branches;\n"
       "  std::string_view pattern;\n"
       "  std::array<std::string_view, 3> bits;      // what each branch bit selects\n"
       "  std::array<std::string_view, 2> failures;  // message of each failing stage (IkDiagnostics::stage 1, 2),\n"
       "                                             // with {value}, {low}, {high}, {aux} to fill in\n"
       "};\n\n";
  t += fmt::format("// Per limb, in the order of kLimbs.\ninline constexpr std::array<ClosedFormInfo, {}> kClosedForm{{{{\n{}\n}}}};\n\n",
                   m.limbs.size(), fmt::join(entries, "\n"));

  // Every limb with a closed form in one function: one pass of sines and cosines for all input
  // angles, and the subexpressions the limbs share (the body's pose) computed once. Emitted for
  // every model, so that the runtime compiles for any mix: the limbs without a closed form are left
  // to Newton's method (their joints in out are not written).
  const bool all = solved.size() == m.limbs.size();
  t += fmt::format("// Whether every limb has a closed form (ik_all then solves them all).\ninline constexpr bool kHasFusedIk = {};\n\n",
                   all ? "true" : "false");
  {
    // Every limb's solver stages, one atan2 pass for all their joints, then every limb's check.
    std::vector<Stage> stages, checks;
    std::vector<SolvedJoint> joints;
    std::vector<std::pair<int, std::string>> outputs;
    std::string prologue, newton;
    for (std::size_t k = 0; k < solved.size(); ++k) {
      const auto& [limb, solve] = solved[k];
      const int index = static_cast<int>(limb - m.limbs.data());
      for (Stage& st : fused_stages(m, solve.stages, limb->name, index)) stages.push_back(std::move(st));
      for (Stage& st : fused_stages(m, {check_stage(m, *limb, solve)}, limb->name, index)) checks.push_back(std::move(st));
      joints.insert(joints.end(), solve.joints.begin(), solve.joints.end());
      for (const auto& o : solve_outputs(m, solve)) outputs.push_back(o);
      prologue += fmt::format("  const int ik_{0}_branch = branches[{1}];\n"
                              "  if (ik_{0}_branch < 0 || ik_{0}_branch >= {2}) {{\n    failed = {1};\n    return IkStatus::bad_branch;\n  }}\n",
                              limb->name, index, solve.branches);
    }
    for (const Limb& limb : m.limbs)
      if (std::none_of(solved.begin(), solved.end(), [&](const auto& sv) { return sv.first == &limb; }))
        newton += (newton.empty() ? "" : ", ") + limb.name;
    if (!joints.empty()) stages.push_back(angle_stage(stages, joints));
    stages.insert(stages.end(), checks.begin(), checks.end());
    OpCount ops;
    const std::string body = emit_body(m, stages, outputs, opt, ops);
    t += fmt::format(
        "// The closed forms of the {0} limbs that have one{6} in one pass: what ik_<limb>() computes for each,\n"
        "// with the sines and cosines of every input angle and the subexpressions the limbs share computed once.\n"
        "// branches[k] is limb k's branch (kLimbs order). On failure returns the status of the first limb that\n"
        "// failed (every limb's reach is tested before any limb's residual check), `failed` its index and `why`\n"
        "// its numbers; out is written only when every limb succeeded.\n"
        "// Operations: {1} (adds {2}, muls {3}, divs {4}, calls {5}), plus the solver calls.\n"
        "// Scalar: float or double.\n"
        "template <typename Scalar>\n"
        "inline IkStatus ik_all(const CoordinatesOf<Scalar>& s, const Params& p, const std::array<int, {7}>& branches,\n"
        "                       detail::NonDeduced<CoordinatesOf<Scalar>>& out, int& failed, IkDiagnostics& why) noexcept {{\n"
        "  static_assert(std::is_floating_point_v<Scalar>, \"the closed-form IK is for float and double\");\n"
        "  static_cast<void>(s);\n  static_cast<void>(p);\n  static_cast<void>(branches);\n  static_cast<void>(out);\n"
        "  static_cast<void>(failed);\n  static_cast<void>(why);\n",
        solved.size(), ops.total(), ops.adds, ops.muls, ops.divs, ops.calls,
        newton.empty() ? "" : " (not " + newton + ": Newton's method at run time)", m.limbs.size());
    t += prologue + body + "}\n\n";
    t += double_overload(opt, "ik_all", "IkStatus",
                         {{"const Coordinates& s", ""},
                          {"const Params& p", ""},
                          {fmt::format("const std::array<int, {}>& branches", m.limbs.size()), ""},
                          {"Coordinates& out", ""},
                          {"int& failed", ""},
                          {"IkDiagnostics& why", ""}},
                         "what the runtime calls");
    report.push_back(fmt::format("all limbs fused: {} operations", ops.total()));
  }
  t += namespace_close(opt);
  return {"wlx/gen/ik.hpp", t};
}

}  // namespace wlx::codegen
