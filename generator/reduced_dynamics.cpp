// reduced_dynamics: Kane's equations projected onto the commanded speeds, derived as code on lanes
// (one per commanded speed, lane_code.hpp) that sums the joints' twists out along the bodies'
// chains and the bodies' wrenches back along them; lane_printer.hpp writes it as C++.
#include "derivations_internal.hpp"
#include "lane_printer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <iterator>
#include <map>
#include <set>

namespace wlx::codegen {

using namespace derivation;
using lane_code::Layout;
using lane_code::Quantity;
using lane_code::Term;
using lane_code::value_id;
using lane_code::ValueId;

namespace {

// Builds reduced_dynamics' lane code (lane_code.hpp): statements on rows of scalars
// (detail::Lanes), one lane per commanded speed, each counted for an output (`charge_to`). A row
// that is structurally zero is the zero ValueId (no statement is made for it).
//
// Rows are narrow or wide. A wide row holds every commanded speed, lane k for speed k. A narrow
// row holds only the speeds its set names, speed k in lane slot[k]: speeds that never move the
// same body (the commanded speeds of two legs, say) share a lane, so that a machine with many
// commanded speeds but few per limb runs its limbs' sums on short rows. A row is narrow when its
// speeds' slots are distinct; sums whose speeds collide (the wrenches where the limbs meet) are
// wide, their narrow parts widened first. With no sharing (slot[k] = k) every row is narrow and
// holds every speed.
class LaneBuilder {
 public:
  using Set = std::vector<int>;                              // commanded speeds, ascending
  using Terms = std::vector<std::pair<ValueId, ValueId>>;  // (scalar factor, row)
  LaneBuilder(std::vector<int> slot, int width) : slot_(std::move(slot)) {
    program_.kind = lane_code::LaneProgram::Kind::lanes;
    program_.width = width;
    program_.speeds = static_cast<int>(slot_.size());
  }
  int charge_to = 0;  // the output the next statements' operations count for
  bool shares_lanes() const { return program_.shares_lanes(); }
  // A row the caller declares (T's rows): its speeds, narrow.
  void declare(const ValueId& row, const Set& speeds) { rows_[row] = {speeds, false}; }
  // A lane scalar (zero for an exact zero).
  ValueId scalar(const ValueId& id, const ex& value) { return program_.scalar(id, value); }
  // A new row "target = base + sum_i factor_i * row_i" (terms with a zero factor or row dropped);
  // returns target, or base itself when no term remains (no code).
  ValueId define(const ValueId& target, const ValueId& base, const Terms& terms) {
    const Terms kept = nonzero(terms);
    if (kept.empty()) return base;
    std::vector<ValueId> rows = rows_of(kept);
    if (!base.is_zero()) rows.insert(rows.begin(), base);
    const Row layout = unify(rows);
    std::vector<Term> sum;
    if (!base.is_zero()) sum.push_back({lane_code::kOne, as(base, layout.wide)});
    products(kept, layout.wide, sum);
    add(lane_code::Define{target, kind(layout.wide), std::move(sum)});
    rows_[target] = layout;
    return target;
  }
  // A new row, the sum of `rows` (at least two).
  ValueId define_sum(const ValueId& target, const std::vector<ValueId>& rows) {
    const Row layout = unify(rows);
    std::vector<Term> sum;
    for (const auto& r : rows) sum.push_back({lane_code::kOne, as(r, layout.wide)});
    add(lane_code::Define{target, kind(layout.wide), std::move(sum)});
    rows_[target] = layout;
    return target;
  }
  // "accumulator += sum_i factor_i * row_i": into one of the accumulator's parts (one whose
  // speeds, with the terms', keep distinct lanes; else a new part).
  void accumulate(const ValueId& accumulator, const Terms& terms) {
    const Terms kept = nonzero(terms);
    if (kept.empty()) return;
    const Part& part = part_for(accumulator, unify(rows_of(kept)));
    std::vector<Term> sum;
    products(kept, part.wide, sum);
    add(lane_code::Accumulate{part.id, kind(part.wide), std::move(sum)});
  }
  // "accumulator += row".
  void add_row(const ValueId& accumulator, const ValueId& row) {
    const Part& part = part_for(accumulator, unify({row}));
    add(lane_code::Accumulate{part.id, kind(part.wide), {{lane_code::kOne, as(row, part.wide)}}});
  }
  // A new row equal to `base` (or zero) plus `value` for speed k only: a unit row of T.
  ValueId plus_lane(const ValueId& target, const ValueId& base, int k, const ValueId& value) {
    Set speeds = base.is_zero() ? Set{} : rows_.at(base).speeds;
    speeds = merged(speeds, {k});
    const bool wide = (!base.is_zero() && rows_.at(base).wide) || !distinct(speeds);
    const ValueId from = base.is_zero() ? base : as(base, wide);
    add(lane_code::PlusLane{target, kind(wide), from, lane(k, wide), value});
    rows_[target] = {speeds, wide};
    return target;
  }
  void comment(const std::string& text) { add(lane_code::Comment{text}); }
  // The lane of speed k in a row of the given kind.
  int lane(int k, bool wide) const { return wide ? k : slot_[static_cast<std::size_t>(k)]; }
  static Layout kind(bool wide) { return wide ? Layout::wide : Layout::narrow; }

