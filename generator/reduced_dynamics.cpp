// reduced_dynamics: Kane's equations projected onto the commanded speeds, written as code on
// lanes (one per commanded speed) that sums the joints' twists out along the bodies' chains and the
// bodies' wrenches back along them.
#include "derivations_internal.hpp"

#include <fmt/format.h>
#include <wlx/support/text.hpp>

#include <algorithm>
#include <iterator>
#include <map>
#include <set>
#include <stdexcept>

namespace wlx::codegen {

using namespace derivation;

namespace {

// Writes reduced_dynamics' lane code: statements on rows of scalars (detail::Lanes), one lane per
// commanded speed, and counts their operations scalar by scalar, per output (`charge_to`).
// A row is named by its variable, or "" when it is structurally zero (nothing is written for it).
//
// Rows are narrow or wide. A wide row (type LW) holds every commanded speed, lane k for speed k. A
// narrow row (type L) holds only the speeds its set names, speed k in lane slot[k]: speeds that
// never move the same body (the commanded speeds of two legs, say) share a lane, so that a
// machine with many commanded speeds but few per limb runs its limbs' sums on short rows. A row
// is narrow when its speeds' slots are distinct; sums whose speeds collide (the wrenches where the
// limbs meet) are wide, their narrow parts widened first. With no sharing (slot[k] = k) every row
// is narrow and L holds every speed.
class LaneWriter {
 public:
  using Set = std::vector<int>;  // commanded speeds, ascending
  using Terms = std::vector<std::pair<std::string, std::string>>;  // (scalar factor, row)
  LaneWriter(std::vector<int> slot, int width) : slot_(std::move(slot)), width_(width), speeds_(static_cast<int>(slot_.size())) {}
  int charge_to = 0;  // the output the next statements' operations count for
  bool shares_lanes() const { return width_ < speeds_; }
  int width() const { return width_; }
  // A row the caller declares (T's rows): its name and speeds, narrow.
  void declare(const std::string& name, const Set& speeds) { rows_[name] = {speeds, false}; }
  const Set& speeds(const std::string& row) const { return rows_.at(row).speeds; }
  // A new row "name = base + sum_i factor_i * row_i" (zero terms, "" rows, dropped); returns the
  // name, or base itself when no term remains (no code).
  std::string define(const std::string& name, const std::string& base, const Terms& terms) {
    const Terms kept = nonzero(terms);
    if (kept.empty()) return base;
    std::vector<std::string> rows = rows_of(kept);
    if (!base.empty()) rows.insert(rows.begin(), base);
    const Layout layout = unify(rows);
    OpCount ops;
    const std::string rhs = products(base.empty() ? "" : as(base, layout.wide), kept, layout.wide, ops);
    add(name, fmt::format("    const {} {} = {};\n", type(layout.wide), name, rhs), ops);
    rows_[name] = {layout.speeds, layout.wide};
    return name;
  }
  // A new row, the sum of `rows` (at least two).
  std::string define_sum(const std::string& name, const std::vector<std::string>& rows) {
    const Layout layout = unify(rows);
    std::vector<std::string> operands;
    for (const auto& r : rows) operands.push_back(as(r, layout.wide));
    add(name, fmt::format("    const {} {} = {};\n", type(layout.wide), name, fmt::join(operands, " + ")),
        OpCount{static_cast<long>(rows.size() - 1) * lanes(layout.wide), 0, 0, 0});
    rows_[name] = {layout.speeds, layout.wide};
    return name;
  }
  // "accumulator += sum_i factor_i * row_i": into one of the accumulator's parts (one whose
  // speeds, with the terms', keep distinct lanes; else a new part).
  void accumulate(const std::string& accumulator, const Terms& terms) {
    const Terms kept = nonzero(terms);
    if (kept.empty()) return;
    const Part& part = part_for(accumulator, unify(rows_of(kept)));
    OpCount ops{lanes(part.wide), 0, 0, 0};  // the +=
    const std::string rhs = products("", kept, part.wide, ops);
    add("", fmt::format("    {} += {};\n", part.name, rhs), ops);
  }
  // "accumulator += row".
  void add_row(const std::string& accumulator, const std::string& row) {
    const Layout layout = unify({row});
    const Part& part = part_for(accumulator, layout);
    add("", fmt::format("    {} += {};\n", part.name, as(row, part.wide)), OpCount{lanes(part.wide), 0, 0, 0});
  }
  // A new row equal to `base` (or zero) plus `value` for speed k only: a unit row of T.
  std::string plus_lane(const std::string& name, const std::string& base, int k, const std::string& value) {
    Set speeds = base.empty() ? Set{} : rows_.at(base).speeds;
    speeds = merged(speeds, {k});
    const bool wide = (!base.empty() && rows_.at(base).wide) || !distinct(speeds);
    add(name, fmt::format("    {} {} = {};\n    {}.add_to_lane({}, {});\n", type(wide), name, base.empty() ? zero(wide) : as(base, wide),
                          name, wide ? k : slot_[static_cast<std::size_t>(k)], value),
        OpCount{1, 0, 0, 0});
    rows_[name] = {speeds, wide};
    return name;
  }
  // Quoted for a comment (wlx/support/text.hpp): the text may hold a body's meaning from the model file.
  void comment(const std::string& text) { add("", "    // " + text::cpp_comment(text) + "\n", {}); }
  std::string zero(bool wide = false) const { return fmt::format("detail::zero_lanes<Scalar, {}>()", lanes(wide)); }
  std::string type(bool wide) const { return wide ? "LW" : "L"; }
  // The lane of speed k in a row of the given kind.
  int lane(int k, bool wide) const { return wide ? k : slot_[static_cast<std::size_t>(k)]; }

