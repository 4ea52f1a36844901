// The model file's sections on how the machine is run: dynamics (actuators, weights, torque limits),
// clearance, contacts, joint limits, the nominal state and the inverse kinematics sweeps.
#include "model_file_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace wlx::codegen::model_file_detail {

void Parser::dynamics(const Item& section) {
  if (m_.bodies.empty()) section.fail("inverse dynamics needs bodies");
  const Fields f(section, {"gravity", "commanded", "pair", "actuated", "weights", "torque_limits"});
  Dynamics d;
  d.gravity = parameter(f["gravity"], ParameterKind::gravity).name;
  // The wheels' dependent rates: a named pair (any model with wheels), none without wheels.
  static const DependentPair no_pair{"none", {}};
  const DependentPair* pair = &no_pair;
  if (m_.wheels.empty()) {
    if (auto p = f.optional("pair")) p->fail("the model has no wheels, so no dependent rates: leave `pair` out");
    d.pair = no_pair.name;
  } else {
    d.pair = f["pair"].name();
    pair = nullptr;
    for (const auto& p : m_.pairs)
      if (p.name == d.pair) pair = &p;
    if (pair == nullptr) f["pair"].fail(fmt::format("no pair '{}' under nonholonomic.pairs", d.pair));
  }
  for (const Item& c : f["commanded"].list()) {
    const int k = coordinate_index(c, true);
    if (std::count(d.commanded.begin(), d.commanded.end(), k)) c.fail("listed twice");
    if (std::count(pair->coordinates.begin(), pair->coordinates.end(), k)) c.fail("a commanded rate cannot be one of the dependent pair");
    d.commanded.push_back(k);
  }
  if (d.commanded.empty()) f["commanded"].fail("name at least one commanded speed");
  // An actuator is a joint (a coordinate's name) or a wheel's drive ({wheel: NAME}, or from a URDF
  // the name of the wheel's continuous joint, which then names the drive).
  const auto wheel_of_urdf_joint = [&](const std::string& joint) {
    for (std::size_t w = 0; w < m_.wheels.size(); ++w)
      if (const auto u = urdf_axle_.find(m_.wheels[w].hub); u != urdf_axle_.end() && u->second.joint == joint)
        return static_cast<int>(w);
    return -1;
  };
  const auto wheel_named = [&](const Item& it) {
    const std::string wheel = it.name();
    std::vector<std::string> names;
    for (std::size_t w = 0; w < m_.wheels.size(); ++w) {
      if (m_.wheels[w].name == wheel) return static_cast<int>(w);
      names.push_back(m_.wheels[w].name);
    }
    it.fail(fmt::format("no wheel '{}' under wheels{}", wheel, suggestion(wheel, names)));
  };
  // The drive of wheel w; `at` is where a message points, `own_name` the file's name for it.
  const auto drive = [&](const Item& at, int w, const std::optional<Item>& own_name) {
    const NonholonomicWheel& wheel = m_.wheels[static_cast<std::size_t>(w)];
    if (wheel.hub.empty())
      at.fail(fmt::format("wheel '{}' has no hub (its contact frame is built by the file): its spin is a joint "
                          "of the file's, so actuate that joint instead; a drive needs a wheel on a hub",
                          wheel.name));
    const auto u = urdf_axle_.find(wheel.hub);
    Actuator a;
    a.wheel = w;
    a.name = own_name ? own_name->name() : u != urdf_axle_.end() ? u->second.joint : "spin_" + wheel.name;
    for (const auto& q : m_.coordinates)
      if (q.name == a.name)
        at.fail(fmt::format("the drive of wheel '{}' is named '{}', as is a coordinate: rename the coordinate",
                            wheel.name, a.name));
    return a;
  };
  for (const Item& c : f["actuated"].list()) {
    Actuator a;
    if (c.is_map()) {
      const Fields af(c, {"wheel", "name"});
      a = drive(af["wheel"], wheel_named(af["wheel"]), af.optional("name"));
    } else if (const int w = wheel_of_urdf_joint(c.text()); w >= 0) {
      a = drive(c, w, std::nullopt);
    } else {
      a.coordinate = coordinate_index(c);
      a.name = m_.coordinates[static_cast<std::size_t>(a.coordinate)].name;
    }
    for (const Actuator& b : d.actuated)
      if (b.name == a.name) c.fail("listed twice");
    d.actuated.push_back(std::move(a));
  }
  if (d.actuated.size() < d.commanded.size())
    f["actuated"].fail(fmt::format("{} actuated joints for {} commanded speeds: the actuators cannot produce every generalized "
                                   "force on the commanded speeds (give at least as many actuated joints as commanded speeds)",
                                   d.actuated.size(), d.commanded.size()));
  if (auto w = f.optional("weights")) {
    for (const Item& x : w->list()) {
      const double v = x.number();
      if (!(v > 0)) x.fail(fmt::format("a weight must be positive, got {}", v));
      d.weights.push_back(v);
    }
    if (d.weights.size() != d.actuated.size()) w->fail(fmt::format("one weight per actuated joint: {} needed", d.actuated.size()));
  } else {
    d.weights.assign(d.actuated.size(), 1.0);
  }
  // The actuators' limits, which the contact-keeping torque distribution respects. Bounded like
  // every number a model file gives: 1e9 N m is beyond any machine's drive.
  if (auto l = f.optional("torque_limits")) {
    for (const Item& x : l->list()) {
      const double v = x.number();
      if (!(v > 0 && v <= 1e9)) x.fail(fmt::format("a torque limit must be in (0, 1e9] N m, got {}", v));
      d.torque_limits.push_back(v);
    }
    if (d.torque_limits.size() != d.actuated.size())
      l->fail(fmt::format("one limit per actuator: {} needed", d.actuated.size()));
  } else {
    // Without torque_limits, the joints' efforts (`limits`, a URDF's <limit effort>) and the
    // drives' (their wheel joint's <limit effort>), when every actuator has one.
    std::vector<double> efforts;
    for (const Actuator& a : d.actuated) {
      double e = 0;
      if (a.coordinate >= 0) {
        e = m_.effort[static_cast<std::size_t>(a.coordinate)];
      } else if (const auto u = urdf_axle_.find(m_.wheels[static_cast<std::size_t>(a.wheel)].hub); u != urdf_axle_.end()) {
        if (const auto l = urdf_limits_.find(u->second.joint); l != urdf_limits_.end() && l->second.effort) e = *l->second.effort;
      }
      if (!(e > 0)) break;
      efforts.push_back(e);
    }
    if (efforts.size() == d.actuated.size()) {
      d.torque_limits = std::move(efforts);
      d.torque_limits_from_efforts = true;
    }
  }
  m_.dynamics = std::move(d);
}