  struct Part {
    ValueId id;
    Set speeds;
    bool wide = false;
  };
  // Every accumulator's parts, in the order they were made (the caller declares them, zero).
  const std::map<ValueId, std::vector<Part>>& accumulators() const { return accumulators_; }
  // An accumulator nothing was added to gets one narrow part, so the caller's code can name it.
  void ensure(const ValueId& accumulator) {
    if (!accumulators_.count(accumulator)) accumulators_[accumulator].push_back({accumulator, {}, false});
  }
  // The code so far (the statements before it and after it are the caller's).
  lane_code::LaneProgram& program() { return program_; }

 private:
  struct Row {
    Set speeds;
    bool wide = false;
  };
  // The terms without a zero factor or row, and their rows.
  static Terms nonzero(const Terms& terms) {
    Terms kept;
    for (const auto& t : terms)
      if (!t.first.is_zero() && !t.second.is_zero()) kept.push_back(t);
    return kept;
  }
  static std::vector<ValueId> rows_of(const Terms& terms) {
    std::vector<ValueId> rows;
    for (const auto& t : terms) rows.push_back(t.second);
    return rows;
  }
  // factor_i * row_i appended to `sum`, the rows as rows of the given kind.
  void products(const Terms& terms, bool wide, std::vector<Term>& sum) {
    for (const auto& [factor, row] : terms) sum.push_back({factor, as(row, wide)});
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
  Row unify(const std::vector<ValueId>& rows) const {
    Row out;
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
  ValueId as(const ValueId& row, bool wide) {
    const Row info = rows_.at(row);
    if (info.wide == wide) return row;
    ValueId copy = row;
    copy.wide_copy = true;
    if (rows_.count(copy)) return copy;
    lane_code::Widen widen{copy, row, {}};
    for (int k : info.speeds) widen.lanes.emplace_back(k, slot_[static_cast<std::size_t>(k)]);
    add(std::move(widen));
    rows_[copy] = {info.speeds, true};
    return copy;
  }
  const Part& part_for(const ValueId& accumulator, const Row& layout) {
    auto& parts = accumulators_[accumulator];
    for (Part& p : parts) {
      if (p.wide != layout.wide) continue;
      const Set speeds = merged(p.speeds, layout.speeds);
      if (p.wide || distinct(speeds)) {
        p.speeds = speeds;
        return p;
      }
    }
    ValueId id = accumulator;  // the first part is the accumulator itself
    if (!parts.empty() && layout.wide) id.wide_copy = true;
    else if (!parts.empty()) id.part = static_cast<int>(parts.size());
    parts.push_back({id, layout.speeds, layout.wide});
    return parts.back();
  }
  void add(lane_code::Step step) { program_.statements.push_back({std::move(step), charge_to}); }
  std::vector<int> slot_;
  lane_code::LaneProgram program_;
  std::map<ValueId, Row> rows_;
  std::map<ValueId, std::vector<Part>> accumulators_;
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

using Wrench = std::array<ValueId, 6>;  // lanes of (force; moment about K0's origin), as in TwistNode
using Twist = std::array<ValueId, 6>;

// reduced_dynamics' documentation when its code is the composite-rigid-body pass
// (composite_dynamics.cpp) rather than Kane's sums.
constexpr const char* kCompositeDoc =
    "The equations of motion on the commanded speeds u, in one pass with the convective terms: with s' = T u and "
    "s'' = T u' + s''_bias, the generalized inertia, velocity and gravity forces on u are M u' + b_velocity + "
    "B_bias s''_bias and Q_gravity. M by composite rigid bodies: each body's inertia about the first revolute "
    "joint's origin is added to the composite I_k beyond its joint k, M on the coordinates is S_j . (I_k S_k) for "
    "each joint k and each joint j on its chain up to k (S the joints' axes in K0), and M on u is T^T M T on T's "
    "pattern, whose T^T M on the dense rows' coordinates is B_bias. b_velocity = T^T tau for the bodies' wrenches "
    "at u' = 0 and s''_bias = 0 (m a; I alpha + omega x I omega) summed back along the chains, and Q_gravity = "
    "T^T tau for gravity, from the composites' masses and first moments. Limbs of one shape run side by side, one "
    "lane each.";

// reduced_dynamics as declared: its documentation and its input T. The names of its lane code are
// the printer's, which the model's coordinates and parameters therefore must not take.
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
  lane_code::reserve_printer_names(m);
  fn.inputs = {{"T", "RateBasis",
                "s' = T u, the rates caused by unit commanded speeds (rate_basis at s); only the rows of the dependent "
                "pair and of the dependent joints are read, the others are fixed by the model file, and in them only "
                "the entries kRateBasisPattern marks (structure.hpp; the others are zero)"}};
  return fn;
}

// The builder of the lane code, its lanes laid out for the speeds that move each joint of the tree
// (speeds_of: each coordinate's), T's dense rows declared.
LaneBuilder lane_builder(const Model& m, const RateRoles& roles, const std::vector<TwistNode>& nodes,
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
  LaneBuilder w(slot, std::min(width, nu));
  for (int j = 0; j < n; ++j)
    if (roles.dense[static_cast<std::size_t>(j)]) w.declare(value_id(Quantity::rate_row, j), speeds_of[static_cast<std::size_t>(j)]);
  return w;
}

// Forward: a joint's twist per unit rate is (a, o x a) for a revolute joint (axis a through o),
// (0, a) for a prismatic one; times T's row of its coordinate, added to its parent's. Writes the
// nodes' twists and adds the dense rows of T they read to rows_used; returns each joint's own
// twist per unit rate (its lane scalars).
std::vector<Twist> forward_twists(const RateRoles& roles, std::vector<TwistNode>& nodes, LaneBuilder& w, std::set<int>& rows_used) {
  w.charge_to = kM;
  w.comment("The joints' partial twists (omega; velocity of the point at K0's origin), one lane per commanded");
  w.comment("speed, summed along the bodies' chains from K0 (chains share their common joints).");
  std::vector<Twist> joint_twist(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    TwistNode& node = nodes[k];
    const JointRecord& joint = *node.joint;
    const std::array<ex, 6> S = spatial_axis(joint);
    const int kk = static_cast<int>(k);
    for (std::size_t c = 0; c < 6; ++c) joint_twist[k][c] = w.scalar(value_id(Quantity::joint_axis, kk, static_cast<int>(c)), S[c]);
    const int j = joint.coordinate;
    const Twist base = node.parent < 0 ? Twist{} : nodes[static_cast<std::size_t>(node.parent)].twist;
    for (std::size_t c = 0; c < 6; ++c) {
      const ValueId target = value_id(Quantity::spatial_velocity, kk, static_cast<int>(c));
      const ValueId& x = joint_twist[k][c];
      if (x.is_zero()) {
        node.twist[c] = base[c];
      } else if (roles.dense[static_cast<std::size_t>(j)]) {
        rows_used.insert(j);
        node.twist[c] = w.define(target, base[c], {{x, value_id(Quantity::rate_row, j)}});
      } else {
        node.twist[c] = w.plus_lane(target, base[c], roles.speed_of[static_cast<std::size_t>(j)], x);
      }
    }
  }
  return joint_twist;
}

// Body i (tw: the twist at its node; minus_g: the lane scalar -g): P from the twist at its CoM,
// D P, and its terms of M, b_velocity and Q_gravity; returns its wrench per unit speed.
Wrench body_terms(const Model& m, std::size_t i, const Twist& tw, const ValueId& minus_g, LaneBuilder& w) {
  const Body& body = m.bodies[i];
  const Frame& f = body.com_frame;
  const int index = static_cast<int>(i);
  const auto id = [&](Quantity what, int a) { return value_id(what, index, a); };
  w.charge_to = kM;
  w.comment(fmt::format("body {}: {}", body.name, body.meaning));
  std::array<ValueId, 3> p, minus_p, pv, pb, dv, db;
  for (int c = 0; c < 3; ++c) {
    p[static_cast<std::size_t>(c)] = w.scalar(id(Quantity::com_offset, c), f.r[c]);
    minus_p[static_cast<std::size_t>(c)] = w.scalar(id(Quantity::minus_com_offset, c), -f.r[c]);
  }
  const auto at = [](const auto& a, int c) -> const ValueId& { return a[static_cast<std::size_t>(c)]; };
  // v = v_0 + omega x p.
  for (int c = 0; c < 3; ++c) {
    const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
    pv[static_cast<std::size_t>(c)] = w.define(id(Quantity::com_velocity, c), at(tw, c + 3), {{at(p, c2), at(tw, c1)}, {at(minus_p, c1), at(tw, c2)}});
  }
  std::array<ValueId, 9> R;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) R[static_cast<std::size_t>(3 * a + b)] = w.scalar(value_id(Quantity::com_rotation, index, a, b), f.R(a, b));
  const auto Rab = [&](int a, int b) -> const ValueId& { return R[static_cast<std::size_t>(3 * a + b)]; };
  for (int a = 0; a < 3; ++a)
    pb[static_cast<std::size_t>(a)] = w.define(id(Quantity::body_rate, a), {}, {{Rab(0, a), at(tw, 0)}, {Rab(1, a), at(tw, 1)}, {Rab(2, a), at(tw, 2)}});
  const ValueId mass = w.scalar(value_id(Quantity::mass, index), m.parameter(body.mass).symbol);
  Vec3 I;
  for (int a = 0; a < 3; ++a) I[a] = m.parameter(body.inertia[static_cast<std::size_t>(a)]).symbol;
  for (int c = 0; c < 3; ++c) dv[static_cast<std::size_t>(c)] = w.define(id(Quantity::force, c), {}, {{mass, at(pv, c)}});
  for (int a = 0; a < 3; ++a)
    db[static_cast<std::size_t>(a)] = w.define(id(Quantity::angular_momentum, a), {}, {{w.scalar(id(Quantity::inertia, a), I[a]), at(pb, a)}});
  // b_velocity += P^T [m a; I alpha_b + omega_b x I omega_b] (body axes); Q_gravity += Pv^T m g.
  const auto to_body = [&](const Vec3& v) {
    Vec3 out;
    for (int a = 0; a < 3; ++a) out[a] = f.R(0, a) * v[0] + f.R(1, a) * v[1] + f.R(2, a) * v[2];
    return out;
  };
  const auto inertia_times = [&](const Vec3& v) { return Vec3(I[0] * v[0], I[1] * v[1], I[2] * v[2]); };
  const Vec3 omega = to_body(f.omega);
  const Vec3 torque = inertia_times(to_body(f.alpha_bias)) + cross(omega, inertia_times(omega));
  LaneBuilder::Terms force;
  for (int c = 0; c < 3; ++c) force.emplace_back(w.scalar(id(Quantity::bias_acceleration, c), f.a_bias[c]), at(dv, c));
  for (int a = 0; a < 3; ++a) force.emplace_back(w.scalar(id(Quantity::bias_torque, a), torque[a]), at(pb, a));
  w.charge_to = kB_velocity;
  w.accumulate(value_id(Quantity::velocity_forces), force);
  w.charge_to = kQ_gravity;
  w.accumulate(value_id(Quantity::gravity_forces), {{minus_g, at(dv, 2)}});
  w.charge_to = kM;
  // Its wrench per unit speed: force D P_v and moment p x force + R (I P_b), in K0.
  Wrench wr;
  for (int c = 0; c < 3; ++c) wr[static_cast<std::size_t>(c)] = at(dv, c);
  for (int c = 0; c < 3; ++c) {
    const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
    wr[static_cast<std::size_t>(c + 3)] =
        w.define(id(Quantity::moment, c), {},
                 {{Rab(c, 0), at(db, 0)}, {Rab(c, 1), at(db, 1)}, {Rab(c, 2), at(db, 2)}, {at(p, c1), at(dv, c2)}, {at(minus_p, c2), at(dv, c1)}});
  }
  return wr;
}

// Backward: the wrench sums beyond each node, and its joint's generalized force tau_j = omega_j .
// moment + v_j . force (lane l: for a unit speed l). A dense joint's is B_bias's column j; and
// M = P^T D P summed over the bodies = sum over the joints of T(j, :)^T tau_j: a commanded speed's
// joint adds its tau to row k, a dense joint T(j, k) tau_j to every row k. Returns B_bias's
// columns that get a tau.
std::set<int> backward_wrenches(const RateRoles& roles, const std::vector<std::vector<int>>& speeds_of, const std::vector<Twist>& joint_twist,
                                const std::vector<Wrench>& body_wrench, std::vector<TwistNode>& nodes, LaneBuilder& w) {
  const auto dense = [&](int j) { return roles.dense[static_cast<std::size_t>(j)]; };
  std::set<int> bias_columns;
  w.charge_to = kM;
  w.comment("Back along the chains: the bodies' wrenches summed beyond each joint, the joint's generalized");
  w.comment("force tau (a dependent joint's is B_bias's column), and M = sum over the joints of T(j, :)^T tau.");
  for (std::size_t k = nodes.size(); k-- > 0;) {
    TwistNode& node = nodes[k];
    for (std::size_t c = 0; c < 6; ++c) {
      std::vector<ValueId> parts;
      for (int i : node.bodies)
        if (!body_wrench[static_cast<std::size_t>(i)][c].is_zero()) parts.push_back(body_wrench[static_cast<std::size_t>(i)][c]);
      for (int child : node.children)
        if (!nodes[static_cast<std::size_t>(child)].wrench[c].is_zero()) parts.push_back(nodes[static_cast<std::size_t>(child)].wrench[c]);
      if (parts.size() == 1) node.wrench[c] = parts[0];
      else if (!parts.empty()) node.wrench[c] = w.define_sum(value_id(Quantity::wrench, static_cast<int>(k), static_cast<int>(c)), parts);
    }
    const int j = node.joint->coordinate;
    LaneBuilder::Terms terms;
    for (std::size_t c = 0; c < 3; ++c) terms.emplace_back(joint_twist[k][c], node.wrench[c + 3]);
    for (std::size_t c = 0; c < 3; ++c) terms.emplace_back(joint_twist[k][c + 3], node.wrench[c]);
    w.charge_to = dense(j) ? kB_bias : kM;
    const ValueId tau = w.define(value_id(Quantity::joint_force, static_cast<int>(k)), {}, terms);
    if (tau.is_zero()) continue;
    if (dense(j)) {
      bias_columns.insert(j);
      w.add_row(value_id(Quantity::bias_column, j), tau);
      w.charge_to = kM;
      // T(j, l) is zero for the speeds j's rate does not depend on.
      for (int l : speeds_of[static_cast<std::size_t>(j)])
        w.accumulate(value_id(Quantity::mass_matrix_row, l), {{value_id(Quantity::rate_basis_entry, j, l), tau}});
    } else {
      w.charge_to = kM;
      w.add_row(value_id(Quantity::mass_matrix_row, roles.speed_of[static_cast<std::size_t>(j)]), tau);
    }
  }
  return bias_columns;
}

// Before the bodies' code: the lane types, T's dense rows the twists read (rows_used) and the
// accumulators of M's rows, b_velocity, Q_gravity and B_bias's columns.
std::vector<lane_code::Statement> lane_declarations(const std::vector<std::vector<int>>& speeds_of, const std::set<int>& rows_used, int nu,
                                                    LaneBuilder& w) {
  for (int k = 0; k < nu; ++k) w.ensure(value_id(Quantity::mass_matrix_row, k));
  w.ensure(value_id(Quantity::velocity_forces));
  w.ensure(value_id(Quantity::gravity_forces));
  std::vector<lane_code::Statement> out;
  out.push_back({lane_code::LaneTypes{}});
  out.push_back({lane_code::Comment{"T's dense rows; the accumulators of M's rows, b_velocity, Q_gravity and B_bias's columns."}});
  for (int j : rows_used) {
    const auto& speeds = speeds_of[static_cast<std::size_t>(j)];
    // Without shared lanes, a row every speed moves is T's row as it is.
    lane_code::LoadRow row{value_id(Quantity::rate_row, j), j, !w.shares_lanes() && static_cast<int>(speeds.size()) == nu, {}};
    if (!row.whole)
      for (int l : speeds) row.lanes.emplace_back(w.lane(l, false), value_id(Quantity::rate_basis_entry, j, l));
    out.push_back({std::move(row)});
  }
  for (const auto& [name, parts] : w.accumulators())
    for (const auto& part : parts) out.push_back({lane_code::ZeroRow{part.id, LaneBuilder::kind(part.wide)}});
  return out;
}

// After the bodies' code: the outputs' entries from the accumulators' parts, their additions
// counted for their outputs.
void output_entries(const std::set<int>& bias_columns, int nu, LaneBuilder& w) {
  auto& code = w.program().statements;
  // An output entry: the sum of the accumulator's parts that hold speed l.
  const auto entry = [&](const ValueId& accumulator, int l) {
    std::vector<Term> terms;
    for (const auto& part : w.accumulators().at(accumulator))
      if (std::binary_search(part.speeds.begin(), part.speeds.end(), l)) terms.push_back({lane_code::kOne, part.id, w.lane(l, part.wide)});
    return terms;
  };
  using lane_code::CloseOutput, lane_code::OpenOutput, lane_code::Store;
  code.push_back({OpenOutput{"M", "the upper triangle, mirrored: M is symmetric to the last bit"}});
  for (int k = 0; k < nu; ++k)
    for (int l = k; l < nu; ++l) code.push_back({Store{"M", k, l, k != l, entry(value_id(Quantity::mass_matrix_row, k), l)}, kM});
  code.push_back({CloseOutput{}});
  code.push_back({OpenOutput{"b_velocity", ""}});
  for (int k = 0; k < nu; ++k) code.push_back({Store{"b_velocity", k, -1, false, entry(value_id(Quantity::velocity_forces), k)}, kB_velocity});
  code.push_back({CloseOutput{}});
  code.push_back({OpenOutput{"Q_gravity", ""}});
  for (int k = 0; k < nu; ++k) code.push_back({Store{"Q_gravity", k, -1, false, entry(value_id(Quantity::gravity_forces), k)}, kQ_gravity});
  code.push_back({CloseOutput{}});
  code.push_back({OpenOutput{"B_bias", "", OpenOutput::Prologue::zero_if_asked}});
  for (int j : bias_columns)
    for (int k = 0; k < nu; ++k) {
      std::vector<Term> e = entry(value_id(Quantity::bias_column, j), k);
      if (!e.empty()) code.push_back({Store{"B_bias", k, j, false, std::move(e)}, kB_bias});
    }
  code.push_back({CloseOutput{}});
}


// Kane's sums on lanes.
lane_code::LaneProgram kane_lanes(const Model& m) {
  const Dynamics& dyn = *m.dynamics;
  const int nu = static_cast<int>(dyn.commanded.size());
  // T's structure is fixed by the model file: the commanded speeds' rows are unit rows, the rows of
  // the dependent pair and of the dependent joints are dense, the rows of the other inputs (held
  // constant) zero. So only the joints of those two kinds move the bodies.
  const RateRoles roles = rate_roles(m);

  // The tree of the bodies' chains, moving joints only (the others add nothing to a twist).
  TwistTree tree = twist_tree(m, roles);
  std::vector<TwistNode>& nodes = tree.nodes;

  // Which commanded speeds each joint's rate depends on, and the lanes they take (LaneBuilder).
  const std::vector<std::vector<int>> speeds_of = rate_speeds(m, roles);  // = rate_basis_pattern(m), from the roles at hand
  LaneBuilder w = lane_builder(m, roles, nodes, speeds_of);
  std::set<int> rows_used;
  const std::vector<Twist> joint_twist = forward_twists(roles, nodes, w, rows_used);

  const ex g = m.parameter(dyn.gravity).symbol;
  const ValueId minus_g = w.scalar(value_id(Quantity::minus_gravity), -g);
  std::vector<Wrench> body_wrench(m.bodies.size());
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const int at = tree.body_node[i];
    if (at < 0) continue;  // moved by no joint of T: no part in u's dynamics
    body_wrench[i] = body_terms(m, i, nodes[static_cast<std::size_t>(at)].twist, minus_g, w);
  }
  const std::set<int> bias_columns = backward_wrenches(roles, speeds_of, joint_twist, body_wrench, nodes, w);