  struct Part {
    std::string name;
    Set speeds;
    bool wide = false;
  };
  // Every accumulator's parts, in the order they were made (the caller declares them, zero).
  const std::map<std::string, std::vector<Part>>& accumulators() const { return accumulators_; }
  // An accumulator nothing was added to gets one narrow part, so the caller's code can name it.
  void ensure(const std::string& accumulator) {
    if (!accumulators_.count(accumulator)) accumulators_[accumulator].push_back({accumulator, {}, false});
  }
  // The code, without the rows nothing reads (a dense joint's wrench sums feed only the
  // components its twist has), and each output's operations.
  std::string finish(std::vector<OpCount>& ops) const {
    // How many kept statements read each named row; dropping a row that none reads can leave its
    // own inputs unread, so this runs until nothing changes.
    std::map<std::string, int> readers;
    std::vector<std::set<std::string>> reads(statements_.size());
    for (std::size_t i = 0; i < statements_.size(); ++i) {
      for (const auto& word : identifiers(statements_[i].text))
        if (word != statements_[i].name) reads[i].insert(word);
      for (const auto& word : reads[i]) ++readers[word];
    }
    std::vector<bool> keep(statements_.size(), true);
    for (bool changed = true; changed;) {
      changed = false;
      for (std::size_t i = 0; i < statements_.size(); ++i) {
        if (!keep[i] || statements_[i].name.empty() || readers[statements_[i].name] > 0) continue;
        keep[i] = false;
        changed = true;
        for (const auto& word : reads[i]) --readers[word];
      }
    }
    std::string code;
    for (std::size_t i = 0; i < statements_.size(); ++i) {
      if (!keep[i]) continue;
      code += statements_[i].text;
      ops[static_cast<std::size_t>(statements_[i].output)] += statements_[i].ops;
    }
    return code;
  }

