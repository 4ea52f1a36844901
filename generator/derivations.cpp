#include "derivations.hpp"

#include <fmt/format.h>
#include <wlx/text.hpp>

#include <algorithm>
#include <cctype>
#include <functional>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace wlx::codegen {

namespace {

int coordinate_count(const Model& m) { return static_cast<int>(m.coordinates.size()); }

// A column-major Eigen matrix element: "(*{})(r, c)".
std::string at(int r, int c) { return fmt::format("(*{{}})({}, {})", r, c); }
std::string at(int r) { return fmt::format("(*{{}})({})", r); }
std::string at_array(int k, int r, int c) { return fmt::format("(*{{}})[{}]({}, {})", k, r, c); }

const char* kZeroMatrix = "{}->setZero();";
const char* kZeroArray = "for (auto& m : *{}) m.setZero();";

struct ClosureRow {
  ex value;
  std::vector<ex> gradient;
  ex convective;  // (d/dt dPhi_i/ds) s'
};

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

struct WheelRow {
  std::vector<ex> C;     // v_W . n_W = C s'
  std::vector<ex> spin;  // spin rate = spin s'
  ex convective;         // (d/dt C) s'
};

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

}  // namespace

ex closure_value(const Model& m, const ClosureCondition& c) { return closure_row(m, c).value; }

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
  // Quoted for a comment (wlx/text.hpp): the text may hold a body's meaning from the model file.
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

// A joint of the bodies' chains as a node of their common tree (chains that share a prefix share
// its nodes), with the partial twists of the chain up to it on lanes.
struct TwistNode {
  const JointRecord* joint = nullptr;
  int parent = -1;
  std::vector<int> children, bodies;
  std::array<std::string, 6> twist;  // lanes of (omega; velocity of the point at K0's origin)
  std::array<std::string, 6> wrench;  // lanes of the sum over the bodies beyond: (force; moment about K0's origin)
};

// The commanded speeds each coordinate's rate depends on (T's nonzero columns in its row), from the
// structure of the equations that fix the dense rates: the closure rows and the wheels' rolling
// rows, linear in s'. Their unknowns (the dependent pair and the dependent joints) split into
// independent blocks, the connected parts of "row r involves unknown j" (a leg's joints and its
// wheel's rate, say); a block's rates depend on the commanded speeds its rows involve, and on no
// other. A commanded speed's rate is itself; a held input's is zero (no speeds).
// The coordinates' roles in s' = T u (model with a dynamics section): each commanded speed's index
// in u (-1 for the others), and whether T's row is dense (the dependent pair and the dependent joints).
struct RateRoles {
  std::vector<int> speed_of;
  std::vector<bool> dense;
  // Coordinate j's joint moves in a step: its rate is a commanded speed or a dense row of T (the
  // other inputs are held, and add nothing to a twist).
  bool moves(int j) const { return dense[static_cast<std::size_t>(j)] || speed_of[static_cast<std::size_t>(j)] >= 0; }
};
RateRoles rate_roles(const Model& m) {
  const Dynamics& dyn = *m.dynamics;
  const int n = coordinate_count(m);
  const std::vector<int> pair = m.wheels.empty() ? std::vector<int>{} : m.pair(dyn.pair).coordinates;
  RateRoles roles{std::vector<int>(static_cast<std::size_t>(n), -1), std::vector<bool>(static_cast<std::size_t>(n), false)};
  for (std::size_t k = 0; k < dyn.commanded.size(); ++k) roles.speed_of[static_cast<std::size_t>(dyn.commanded[k])] = static_cast<int>(k);
  for (int j = 0; j < n; ++j) roles.dense[static_cast<std::size_t>(j)] = j >= m.input_count || std::count(pair.begin(), pair.end(), j) > 0;
  return roles;
}