  // Around the bodies: T's rows, the accumulators, then the outputs.
  std::vector<lane_code::Statement> before = lane_declarations(speeds_of, rows_used, nu, w);
  auto& statements = w.program().statements;
  statements.insert(statements.begin(), std::make_move_iterator(before.begin()), std::make_move_iterator(before.end()));
  output_entries(bias_columns, nu, w);
  return std::move(w.program());
}

}  // namespace

FunctionSpec derive_reduced_dynamics(const Model& m) {
  FunctionSpec fn = reduced_dynamics_spec(m);
  // Two derivations of the same outputs; the one that takes the machine fewer instructions is
  // emitted (lane_code::instructions: Kane's rows run 4 lanes per vector instruction). Kane's sums
  // cost bodies times commanded speeds, the composite pass pairs of joints on a chain plus T^T M T,
  // with sibling limbs of one shape side by side on lanes. The composite pass wins where limbs
  // repeat or the commanded speeds are many (a quadruped: 1.27 times faster), Kane's sums where a
  // row of lanes is one vector and no two limbs are alike (the excavator: twice as fast).
  const lane_code::LaneProgram kane = kane_lanes(m);
  const lane_code::LaneProgram composite = composite_rigid_body_program(m);
  const bool use_composite = lane_code::instructions(composite) < lane_code::instructions(kane);
  lane_code::PrintedCode printed = lane_code::print(use_composite ? composite : kane, kReducedOutputs);
  if (use_composite) fn.doc = kCompositeDoc;
  fn.lane_code = std::move(printed.code);
  fn.lane_scalars = std::move(printed.scalars);
  fn.lane_layout = std::move(printed.layout);
  const std::vector<OpCount>& lane_ops = printed.ops;

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