 private:
  struct Row {
    Set speeds;
    bool wide = false;
  };
  struct Layout {
    Set speeds;
    bool wide = false;
  };
  struct Statement {
    std::string name, text;
    OpCount ops;
    int output = 0;
  };
  // The terms without a zero factor or row, and their rows.
  static Terms nonzero(const Terms& terms) {
    Terms kept;
    for (const auto& t : terms)
      if (!t.first.empty() && !t.second.empty()) kept.push_back(t);
    return kept;
  }
  static std::vector<std::string> rows_of(const Terms& terms) {
    std::vector<std::string> rows;
    for (const auto& t : terms) rows.push_back(t.second);
    return rows;
  }
  // "rhs + factor_i * row_i + ...", the rows as rows of the given kind; counts the operations on its lanes.
  std::string products(std::string rhs, const Terms& terms, bool wide, OpCount& ops) {
    const int n = lanes(wide);
    for (const auto& [factor, row] : terms) {
      if (!rhs.empty()) {
        rhs += " + ";
        ops.adds += n;
      }
      rhs += factor + " * " + as(row, wide);
      ops.muls += n;
    }
    return rhs;
  }
  static Set merged(const Set& a, const Set& b) {
    Set out;
    std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
    return out;
  }
  bool distinct(const Set& speeds) const {
    std::set<int> used;
    for (int k : speeds)
      if (!used.insert(slot_[static_cast<std::size_t>(k)]).second) return false;
    return true;
  }
  int lanes(bool wide) const { return wide ? speeds_ : width_; }
  Layout unify(const std::vector<std::string>& rows) const {
    Layout out;
    for (const auto& r : rows) {
      const Row& row = rows_.at(r);
      out.speeds = merged(out.speeds, row.speeds);
      out.wide = out.wide || row.wide;
    }
    out.wide = out.wide || !distinct(out.speeds);
    return out;
  }
  // `row` as a row of the given kind: itself, or (narrow to wide) its lanes moved to a new wide
  // row, once.
  std::string as(const std::string& row, bool wide) {
    const Row info = rows_.at(row);
    if (info.wide == wide) return row;
    const std::string name = row + "_all";
    if (rows_.count(name)) return name;
    std::string text = fmt::format("    LW {} = {};\n", name, zero(true));
    for (int k : info.speeds) text += fmt::format("    {}.set_lane({}, {}.lane({}));\n", name, k, row, slot_[static_cast<std::size_t>(k)]);
    add(name, text, {});
    rows_[name] = {info.speeds, true};
    return name;
  }
  const Part& part_for(const std::string& accumulator, const Layout& layout) {
    auto& parts = accumulators_[accumulator];
    for (Part& p : parts) {
      if (p.wide != layout.wide) continue;
      const Set speeds = merged(p.speeds, layout.speeds);
      if (p.wide || distinct(speeds)) {
        p.speeds = speeds;
        return p;
      }
    }
    const std::string name = parts.empty() ? accumulator
                             : layout.wide ? accumulator + "_all"
                                           : fmt::format("{}_part{}", accumulator, parts.size());
    parts.push_back({name, layout.speeds, layout.wide});
    return parts.back();
  }
  void add(const std::string& name, const std::string& text, const OpCount& ops) {
    statements_.push_back({name, text, ops, charge_to});
  }
  std::vector<int> slot_;
  int width_, speeds_;
  std::map<std::string, Row> rows_;
  std::map<std::string, std::vector<Part>> accumulators_;
  std::vector<Statement> statements_;
};

// A lane for each commanded speed such that the speeds of any one set (the speeds that move one
// joint) get distinct lanes: greedy colouring of "share a set". Speeds of different limbs that
// never move a common joint share a lane.
std::vector<int> shared_lanes(int nu, const std::vector<std::vector<int>>& sets) {
  std::vector<std::set<int>> conflicts(static_cast<std::size_t>(nu));
  for (const auto& set : sets)
    for (int a : set)
      for (int b : set)
        if (a != b) conflicts[static_cast<std::size_t>(a)].insert(b);
  std::vector<int> slot(static_cast<std::size_t>(nu), -1);
  for (int k = 0; k < nu; ++k) {
    std::set<int> taken;
    for (int other : conflicts[static_cast<std::size_t>(k)])
      if (slot[static_cast<std::size_t>(other)] >= 0) taken.insert(slot[static_cast<std::size_t>(other)]);
    int s = 0;
    while (taken.count(s)) ++s;
    slot[static_cast<std::size_t>(k)] = s;
  }
  return slot;
}

// The outputs whose shares of the lane code's operations are counted apart (LaneWriter::charge_to);
// the twists and D P count with M.
enum ReducedOutput { kM, kB_velocity, kB_bias, kQ_gravity };

using Wrench = std::array<std::string, 6>;  // lanes of (force; moment about K0's origin), as in TwistNode

// reduced_dynamics as declared: its documentation and its input T. The names of its lane code start
// with kane_, which the model's coordinates and parameters therefore must not.
FunctionSpec reduced_dynamics_spec(const Model& m) {
  FunctionSpec fn{"reduced_dynamics", "reduced_dynamics.hpp",
                  "Kane's equations on the commanded speeds u, in one pass with the convective terms: with "
                  "s' = T u and s'' = T u' + s''_bias, the generalized inertia, velocity and gravity forces on u "
                  "are M u' + b_velocity + B_bias s''_bias and Q_gravity. Per body, P = [dv/du; R^T domega/du] "
                  "(the CoM velocity in K0, the angular velocity in body axes) and D = diag(m, m, m, I) give "
                  "M = sum P^T D P, b_velocity = sum P^T [m Jv_dot s'; I R^T Jw_dot s' + omega x I omega] and "
                  "B_bias = sum P^T D [Jv; R^T Jw]. P comes from the joints' twists summed along the chains (one "
                  "lane per speed), B_bias from the bodies' wrenches summed back along them.",
                  true, {}};
  const auto reserved = [](const char* what, const std::string& name) {
    if (name.rfind("kane_", 0) == 0) throw std::runtime_error(std::string(what) + " name " + name + ": names starting with kane_ are reserved");
  };
  for (const auto& c : m.coordinates) reserved("coordinate", c.name);
  for (const auto& par : m.parameters) reserved("parameter", par.name);
  fn.inputs = {{"T", "RateBasis",
                "s' = T u, the rates caused by unit commanded speeds (rate_basis at s); only the rows of the dependent "
                "pair and of the dependent joints are read, the others are fixed by the model file, and in them only "
                "the entries kRateBasisPattern marks (structure.hpp; the others are zero)"}};
  return fn;
}

// The writer of the lane code, its lanes laid out for the speeds that move each joint of the tree
// (speeds_of: each coordinate's), T's dense rows declared.
LaneWriter lane_writer(const Model& m, const RateRoles& roles, const std::vector<TwistNode>& nodes,
                       const std::vector<std::vector<int>>& speeds_of) {
  const int n = coordinate_count(m);
  const int nu = static_cast<int>(m.dynamics->commanded.size());
  std::vector<std::vector<int>> node_speeds(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const int j = nodes[k].joint->coordinate;
    const int parent = nodes[k].parent;
    const std::vector<int>& own = speeds_of[static_cast<std::size_t>(j)];  // a commanded speed's: itself
    const std::vector<int> before = parent < 0 ? std::vector<int>{} : node_speeds[static_cast<std::size_t>(parent)];
    std::set_union(before.begin(), before.end(), own.begin(), own.end(), std::back_inserter(node_speeds[k]));
  }
  std::vector<int> slot = shared_lanes(nu, node_speeds);
  const int width = slot.empty() ? nu : *std::max_element(slot.begin(), slot.end()) + 1;
  if (width >= nu)  // nothing to gain: every speed its own lane
    for (int k = 0; k < nu; ++k) slot[static_cast<std::size_t>(k)] = k;
  LaneWriter w(slot, std::min(width, nu));
  for (int j = 0; j < n; ++j)
    if (roles.dense[static_cast<std::size_t>(j)]) w.declare(fmt::format("kane_T_{}", j), speeds_of[static_cast<std::size_t>(j)]);
  return w;
}

// Forward: a joint's twist per unit rate is (a, o x a) for a revolute joint (axis a through o),
// (0, a) for a prismatic one; times T's row of its coordinate, added to its parent's. Writes the
// nodes' twists and adds the dense rows of T they read to rows_used; returns each joint's own
// twist per unit rate (its scalars' names).
std::vector<std::array<std::string, 6>> forward_twists(FunctionSpec& fn, const RateRoles& roles, std::vector<TwistNode>& nodes,
                                                       LaneWriter& w, std::set<int>& rows_used) {
  w.charge_to = kM;
  w.comment("The joints' partial twists (omega; velocity of the point at K0's origin), one lane per commanded");
  w.comment("speed, summed along the bodies' chains from K0 (chains share their common joints).");
  std::vector<std::array<std::string, 6>> joint_twist(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    TwistNode& node = nodes[k];
    const JointRecord& joint = *node.joint;
    const std::array<ex, 6> S = spatial_axis(joint);
    for (std::size_t c = 0; c < 6; ++c) joint_twist[k][c] = lane_scalar(fn, fmt::format("kane_twist_{}_{}", k, c), S[c]);
    const int j = joint.coordinate;
    const std::array<std::string, 6> base =
        node.parent < 0 ? std::array<std::string, 6>{} : nodes[static_cast<std::size_t>(node.parent)].twist;
    for (std::size_t c = 0; c < 6; ++c) {
      const std::string name = fmt::format("twist{}_{}", k, c);
      const std::string& x = joint_twist[k][c];
      if (x.empty()) {
        node.twist[c] = base[c];
      } else if (roles.dense[static_cast<std::size_t>(j)]) {
        rows_used.insert(j);
        node.twist[c] = w.define(name, base[c], {{x, fmt::format("kane_T_{}", j)}});
      } else {
        node.twist[c] = w.plus_lane(name, base[c], roles.speed_of[static_cast<std::size_t>(j)], x);
      }
    }
  }
  return joint_twist;
}

// Body i (tw: the twist at its node; minus_g: the lane scalar -g): P from the twist at its CoM,
// D P, and its terms of M, b_velocity and Q_gravity; returns its wrench per unit speed.
Wrench body_terms(const Model& m, std::size_t i, const std::array<std::string, 6>& tw, const std::string& minus_g, FunctionSpec& fn,
                  LaneWriter& w) {
  const auto scalar = [&](const std::string& name, const ex& value) { return lane_scalar(fn, name, value); };
  const Body& body = m.bodies[i];
  const Frame& f = body.com_frame;
  const auto name = [&](const char* what, int a) { return fmt::format("kane_{}_{}_{}", what, i, a); };
  w.charge_to = kM;
  w.comment(fmt::format("body {}: {}", body.name, body.meaning));
  std::array<std::string, 3> p, minus_p, pv, pb, dv, db;
  for (int c = 0; c < 3; ++c) {
    p[static_cast<std::size_t>(c)] = scalar(name("p", c), f.r[c]);
    minus_p[static_cast<std::size_t>(c)] = scalar(name("minus_p", c), -f.r[c]);
  }
  const auto at = [](const auto& a, int c) -> const std::string& { return a[static_cast<std::size_t>(c)]; };
  // v = v_0 + omega x p.
  for (int c = 0; c < 3; ++c) {
    const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
    pv[static_cast<std::size_t>(c)] = w.define(fmt::format("pv{}_{}", i, c), at(tw, c + 3),
                                               {{at(p, c2), at(tw, c1)}, {at(minus_p, c1), at(tw, c2)}});
  }
  std::array<std::string, 9> R;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) R[static_cast<std::size_t>(3 * a + b)] = scalar(fmt::format("kane_R_{}_{}_{}", i, a, b), f.R(a, b));
  const auto Rab = [&](int a, int b) -> const std::string& { return R[static_cast<std::size_t>(3 * a + b)]; };
  for (int a = 0; a < 3; ++a)
    pb[static_cast<std::size_t>(a)] = w.define(fmt::format("pb{}_{}", i, a), "", {{Rab(0, a), at(tw, 0)}, {Rab(1, a), at(tw, 1)}, {Rab(2, a), at(tw, 2)}});
  const std::string mass = scalar(name("mass", 0), m.parameter(body.mass).symbol);
  Vec3 I;
  for (int a = 0; a < 3; ++a) I[a] = m.parameter(body.inertia[static_cast<std::size_t>(a)]).symbol;
  for (int c = 0; c < 3; ++c) dv[static_cast<std::size_t>(c)] = w.define(fmt::format("dv{}_{}", i, c), "", {{mass, at(pv, c)}});
  for (int a = 0; a < 3; ++a)
    db[static_cast<std::size_t>(a)] = w.define(fmt::format("db{}_{}", i, a), "", {{scalar(name("inertia", a), I[a]), at(pb, a)}});
  // b_velocity += P^T [m a; I alpha_b + omega_b x I omega_b] (body axes); Q_gravity += Pv^T m g.
  const auto to_body = [&](const Vec3& v) {
    Vec3 out;
    for (int a = 0; a < 3; ++a) out[a] = f.R(0, a) * v[0] + f.R(1, a) * v[1] + f.R(2, a) * v[2];
    return out;
  };
  const auto inertia_times = [&](const Vec3& v) { return Vec3(I[0] * v[0], I[1] * v[1], I[2] * v[2]); };
  const Vec3 omega = to_body(f.omega);
  const Vec3 torque = inertia_times(to_body(f.alpha_bias)) + cross(omega, inertia_times(omega));
  std::vector<std::pair<std::string, std::string>> force;
  for (int c = 0; c < 3; ++c) force.emplace_back(scalar(name("acc", c), f.a_bias[c]), at(dv, c));
  for (int a = 0; a < 3; ++a) force.emplace_back(scalar(name("torque", a), torque[a]), at(pb, a));
  w.charge_to = kB_velocity;
  w.accumulate("kane_b", force);
  w.charge_to = kQ_gravity;
  w.accumulate("kane_Q", {{minus_g, at(dv, 2)}});
  w.charge_to = kM;
  // Its wrench per unit speed: force D P_v and moment p x force + R (I P_b), in K0.
  Wrench wr;
  for (int c = 0; c < 3; ++c) wr[static_cast<std::size_t>(c)] = at(dv, c);
  for (int c = 0; c < 3; ++c) {
    const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
    wr[static_cast<std::size_t>(c + 3)] = w.define(
        fmt::format("moment{}_{}", i, c), "",
        {{Rab(c, 0), at(db, 0)}, {Rab(c, 1), at(db, 1)}, {Rab(c, 2), at(db, 2)}, {at(p, c1), at(dv, c2)}, {at(minus_p, c2), at(dv, c1)}});
  }
  return wr;
}

// Backward: the wrench sums beyond each node, and its joint's generalized force tau_j = omega_j .
// moment + v_j . force (lane l: for a unit speed l). A dense joint's is B_bias's column j; and
// M = P^T D P summed over the bodies = sum over the joints of T(j, :)^T tau_j: a commanded speed's
// joint adds its tau to row k, a dense joint T(j, k) tau_j to every row k. Returns B_bias's
// columns that get a tau.
std::set<int> backward_wrenches(const RateRoles& roles, const std::vector<std::vector<int>>& speeds_of,
                                const std::vector<std::array<std::string, 6>>& joint_twist, const std::vector<Wrench>& body_wrench,
                                std::vector<TwistNode>& nodes, LaneWriter& w) {
  const auto dense = [&](int j) { return roles.dense[static_cast<std::size_t>(j)]; };
  std::set<int> bias_columns;
  w.charge_to = kM;
  w.comment("Back along the chains: the bodies' wrenches summed beyond each joint, the joint's generalized");
  w.comment("force tau (a dependent joint's is B_bias's column), and M = sum over the joints of T(j, :)^T tau.");
  for (std::size_t k = nodes.size(); k-- > 0;) {
    TwistNode& node = nodes[k];
    for (std::size_t c = 0; c < 6; ++c) {
      std::vector<std::string> parts;
      for (int i : node.bodies)
        if (!body_wrench[static_cast<std::size_t>(i)][c].empty()) parts.push_back(body_wrench[static_cast<std::size_t>(i)][c]);
      for (int child : node.children)
        if (!nodes[static_cast<std::size_t>(child)].wrench[c].empty()) parts.push_back(nodes[static_cast<std::size_t>(child)].wrench[c]);
      if (parts.size() == 1) node.wrench[c] = parts[0];
      else if (!parts.empty()) node.wrench[c] = w.define_sum(fmt::format("wrench{}_{}", k, c), parts);
    }
    const int j = node.joint->coordinate;
    std::vector<std::pair<std::string, std::string>> terms;
    for (std::size_t c = 0; c < 3; ++c) terms.emplace_back(joint_twist[k][c], node.wrench[c + 3]);
    for (std::size_t c = 0; c < 3; ++c) terms.emplace_back(joint_twist[k][c + 3], node.wrench[c]);
    w.charge_to = dense(j) ? kB_bias : kM;
    const std::string tau = w.define(fmt::format("tau{}", k), "", terms);
    if (tau.empty()) continue;
    if (dense(j)) {
      bias_columns.insert(j);
      w.add_row(fmt::format("kane_B_{}", j), tau);
      w.charge_to = kM;
      // T(j, l) is zero for the speeds j's rate does not depend on.
      for (int l : speeds_of[static_cast<std::size_t>(j)]) w.accumulate(fmt::format("kane_M_{}", l), {{fmt::format("T({}, {})", j, l), tau}});
    } else {
      w.charge_to = kM;
      w.add_row(fmt::format("kane_M_{}", roles.speed_of[static_cast<std::size_t>(j)]), tau);
    }
  }
  return bias_columns;
}

// Before the bodies' code: the lane types, T's dense rows the twists read (rows_used) and the
// accumulators of M's rows, b_velocity, Q_gravity and B_bias's columns.
std::string lane_declarations(const std::vector<std::vector<int>>& speeds_of, const std::set<int>& rows_used, int nu, LaneWriter& w) {
  for (int k = 0; k < nu; ++k) w.ensure(fmt::format("kane_M_{}", k));
  w.ensure("kane_b");
  w.ensure("kane_Q");
  std::string code = fmt::format("    using L = detail::Lanes<Scalar, {}>;\n", w.width());
  if (w.shares_lanes()) code += fmt::format("    using LW = detail::Lanes<Scalar, {}>;\n", nu);
  code += "    // T's dense rows; the accumulators of M's rows, b_velocity, Q_gravity and B_bias's columns.\n";
  for (int j : rows_used) {
    const auto& speeds = speeds_of[static_cast<std::size_t>(j)];
    if (!w.shares_lanes() && static_cast<int>(speeds.size()) == nu) {
      code += fmt::format("    const L kane_T_{0} = detail::lanes_of_row<Scalar, {1}>(T, {0});\n", j, nu);
      continue;
    }
    code += fmt::format("    L kane_T_{} = {};\n", j, w.zero());
    for (int l : speeds) code += fmt::format("    kane_T_{}.set_lane({}, T({}, {}));\n", j, w.lane(l, false), j, l);
  }
  for (const auto& [name, parts] : w.accumulators())
    for (const auto& part : parts) code += fmt::format("    {} {} = {};\n", w.type(part.wide), part.name, w.zero(part.wide));
  return code;
}

// After the bodies' code: the outputs' entries from the accumulators' parts, their additions
// counted for their outputs in lane_ops.
std::string output_entries(const std::set<int>& bias_columns, int nu, const LaneWriter& w, std::vector<OpCount>& lane_ops) {
  std::string code;
  // An output entry: the sum of the accumulator's parts that hold speed l.
  OpCount output_adds;
  const auto entry = [&](const std::string& accumulator, int l) {
    std::vector<std::string> terms;
    for (const auto& part : w.accumulators().at(accumulator))
      if (std::binary_search(part.speeds.begin(), part.speeds.end(), l)) terms.push_back(fmt::format("{}.lane({})", part.name, w.lane(l, part.wide)));
    if (terms.empty()) return std::string("Scalar(0)");
    output_adds.adds += static_cast<long>(terms.size()) - 1;
    return fmt::format("{}", fmt::join(terms, " + "));
  };
  code += "    if (M != nullptr) {  // the upper triangle, mirrored: M is symmetric to the last bit\n";
  output_adds = {};
  for (int k = 0; k < nu; ++k)
    for (int l = k; l < nu; ++l) {
      const std::string e = entry(fmt::format("kane_M_{}", k), l);
      code += k == l ? fmt::format("      (*M)({0}, {0}) = {1};\n", k, e) : fmt::format("      (*M)({0}, {1}) = (*M)({1}, {0}) = {2};\n", k, l, e);
    }
  const OpCount M_adds = output_adds;
  code += "    }\n    if (b_velocity != nullptr) {\n";
  output_adds = {};
  for (int k = 0; k < nu; ++k) code += fmt::format("      (*b_velocity)({}) = {};\n", k, entry("kane_b", k));
  const OpCount b_adds = output_adds;
  code += "    }\n    if (Q_gravity != nullptr) {\n";
  output_adds = {};
  for (int k = 0; k < nu; ++k) code += fmt::format("      (*Q_gravity)({}) = {};\n", k, entry("kane_Q", k));
  const OpCount Q_adds = output_adds;
  code += "    }\n    if (B_bias != nullptr) {\n      if (zero_fill) B_bias->setZero();\n";
  output_adds = {};
  for (int j : bias_columns)
    for (int k = 0; k < nu; ++k) {
      const std::string e = entry(fmt::format("kane_B_{}", j), k);
      if (e != "Scalar(0)") code += fmt::format("      (*B_bias)({}, {}) = {};\n", k, j, e);
    }
  const OpCount B_adds = output_adds;
  code += "    }\n";
  lane_ops[kM] += M_adds;
  lane_ops[kB_velocity] += b_adds;
  lane_ops[kQ_gravity] += Q_adds;
  lane_ops[kB_bias] += B_adds;
  return code;
}

}  // namespace