void Parser::clearance(const Item& section) {
  const Fields f(section, {"frame", "size"});
  ClearanceBox box;
  box.frame = m_.frames[static_cast<std::size_t>(frame_index(f["frame"]))].name;
  const Vec3 size = vector3(f["size"]);
  box.size = {size[0], size[1], size[2]};
  m_.clearance = std::move(box);
}

// Friction coefficients per kind of contact. Bounded: no ground grips with mu above 10 (rubber on
// dry concrete is about 1); a coefficient of 0 would make every tangential force a slip.
void Parser::contacts(const Item& section) {
  const Fields f(section, {"friction"});
  const Item friction_item = f["friction"];  // (Fields keeps a reference)
  const Fields friction(friction_item, {"feet", "wheels"});
  for (auto [key, value] : {std::pair{"feet", &m_.friction.feet}, std::pair{"wheels", &m_.friction.wheels}}) {
    const std::optional<Item> item = friction.optional(key);
    if (!item) continue;
    const double mu = item->number();
    if (!(mu > 0 && mu <= 10))
      item->fail(fmt::format("a friction coefficient must be in (0, 10], got {}", mu));
    *value = mu;
  }
}

// The joints' limits: the URDF's <limit>s, then the file's `limits` entries, which replace what
// they give field by field. A range is checked against nothing else here: the nominal state
// may lie outside it (the runtime then says so), and Newton's starts are starts.
void Parser::limits(const std::optional<Item>& section) {
  const std::size_t n = m_.coordinates.size();
  const double inf = std::numeric_limits<double>::infinity();
  m_.lower.assign(n, -inf);
  m_.upper.assign(n, inf);
  m_.effort.assign(n, 0.0);
  m_.velocity.assign(n, 0.0);
  for (const auto& entry : urdf_limits_) {
    const std::string& joint = entry.first;
    const UrdfLimit& l = entry.second;
    const auto c = std::find_if(m_.coordinates.begin(), m_.coordinates.end(), [&](const Coordinate& x) { return x.name == joint; });
    if (c == m_.coordinates.end()) continue;  // a wheel's spin: its effort is its drive's (dynamics)
    const auto k = static_cast<std::size_t>(c - m_.coordinates.begin());
    if (l.lower) m_.lower[k] = *l.lower, m_.upper[k] = *l.upper;
    if (l.effort && *l.effort > 0) m_.effort[k] = *l.effort;
    if (l.velocity && *l.velocity > 0) m_.velocity[k] = *l.velocity;
  }
  if (!section) return;
  std::set<int> given;
  each(*section, [&](const Item& it) {
    const Fields f(it, {"joint", "lower", "upper", "effort", "velocity"});
    const int k = coordinate_index(f["joint"]);
    const auto kk = static_cast<std::size_t>(k);
    if (!given.insert(k).second) f["joint"].fail(fmt::format("'{}' has limits already: give them once", m_.coordinates[kk].name));
    const auto lower = f.optional("lower"), upper = f.optional("upper");
    if (lower.has_value() != upper.has_value())
      (lower ? *lower : *upper).fail("a range needs both `lower` and `upper`");
    if (lower) {
      const double lo = lower->number(true), hi = upper->number(true);
      for (const auto& [item, v] : {std::pair{&*lower, lo}, std::pair{&*upper, hi}})
        if (!(std::abs(v) <= 1e6)) item->fail(fmt::format("must be within [-1e6, 1e6], got {}", v));
      if (!(lo < hi)) lower->fail(fmt::format("lower ({}) must be below upper ({})", lo, hi));
      m_.lower[kk] = lo;
      m_.upper[kk] = hi;
    }
    for (const auto& [key, out] : {std::pair{"effort", &m_.effort}, std::pair{"velocity", &m_.velocity}})
      if (auto x = f.optional(key)) {
        const double v = x->number(true);
        if (!(v > 0 && v <= 1e9)) x->fail(fmt::format("must be in (0, 1e9], got {}", v));
        (*out)[kk] = v;
      }
  });
}