std::vector<std::vector<int>> rate_speeds(const Model& m, const RateRoles& roles) {
  const std::vector<int>& speed_of = roles.speed_of;
  const auto dense = [&](int j) { return roles.dense[static_cast<std::size_t>(j)]; };
  const int n = coordinate_count(m);
  std::vector<std::vector<ex>> rows;
  for (const auto& c : m.closure) rows.push_back(closure_row(m, c).gradient);
  if (m.dynamics && !m.wheels.empty())
    for (const auto& wheel : m.wheels) rows.push_back(wheel_row(m, wheel).C);
  // Union-find over the rows (0 .. rows-1) and the coordinates (rows + j).
  const int count = static_cast<int>(rows.size()) + n;
  std::vector<int> parent(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) parent[static_cast<std::size_t>(i)] = i;
  const std::function<int(int)> root = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  };
  const int R = static_cast<int>(rows.size());
  for (int r = 0; r < R; ++r)
    for (int j = 0; j < n; ++j)
      if (dense(j) && !rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(j)].is_zero()) parent[static_cast<std::size_t>(root(r))] = root(R + j);
  std::map<int, std::set<int>> block_speeds;
  std::set<int> blocks_with_rows;
  for (int r = 0; r < R; ++r) {
    blocks_with_rows.insert(root(r));
    for (int j = 0; j < n; ++j)
      if (speed_of[static_cast<std::size_t>(j)] >= 0 && !rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(j)].is_zero())
        block_speeds[root(r)].insert(speed_of[static_cast<std::size_t>(j)]);
  }
  const int nu = static_cast<int>(std::count_if(speed_of.begin(), speed_of.end(), [](int k) { return k >= 0; }));
  std::vector<std::vector<int>> out(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    auto& speeds = out[static_cast<std::size_t>(j)];
    if (speed_of[static_cast<std::size_t>(j)] >= 0) {
      speeds = {speed_of[static_cast<std::size_t>(j)]};
    } else if (dense(j)) {
      const int b = root(R + j);
      if (!blocks_with_rows.count(b)) {  // no row fixes it (the solve would fail): assume every speed
        for (int k = 0; k < nu; ++k) speeds.push_back(k);
      } else {
        speeds.assign(block_speeds[b].begin(), block_speeds[b].end());
      }
    }
  }
  return out;
}

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

bool same_joint(const JointRecord& a, const JointRecord& b) {
  if (a.coordinate != b.coordinate || a.revolute != b.revolute) return false;
  for (int c = 0; c < 3; ++c)
    if (!a.axis[c].is_equal(b.axis[c]) || !a.origin[c].is_equal(b.origin[c])) return false;
  return true;
}

// A joint's twist per unit rate in K0, (omega; velocity of the point at K0's origin): (a; o x a)
// for a revolute joint (axis a through o), (0; a) for a prismatic one.
std::array<ex, 6> spatial_axis(const JointRecord& joint) {
  const Vec3 linear = joint.revolute ? cross(joint.origin, joint.axis) : joint.axis;
  std::array<ex, 6> S;
  for (int c = 0; c < 3; ++c) {
    S[static_cast<std::size_t>(c)] = joint.revolute ? joint.axis[c] : ex(0);
    S[static_cast<std::size_t>(c + 3)] = linear[c];
  }
  return S;
}

// A value the lane code reads, named and handed to CSE with the function's other expressions; ""
// for an exact zero, which the code writers drop.
std::string lane_scalar(FunctionSpec& fn, const std::string& name, const ex& value) {
  if (value.is_zero()) return {};
  fn.lane_scalars.emplace_back(name, value);
  return name;
}

// The tree of the bodies' chains through the joints that move in a step (RateRoles::moves): chains
// share their common joints; nodes come parents first.
struct TwistTree {
  std::vector<TwistNode> nodes;
  std::vector<int> body_node;  // each body's last node, -1 for a body no such joint moves
};
TwistTree twist_tree(const Model& m, const RateRoles& roles) {
  TwistTree tree;
  std::vector<int> roots;  // the nodes next to K0
  tree.body_node.assign(m.bodies.size(), -1);
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    int at = -1;
    for (const JointRecord& joint : m.bodies[i].com_frame.joints) {
      if (!roles.moves(joint.coordinate)) continue;
      std::vector<int>& siblings = at < 0 ? roots : tree.nodes[static_cast<std::size_t>(at)].children;
      int next = -1;
      for (int c : siblings)
        if (same_joint(*tree.nodes[static_cast<std::size_t>(c)].joint, joint)) next = c;
      if (next < 0) {
        next = static_cast<int>(tree.nodes.size());
        siblings.push_back(next);  // before nodes grows: `siblings` may live in it
        tree.nodes.push_back({&joint, at, {}, {}, {}, {}});
      }
      at = next;
    }
    tree.body_node[i] = at;
    if (at >= 0) tree.nodes[static_cast<std::size_t>(at)].bodies.push_back(static_cast<int>(i));
  }
  return tree;
}

}  // namespace