FunctionSpec derive_reduced_dynamics(const Model& m) {
  const Dynamics& dyn = *m.dynamics;
  const int nu = static_cast<int>(dyn.commanded.size());
  FunctionSpec fn = reduced_dynamics_spec(m);
  // T's structure is fixed by the model file: the commanded speeds' rows are unit rows, the rows of
  // the dependent pair and of the dependent joints are dense, the rows of the other inputs (held
  // constant) zero. So only the joints of those two kinds move the bodies.
  const RateRoles roles = rate_roles(m);

  // The tree of the bodies' chains, moving joints only (the others add nothing to a twist).
  TwistTree tree = twist_tree(m, roles);
  std::vector<TwistNode>& nodes = tree.nodes;

  // Which commanded speeds each joint's rate depends on, and the lanes they take (LaneWriter).
  const std::vector<std::vector<int>> speeds_of = rate_speeds(m, roles);  // = rate_basis_pattern(m), from the roles at hand
  LaneWriter w = lane_writer(m, roles, nodes, speeds_of);
  std::set<int> rows_used;
  const std::vector<std::array<std::string, 6>> joint_twist = forward_twists(fn, roles, nodes, w, rows_used);

  const ex g = m.parameter(dyn.gravity).symbol;
  const std::string minus_g = lane_scalar(fn, "kane_minus_g", -g);
  std::vector<Wrench> body_wrench(m.bodies.size());
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const int at = tree.body_node[i];
    if (at < 0) continue;  // moved by no joint of T: no part in u's dynamics
    body_wrench[i] = body_terms(m, i, nodes[static_cast<std::size_t>(at)].twist, minus_g, fn, w);
  }
  const std::set<int> bias_columns = backward_wrenches(roles, speeds_of, joint_twist, body_wrench, nodes, w);

  std::vector<OpCount> lane_ops(4);
  const std::string body_code = w.finish(lane_ops);
  const auto body_words = identifiers(body_code);
  const std::set<std::string> read(body_words.begin(), body_words.end());
  std::erase_if(fn.lane_scalars, [&](const auto& named) { return !read.count(named.first); });
  // Around the bodies: T's rows, the accumulators, then the outputs.
  const std::string before = lane_declarations(speeds_of, rows_used, nu, w);
  fn.lane_code = before + body_code + output_entries(bias_columns, nu, w, lane_ops);
  fn.lane_layout = w.shares_lanes() ? fmt::format("{} lanes, {} where the limbs' sums meet", w.width(), nu) : fmt::format("{} lanes", nu);

  const FunctionSpec c = derive_convective(m);
  OutputSpec Mo{"M", "CommandMatrix", "generalized mass matrix on u (symmetric)", "", {}};
  OutputSpec bo{"b_velocity", "CommandVector", "velocity-dependent forces on u, s''_bias excluded", "", {}};
  OutputSpec Bo{"B_bias", "CommandRows", "forces on u per unit s''_bias: b = b_velocity + B_bias s''_bias", kZeroMatrix, {}};
  OutputSpec Qo{"Q_gravity", "CommandVector", "generalized gravity force on u (gravity along -z of K0)", "", {}};
  for (OutputSpec* o : {&Mo, &bo, &Bo, &Qo}) o->from_lanes = true;
  Mo.lane_ops = lane_ops[kM];
  bo.lane_ops = lane_ops[kB_velocity];
  Bo.lane_ops = lane_ops[kB_bias];
  Qo.lane_ops = lane_ops[kQ_gravity];
  fn.outputs = {c.outputs[0], c.outputs[1], Mo, bo, Bo, Qo};
  return fn;
}

}  // namespace wlx::codegen