// The inputs' nominal values, and for dependent joints the start of Newton's method (a limb's
// own `start` takes precedence).
void Parser::nominal(const std::optional<Item>& section) {
  m_.nominal.assign(m_.coordinates.size(), 0.0);
  if (section) {
    if (!section->is_map()) section->fail("must map coordinate names to values");
    for (const auto& kv : section->node()) {
      const Item key(src_, kv.first, section->path(), {});
      const int k = coordinate_index(key);
      if (limb_start_.count(k))
        key.fail(fmt::format("'{}' has a start value in its limb's `start` already: give it once",
                             m_.coordinates[static_cast<std::size_t>(k)].name));
      m_.nominal[static_cast<std::size_t>(k)] = section->child(kv.first.Scalar()).number(true);
    }
  }
  for (const auto& [k, value] : limb_start_) m_.nominal[static_cast<std::size_t>(k)] = value;
}

void Parser::sweeps(const std::optional<Item>& section) {
  m_.sweep_start.assign(m_.nominal.begin(), m_.nominal.begin() + m_.input_count);
  if (!section) return;
  const Fields f(*section, {"start", "sweeps"});
  if (auto start = f.optional("start")) {
    if (!start->is_map()) start->fail("must map input names to values");
    for (const auto& kv : start->node()) {
      const Item key(src_, kv.first, start->path(), {});
      m_.sweep_start[static_cast<std::size_t>(coordinate_index(key, true))] =
          start->child(kv.first.Scalar()).number(true);
    }
  }
  each(f["sweeps"], [&](const Item& it) {
    const Fields s(it, {"id", "input", "from", "to", "step", "unit", "limb", "branch"});
    IkSweep sw;
    sw.id = s["id"].text();
    for (const auto& other : m_.sweeps)
      if (other.id == sw.id) s["id"].fail(fmt::format("sweep '{}' is defined twice", sw.id));
    sw.input = coordinate_index(s["input"], true);
    double scale = 1;
    if (auto unit = s.optional("unit")) {
      const std::string u = unit->text();
      const std::string& own = m_.coordinates[static_cast<std::size_t>(sw.input)].unit;
      if (u == "deg" && own == "rad") {
        sw.degrees = true;
        scale = std::numbers::pi / 180;
      } else if (u != own) {
        unit->fail(fmt::format("'{}' is in {}; give the sweep in {}{}", m_.coordinates[static_cast<std::size_t>(sw.input)].name, own,
                               own, own == "rad" ? " or deg" : ""));
      }
    }
    sw.from = s["from"].number(true) * scale;
    sw.to = s["to"].number(true) * scale;
    sw.step = s["step"].number(true) * scale;
    if (!(sw.step > 0)) s["step"].fail("a step must be positive");
    if (std::abs(sw.to - sw.from) / sw.step > 1e6) s["step"].fail("more than 10^6 points");
    const std::string limb = s["limb"].name();
    for (std::size_t k = 0; k < m_.limbs.size(); ++k)
      if (m_.limbs[k].name == limb) sw.limb = static_cast<int>(k);
    if (sw.limb < 0) s["limb"].fail(fmt::format("no limb '{}'", limb));
    // The branch the sweep checks (checked against the closed form's branches at run time, as
    // every branch a file or a request gives: settings).
    if (auto b = s.optional("branch")) sw.branch = b->branch();
    m_.sweeps.push_back(std::move(sw));
  });
}

}  // namespace wlx::codegen::model_file_detail