std::vector<std::vector<int>> rate_basis_pattern(const Model& m) {
  const int n = coordinate_count(m);
  if (!m.dynamics) return std::vector<std::vector<int>>(static_cast<std::size_t>(n));
  return rate_speeds(m, rate_roles(m));
}

FunctionSpec derive_reduced_dynamics(const Model& m) {
  const Dynamics& dyn = *m.dynamics;
  const int n = coordinate_count(m);
  const int nu = static_cast<int>(dyn.commanded.size());
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
  // T's structure is fixed by the model file: the commanded speeds' rows are unit rows, the rows of
  // the dependent pair and of the dependent joints are dense, the rows of the other inputs (held
  // constant) zero. So only the joints of those two kinds move the bodies.
  const RateRoles roles = rate_roles(m);
  const std::vector<int>& speed_of = roles.speed_of;
  const auto dense = [&](int j) { return roles.dense[static_cast<std::size_t>(j)]; };
  fn.inputs = {{"T", "RateBasis",
                "s' = T u, the rates caused by unit commanded speeds (rate_basis at s); only the rows of the dependent "
                "pair and of the dependent joints are read, the others are fixed by the model file, and in them only "
                "the entries kRateBasisPattern marks (structure.hpp; the others are zero)"}};
  const auto scalar = [&](const std::string& name, const ex& value) { return lane_scalar(fn, name, value); };

  // The tree of the bodies' chains, moving joints only (the others add nothing to a twist).
  TwistTree tree = twist_tree(m, roles);
  std::vector<TwistNode>& nodes = tree.nodes;
  const std::vector<int>& body_node = tree.body_node;

  // Which commanded speeds each joint's rate depends on, and the lanes they take (LaneWriter).
  const std::vector<std::vector<int>> speeds_of = rate_speeds(m, roles);  // = rate_basis_pattern(m), from the roles at hand
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
    if (dense(j)) w.declare(fmt::format("kane_T_{}", j), speeds_of[static_cast<std::size_t>(j)]);
  // Each output's share of the lane code's operations (the twists and D P count with M).
  enum { kM, kB_velocity, kB_bias, kQ_gravity };
  std::set<int> rows_used;
  w.charge_to = kM;
  // Forward: a joint's twist per unit rate is (a, o x a) for a revolute joint (axis a through o),
  // (0, a) for a prismatic one; times T's row of its coordinate, added to its parent's.
  w.comment("The joints' partial twists (omega; velocity of the point at K0's origin), one lane per commanded");
  w.comment("speed, summed along the bodies' chains from K0 (chains share their common joints).");
  std::vector<std::array<std::string, 6>> joint_twist(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    TwistNode& node = nodes[k];
    const JointRecord& joint = *node.joint;
    const std::array<ex, 6> S = spatial_axis(joint);
    for (std::size_t c = 0; c < 6; ++c) joint_twist[k][c] = scalar(fmt::format("kane_twist_{}_{}", k, c), S[c]);
    const int j = joint.coordinate;
    const std::array<std::string, 6> base =
        node.parent < 0 ? std::array<std::string, 6>{} : nodes[static_cast<std::size_t>(node.parent)].twist;
    for (std::size_t c = 0; c < 6; ++c) {
      const std::string name = fmt::format("twist{}_{}", k, c);
      const std::string& x = joint_twist[k][c];
      if (x.empty()) {
        node.twist[c] = base[c];
      } else if (dense(j)) {
        rows_used.insert(j);
        node.twist[c] = w.define(name, base[c], {{x, fmt::format("kane_T_{}", j)}});
      } else {
        node.twist[c] = w.plus_lane(name, base[c], speed_of[static_cast<std::size_t>(j)], x);
      }
    }
  }

  // Per body: P from the twist at its CoM, D P, and its terms of M, b_velocity and Q_gravity.
  const ex g = m.parameter(dyn.gravity).symbol;
  const std::string minus_g = scalar("kane_minus_g", -g);
  std::vector<std::array<std::string, 6>> body_wrench(m.bodies.size());
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    if (body_node[i] < 0) continue;  // moved by no joint of T: no part in u's dynamics
    const Body& body = m.bodies[i];
    const Frame& f = body.com_frame;
    const auto& tw = nodes[static_cast<std::size_t>(body_node[i])].twist;
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
    auto& wr = body_wrench[i];
    for (int c = 0; c < 3; ++c) wr[static_cast<std::size_t>(c)] = at(dv, c);
    for (int c = 0; c < 3; ++c) {
      const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
      wr[static_cast<std::size_t>(c + 3)] = w.define(
          fmt::format("moment{}_{}", i, c), "",
          {{Rab(c, 0), at(db, 0)}, {Rab(c, 1), at(db, 1)}, {Rab(c, 2), at(db, 2)}, {at(p, c1), at(dv, c2)}, {at(minus_p, c2), at(dv, c1)}});
    }
  }

  // Backward: the wrench sums beyond each node, and its joint's generalized force tau_j = omega_j .
  // moment + v_j . force (lane l: for a unit speed l). A dense joint's is B_bias's column j; and
  // M = P^T D P summed over the bodies = sum over the joints of T(j, :)^T tau_j: a commanded speed's
  // joint adds its tau to row k, a dense joint T(j, k) tau_j to every row k.
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
      w.add_row(fmt::format("kane_M_{}", speed_of[static_cast<std::size_t>(j)]), tau);
    }
  }
  std::vector<OpCount> lane_ops(4);
  const std::string body_code = w.finish(lane_ops);
  const auto body_words = identifiers(body_code);
  const std::set<std::string> read(body_words.begin(), body_words.end());
  std::erase_if(fn.lane_scalars, [&](const auto& named) { return !read.count(named.first); });

  // Around the bodies: T's rows, the accumulators, then the outputs.
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
  code += body_code;
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
  fn.lane_layout = w.shares_lanes() ? fmt::format("{} lanes, {} where the limbs' sums meet", w.width(), nu) : fmt::format("{} lanes", nu);
  fn.lane_code = code;

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

namespace {

// Straight-line scalar code, one `const Scalar name = ...;` per value, for the recursive
// Newton-Euler pass. A value is a name, or empty for an exact zero: products with a zero and zero
// terms are dropped, a sum of one plain term is that term (no line, no operation).
class ScalarWriter {
 public:
  struct Term {
    std::string a, b;  // a * b; b == kOne: a alone; an empty factor: zero
    bool negate = false;
  };
  static inline const std::string kOne = "1";
  std::string define(const std::string& name, const std::vector<Term>& terms) {
    std::vector<const Term*> live;
    for (const Term& t : terms)
      if (!t.a.empty() && !t.b.empty()) live.push_back(&t);
    if (live.empty()) return {};
    if (live.size() == 1 && !live[0]->negate && live[0]->b == kOne) return live[0]->a;
    std::string line = "    const Scalar " + name + " = ";
    for (std::size_t k = 0; k < live.size(); ++k) {
      const Term& t = *live[k];
      if (k > 0) line += t.negate ? " - " : " + ";
      else if (t.negate) line += "-";
      if (k > 0 || t.negate) ++ops.adds;
      line += t.b == kOne ? t.a : t.a + " * " + t.b;
      if (t.b != kOne) ++ops.muls;
    }
    code += line + ";\n";
    return name;
  }
  // The code without the values nothing reads (a link turning about one axis: of its I omega only
  // the component along that axis, which the cross product omega x I omega never reads), over and
  // over until each value left is read; their operations are taken off `ops`.
  std::string finish() {
    std::vector<std::string> lines;
    std::istringstream in(code);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    const std::string prefix = "    const Scalar ";
    for (bool dropped = true; dropped;) {
      dropped = false;
      std::map<std::string, int> uses;
      for (const auto& l : lines)
        for (const auto& w : identifiers(l)) ++uses[w];
      for (auto it = lines.begin(); it != lines.end();) {
        const std::size_t eq = it->find(" = ");
        if (it->rfind(prefix, 0) != 0 || eq == std::string::npos || uses[it->substr(prefix.size(), eq - prefix.size())] > 1) {
          ++it;
          continue;
        }
        const std::string value = it->substr(eq + 3);
        const auto count = [&](const std::string& what) {
          int n = 0;
          for (auto at = value.find(what); at != std::string::npos; at = value.find(what, at + 1)) ++n;
          return n;
        };
        ops.adds -= count(" + ") + count(" - ") + (value.rfind('-', 0) == 0 ? 1 : 0);
        ops.muls -= count(" * ");
        it = lines.erase(it);
        dropped = true;
      }
    }
    std::string out;
    for (const auto& l : lines) out += l + "\n";
    return out;
  }
  std::string code;
  OpCount ops;
};
using Term = ScalarWriter::Term;

// (x cross y)_c as two terms.
std::vector<Term> cross_terms(const std::array<std::string, 3>& x, const std::array<std::string, 3>& y, int c) {
  const auto c1 = static_cast<std::size_t>((c + 1) % 3), c2 = static_cast<std::size_t>((c + 2) % 3);
  return {{x[c1], y[c2]}, {x[c2], y[c1], true}};
}

}  // namespace

FunctionSpec derive_generalized_forces(const Model& m) {
  const Dynamics& dyn = *m.dynamics;
  const int nu = static_cast<int>(dyn.commanded.size());
  FunctionSpec fn{"generalized_forces", "generalized_forces.hpp",
                  "The inverse dynamics of the bodies by the recursive Newton-Euler equations, without the mass "
                  "matrix: from s, s' and s'' the joints' spatial velocities and accelerations out along the chains, "
                  "each body's force m (a + g e_z) and moment I alpha + omega x I omega, their wrenches summed back "
                  "along the chains, and each moving coordinate's generalized force tau (the bodies' inertia, "
                  "velocity and gravity forces on s). Projected on the commanded speeds, Q* = T^T tau: with "
                  "s' = T u and s'' = T u' + s''_bias this is M u' + b - Q_gravity (reduced_dynamics) at a cost "
                  "linear in the number of joints.",
                  true, {}};
  fn.inputs = {{"sddot", "Coordinates",
                "s'', the accelerations of the coordinates (T u' + s''_bias in a step); with s' zero on the inputs held in a "
                "step (T's zero rows, whose joints this pass leaves out)"},
               {"T", "RateBasis",
                "s' = T u, as for reduced_dynamics: only the rows of the dependent pair and of the dependent joints are "
                "read, and in them only the entries kRateBasisPattern marks"}};
  const RateRoles roles = rate_roles(m);
  const auto dense = [&](int j) { return roles.dense[static_cast<std::size_t>(j)]; };
  const auto scalar = [&](const std::string& name, const ex& value) { return lane_scalar(fn, name, value); };
  using V3 = std::array<std::string, 3>;
  using V6 = std::array<std::string, 6>;
  const auto head = [](const V6& v) { return V3{v[0], v[1], v[2]}; };
  const auto tail = [](const V6& v) { return V3{v[3], v[4], v[5]}; };
  TwistTree tree = twist_tree(m, roles);
  ScalarWriter w;
  const std::string one = ScalarWriter::kOne;

  // Out along the chains: a joint's spatial axis S = (a; o x a) (revolute, axis a through o) or
  // (0; a) (prismatic), in K0; V = V_parent + S s'_j; A = A_parent + S s''_j + (V_parent x S) s'_j
  // (the axis moves with the parent: d/dt S = V_parent x S, the motion cross product).
  std::vector<V6> axis(tree.nodes.size()), velocity(tree.nodes.size()), acceleration(tree.nodes.size());
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    const TwistNode& node = tree.nodes[k];
    const JointRecord& joint = *node.joint;
    const std::array<ex, 6> S = spatial_axis(joint);
    for (std::size_t c = 0; c < 6; ++c) axis[k][c] = scalar(fmt::format("kane_S_{}_{}", k, c), S[c]);
    const std::string sd = fmt::format("sdot({})", joint.coordinate), sdd = fmt::format("sddot({})", joint.coordinate);
    const V6 V0 = node.parent < 0 ? V6{} : velocity[static_cast<std::size_t>(node.parent)];
    const V6 A0 = node.parent < 0 ? V6{} : acceleration[static_cast<std::size_t>(node.parent)];
    // V_parent x S = (w x a; w x b + v x a).
    V6 X;
    for (int c = 0; c < 3; ++c) {
      X[static_cast<std::size_t>(c)] = w.define(fmt::format("kane_X{}_{}", k, c), cross_terms(head(V0), head(axis[k]), c));
      std::vector<Term> lin = cross_terms(head(V0), tail(axis[k]), c);
      for (const Term& t : cross_terms(tail(V0), head(axis[k]), c)) lin.push_back(t);
      X[static_cast<std::size_t>(c + 3)] = w.define(fmt::format("kane_X{}_{}", k, c + 3), lin);
    }
    for (std::size_t c = 0; c < 6; ++c) {
      velocity[k][c] = w.define(fmt::format("kane_V{}_{}", k, c), {{V0[c], one}, {axis[k][c], sd}});
      acceleration[k][c] = w.define(fmt::format("kane_A{}_{}", k, c), {{A0[c], one}, {axis[k][c], sdd}, {X[c], sd}});
    }
  }

  // Each body: its CoM's velocity v = V_lin + omega x p and acceleration a = A_lin + alpha x p +
  // omega x v; force F = m (a + g e_z); moment in body axes N = I alpha_b + omega_b x I omega_b;
  // wrench about K0's origin (F; R N + p x F).
  const std::string g = scalar("kane_g", m.parameter(dyn.gravity).symbol);
  std::vector<V6> wrench(m.bodies.size());
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const int at_node = tree.body_node[i];
    if (at_node < 0) continue;
    const Body& body = m.bodies[i];
    const Frame& f = body.com_frame;
    const V6& V = velocity[static_cast<std::size_t>(at_node)];
    const V6& A = acceleration[static_cast<std::size_t>(at_node)];
    const auto name = [&](const char* what, int c) { return fmt::format("kane_{}{}_{}", what, i, c); };
    w.code += "    // " + text::cpp_comment(fmt::format("body {}: {}", body.name, body.meaning)) + "\n";
    V3 p, v, a, F, wb, ab, Iw, N, M;
    std::array<std::string, 9> R;
    for (int c = 0; c < 3; ++c) p[static_cast<std::size_t>(c)] = scalar(fmt::format("kane_p_{}_{}", i, c), f.r[c]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) R[static_cast<std::size_t>(3 * r + c)] = scalar(fmt::format("kane_R_{}_{}_{}", i, r, c), f.R(r, c));
    const auto Rrc = [&](int r, int c) -> const std::string& { return R[static_cast<std::size_t>(3 * r + c)]; };
    const std::string mass = scalar(fmt::format("kane_mass_{}", i), m.parameter(body.mass).symbol);
    V3 I;
    for (int c = 0; c < 3; ++c)
      I[static_cast<std::size_t>(c)] = scalar(fmt::format("kane_inertia_{}_{}", i, c), m.parameter(body.inertia[static_cast<std::size_t>(c)]).symbol);
    for (int c = 0; c < 3; ++c) {
      std::vector<Term> t = cross_terms(head(V), p, c);
      t.insert(t.begin(), {V[static_cast<std::size_t>(c + 3)], one});
      v[static_cast<std::size_t>(c)] = w.define(name("v", c), t);
    }
    for (int c = 0; c < 3; ++c) {
      std::vector<Term> t = cross_terms(head(A), p, c);
      for (const Term& x : cross_terms(head(V), v, c)) t.push_back(x);
      t.insert(t.begin(), {A[static_cast<std::size_t>(c + 3)], one});
      if (c == 2) t.push_back({g, one});
      a[static_cast<std::size_t>(c)] = w.define(name("a", c), t);
      F[static_cast<std::size_t>(c)] = w.define(name("F", c), {{mass, a[static_cast<std::size_t>(c)]}});
    }
    for (int c = 0; c < 3; ++c) {
      wb[static_cast<std::size_t>(c)] = w.define(name("wb", c), {{Rrc(0, c), V[0]}, {Rrc(1, c), V[1]}, {Rrc(2, c), V[2]}});
      ab[static_cast<std::size_t>(c)] = w.define(name("ab", c), {{Rrc(0, c), A[0]}, {Rrc(1, c), A[1]}, {Rrc(2, c), A[2]}});
    }
    for (int c = 0; c < 3; ++c) Iw[static_cast<std::size_t>(c)] = w.define(name("Iw", c), {{I[static_cast<std::size_t>(c)], wb[static_cast<std::size_t>(c)]}});
    for (int c = 0; c < 3; ++c) {
      std::vector<Term> t = cross_terms(wb, Iw, c);
      t.insert(t.begin(), {I[static_cast<std::size_t>(c)], ab[static_cast<std::size_t>(c)]});
      N[static_cast<std::size_t>(c)] = w.define(name("N", c), t);
    }
    for (int c = 0; c < 3; ++c) {
      std::vector<Term> t = cross_terms(p, F, c);
      for (int k = 0; k < 3; ++k) t.push_back({Rrc(c, k), N[static_cast<std::size_t>(k)]});
      M[static_cast<std::size_t>(c)] = w.define(name("M", c), t);
    }
    wrench[i] = {F[0], F[1], F[2], M[0], M[1], M[2]};
  }

  // Back along the chains: the wrenches beyond each joint, tau_j = S . (moment; force).
  w.code += "    // Back along the chains: the wrenches beyond each joint and the joints' generalized forces.\n";
  std::vector<V6> beyond(tree.nodes.size());
  // A component of a joint's wrench sum is read by its tau where the axis has the matching component
  // (force with the linear part, moment with the angular), and by the joints before it that read it.
  std::vector<std::array<bool, 6>> read(tree.nodes.size());
  for (std::size_t k = 0; k < tree.nodes.size(); ++k)
    for (std::size_t c = 0; c < 6; ++c)
      read[k][c] = !axis[k][c < 3 ? c + 3 : c - 3].empty() ||
                   (tree.nodes[k].parent >= 0 && read[static_cast<std::size_t>(tree.nodes[k].parent)][c]);
  std::map<int, std::vector<Term>> tau_terms;  // coordinate -> its joints' taus
  for (std::size_t k = tree.nodes.size(); k-- > 0;) {
    const TwistNode& node = tree.nodes[k];
    for (std::size_t c = 0; c < 6; ++c) {
      if (!read[k][c]) continue;
      std::vector<Term> parts;
      for (int i : node.bodies) parts.push_back({wrench[static_cast<std::size_t>(i)][c], one});
      for (int child : node.children) parts.push_back({beyond[static_cast<std::size_t>(child)][c], one});
      beyond[k][c] = w.define(fmt::format("kane_W{}_{}", k, c), parts);
    }
    std::vector<Term> t;
    for (std::size_t c = 0; c < 3; ++c) t.push_back({axis[k][c], beyond[k][c + 3]});
    for (std::size_t c = 0; c < 3; ++c) t.push_back({axis[k][c + 3], beyond[k][c]});
    const std::string tau = w.define(fmt::format("kane_tau{}", k), t);
    if (!tau.empty()) tau_terms[node.joint->coordinate].push_back({tau, one});
  }
  std::map<int, std::string> tau_of;
  for (const auto& [j, terms] : tau_terms) {
    const std::string t = w.define(fmt::format("kane_tau_s{}", j), terms);
    if (!t.empty()) tau_of[j] = t;
  }
  // Q*_l = sum_j T(j, l) tau_j: a commanded speed's coordinate adds its tau to its row; a dense
  // coordinate's, times T(j, l), to the rows of the speeds its rate depends on (kRateBasisPattern).
  const std::vector<std::vector<int>> speeds_of = rate_speeds(m, roles);
  w.code += "    if (Qstar != nullptr) {\n";
  for (int l = 0; l < nu; ++l) {
    std::vector<Term> t;
    for (const auto& [j, tau] : tau_of) {
      if (roles.speed_of[static_cast<std::size_t>(j)] == l) t.push_back({tau, one});
      else if (dense(j) && std::binary_search(speeds_of[static_cast<std::size_t>(j)].begin(), speeds_of[static_cast<std::size_t>(j)].end(), l))
        t.push_back({fmt::format("T({}, {})", j, l), tau});
    }
    const std::string q = w.define(fmt::format("kane_Q{}", l), t);
    w.code += fmt::format("    (*Qstar)({}) = {};\n", l, q.empty() ? "Scalar(0)" : q);
  }
  w.code += "    }\n    if (tau != nullptr) {\n      tau->setZero();\n";
  for (const auto& [j, t] : tau_of) w.code += fmt::format("      (*tau)({}) = {};\n", j, t);
  w.code += "    }\n";
  fn.lane_code = w.finish();
  // A body whose rotation or offset the recursion never reads (one link on a fixed joint: its
  // wrench needs only p and the mass) leaves those scalars unread: they are not computed.
  const auto words = identifiers(fn.lane_code);
  const std::set<std::string> lane_words(words.begin(), words.end());
  std::erase_if(fn.lane_scalars, [&](const auto& named) { return !lane_words.count(named.first); });
  // The pass runs for either output: its operations are Q*'s (tau adds no operation of its own).
  OutputSpec Qo{"Qstar", "CommandVector", "M u' + b - Q_gravity for s'' = sddot: T^T tau, the forces the actuators must supply on u", "", {}};
  OutputSpec to{"tau", "Coordinates", "the bodies' generalized inertia, velocity and gravity forces on each coordinate (0 on the held inputs; computed with Qstar)", "", {}};
  Qo.from_lanes = to.from_lanes = true;
  Qo.lane_ops = w.ops;
  fn.outputs = {Qo, to};
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
