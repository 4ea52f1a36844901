// The model file's sections that build the machine: parameters, coordinates, frames (built
// parents first), bodies, and wheels (a wheel on a hub adds its contact frame).
#include "model_file_internal.hpp"

#include <fmt/ranges.h>

#include <algorithm>

namespace wlx::codegen::model_file_detail {

void Parser::parameters(const Item& list) {
  each(list, [&](const Item& it) {
    const Fields f(it, {"name", "value", "unit", "kind", "meaning"});
    const std::string n = f["name"].name();
    claim_symbol_name(f["name"], n);
    const Item kind_item = f["kind"];
    const std::string kind = kind_item.text();
    static const std::map<std::string, std::pair<ParameterKind, const char*>> kinds = {
        {"length", {ParameterKind::length, "m"}},   {"offset", {ParameterKind::offset, "m"}},
        {"angle", {ParameterKind::angle, "rad"}},   {"mass", {ParameterKind::mass, "kg"}},
        {"inertia", {ParameterKind::inertia, "kg*m^2"}}, {"gravity", {ParameterKind::gravity, "m/s^2"}},
        {"other", {ParameterKind::other, nullptr}}};
    const auto k = kinds.find(kind);
    if (k == kinds.end()) {
      std::vector<std::string> names;
      for (const auto& kv : kinds) names.push_back(kv.first);
      kind_item.fail(fmt::format("unknown kind '{}'{}; the kinds are {}", excerpt(kind), suggestion(kind, names), fmt::join(names, ", ")));
    }
    const std::string unit = f["unit"].text();
    if (k->second.second != nullptr && unit != k->second.second)
      f["unit"].fail(fmt::format("a parameter of kind {} has unit {}, not '{}'", kind, k->second.second, excerpt(unit)));
    const double value = f["value"].number();
    const ParameterKind pk = k->second.first;
    if (const std::string why = parameter_value_problem(pk, value); !why.empty())
      f["value"].fail(fmt::format("{} {}, got {}", pk == ParameterKind::gravity ? "gravity" : "a " + kind, why, value));
    m_.parameters.push_back({n, value, unit, f.optional("meaning") ? f["meaning"].text() : "", GiNaC::realsymbol(n)});
    m_.parameter_kinds.push_back(pk);
    params_[n] = m_.parameters.back().symbol;
    param_defaults_[m_.parameters.back().symbol] = value;
    symbol_kind_[n] = "parameter";
  });
  if (m_.parameters.empty()) list.fail("a model needs at least one parameter");
}

void Parser::coordinate(const Item& it) {
  const Fields f(it, {"name", "unit", "meaning"});
  const std::string n = f["name"].name();
  claim_symbol_name(f["name"], n);
  const std::string unit = f["unit"].text();
  if (unit != "m" && unit != "rad") f["unit"].fail(fmt::format("a coordinate is in m or rad, not '{}'", excerpt(unit)));
  if (m_.coordinates.size() == kMaxCoordinates) it.fail(fmt::format("a model has at most {} coordinates", kMaxCoordinates));
  const int index = static_cast<int>(m_.coordinates.size());
  m_.coordinates.push_back({n, index, GiNaC::realsymbol(n), GiNaC::realsymbol(n + "_dot"), unit,
                            f.optional("meaning") ? f["meaning"].text() : ""});
  coordinates_[n] = m_.coordinates.back().q;
  symbol_kind_[n] = "coordinate";
}

void Parser::coordinates(const Item& c) {
  const Fields f(c, {"inputs", "dependent"});
  each(f["inputs"], [&](const Item& it) { coordinate(it); });
  m_.input_count = static_cast<int>(m_.coordinates.size());
  if (m_.input_count == 0) f["inputs"].fail("a model needs at least one input");
  if (auto d = f.optional("dependent")) each(*d, [&](const Item& it) { coordinate(it); });
}

// Frames may name parents listed after them; they are built parents first, with cycles found.
void Parser::frames(const Item& list) {
  std::vector<Item> entries;
  each(list, [&](const Item& it) { entries.push_back(it); });
  if (entries.empty()) list.fail("a model needs at least one frame");
  if (entries.size() > kMaxFrames) list.fail(fmt::format("has {} frames; a model has at most {}", entries.size(), kMaxFrames));
  std::map<std::string, std::size_t> by_name;
  std::vector<std::string> names;
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const Fields f(entries[k], {"name", "meaning", "parent", "chain"});
    const std::string n = f["name"].name();
    if (n == "K0") f["name"].fail("K0 is the ground frame and cannot be defined");
    if (by_name.count(n)) f["name"].fail(fmt::format("frame '{}' is defined twice", n));
    by_name[n] = k;
    names.push_back(n);
  }
  m_.frames.resize(entries.size());
  // Each frame is built after its parent. The order comes from walking up the parents without
  // recursion, so no file decides the depth of the generator's stack (10^5 chained frames once
  // overflowed it); the depth of a chain is bounded too (its expressions grow with it).
  std::vector<int> state(entries.size(), 0);  // 0 not built, 1 on the walk, 2 built
  std::vector<std::size_t> parent_of(entries.size(), entries.size());  // entries.size(): K0
  std::vector<std::size_t> depth_of(entries.size(), 0);  // frames from K0, once built
  const auto build_one = [&](std::size_t k) {
    NamedFrame& out = m_.frames[k];
    const Item& it = entries[k];
    const Fields f(it, {"name", "meaning", "parent", "chain"});
    out.name = names[k];
    out.meaning = f.optional("meaning") ? f["meaning"].text() : "";
    Frame frame = parent_of[k] == entries.size() ? Frame::ground() : m_.frames[parent_of[k]].frame;
    for (const Item& step : f["chain"].list()) {
      if (!step.is_map() || step.size() != 1)
        step.fail("a chain step is one of tx, ty, tz, rx, ry, rz: <coordinate or expression>, or translate: [x, y, z]");
      const std::string op = step.node().begin()->first.Scalar();
      const Item arg = step.child(op);
      ChainStep cs;
      if (op == "translate") {
        cs.kind = ChainStep::Kind::Translate;
        cs.offset = vector3(arg);
        frame = frame.translated(cs.offset);
      } else if (op.size() == 2 && (op[0] == 't' || op[0] == 'r') && op[1] >= 'x' && op[1] <= 'z') {
        cs.axis = static_cast<Axis>(op[1] - 'x');
        const ex e = expression(arg, true);
        const bool rotation = op[0] == 'r';
        // `rz: q` is a joint; so is `rz: -q`, about (along) the negative axis (URDF's axis 0 0 -1).
        const auto joint_symbol = [&](const ex& x) {
          return GiNaC::is_a<GiNaC::symbol>(x) && coordinates_.count(GiNaC::ex_to<GiNaC::symbol>(x).get_name());
        };
        const int sign = joint_symbol(e) ? 1 : joint_symbol(-e) ? -1 : 0;
        if (sign != 0) {
          const Coordinate& c = m_.coordinate(GiNaC::ex_to<GiNaC::symbol>(sign > 0 ? e : -e).get_name());
          if (rotation && c.unit != "rad") arg.fail(fmt::format("'{}' turns a revolute joint, so its unit must be rad, not {}", c.name, c.unit));
          if (!rotation && c.unit != "m") arg.fail(fmt::format("'{}' drives a prismatic joint, so its unit must be m, not {}", c.name, c.unit));
          for (const auto& [user, at] : joint_users_)
            if (user == c.index) arg.fail(fmt::format("coordinate '{}' already drives a joint (at {})", c.name, at));
          joint_users_.emplace_back(c.index, arg.path());
          cs.kind = rotation ? ChainStep::Kind::Rotate : ChainStep::Kind::Slide;
          cs.coordinate = c.index;
          cs.sign = sign;
          frame = rotation ? frame.rotated(cs.axis, c, sign) : frame.slid(cs.axis, c, sign);
        } else {
          for (const auto& kv : coordinates_)
            if (e.has(kv.second))
              arg.fail(fmt::format("a joint is driven by one coordinate alone (or its negative); '{}' mixes coordinate '{}' with other terms",
                                   excerpt(arg.text()), kv.first));
          if (rotation) {
            cs.kind = ChainStep::Kind::Turn;
            cs.angle = e;
            frame = frame.turned(cs.axis, e);
          } else {
            cs.kind = ChainStep::Kind::Translate;
            cs.offset[static_cast<int>(cs.axis)] = e;
            frame = frame.translated(cs.offset);
          }
        }
      } else {
        step.fail(fmt::format("unknown chain step '{}'{}; the steps are tx, ty, tz, rx, ry, rz, translate", excerpt(op),
                              suggestion(op, {"tx", "ty", "tz", "rx", "ry", "rz", "translate"})));
      }
      out.chain.push_back(cs);
    }
    out.frame = std::move(frame);
    state[k] = 2;
  };
  std::vector<std::size_t> walk;
  for (std::size_t k = 0; k < entries.size(); ++k) {
    walk.clear();
    for (std::size_t j = k; j != entries.size() && state[j] != 2;) {
      const Fields f(entries[j], {"name", "meaning", "parent", "chain"});
      if (state[j] == 1) {
        // The cycle is the walk from j's first visit; shown in full when short, else its ends.
        const auto first = std::find(walk.begin(), walk.end(), j);
        std::vector<std::string> cycle;
        for (auto w = first; w != walk.end(); ++w) cycle.push_back(names[*w]);
        cycle.push_back(names[j]);
        const std::string shown = cycle.size() <= 12 ? fmt::format("{}", fmt::join(cycle, " -> "))
                                                     : fmt::format("{} -> ... -> {} ({} frames)", fmt::join(cycle.begin(), cycle.begin() + 5, " -> "),
                                                                   fmt::join(cycle.end() - 5, cycle.end(), " -> "), cycle.size() - 1);
        f["parent"].fail(fmt::format("the frames' parents form a cycle: {}", shown));
      }
      state[j] = 1;
      walk.push_back(j);
      m_.frames[j].parent = f["parent"].name();
      if (m_.frames[j].parent == "K0") {
        parent_of[j] = entries.size();
        break;
      }
      const auto p = by_name.find(m_.frames[j].parent);
      if (p == by_name.end())
        f["parent"].fail(fmt::format("no frame '{}' (K0 is the ground){}", m_.frames[j].parent, suggestion(m_.frames[j].parent, names)));
      parent_of[j] = p->second;
      j = p->second;
    }
    // The walk ends at K0 or at a built frame: every frame on it is that much further from K0.
    const std::size_t end = walk.empty() ? entries.size() : parent_of[walk.back()];
    const std::size_t base = end == entries.size() ? 0 : depth_of[end];
    if (base + walk.size() > kMaxChainDepth)
      Fields(entries[k], {"name", "meaning", "parent", "chain"})["parent"].fail(
          fmt::format("frame '{}' is {} frames away from K0, more than {}: chains this deep are not a machine, and their "
                      "expressions would grow without bound",
                      names[k], base + walk.size(), kMaxChainDepth));
    for (std::size_t w = walk.size(); w-- > 0;) {
      depth_of[walk[w]] = base + walk.size() - w;
      build_one(walk[w]);
    }
  }
}

void Parser::bodies(const Item& list) {
  std::set<std::string> seen;
  each(list, [&](const Item& it) {
    const Fields f(it, {"name", "meaning", "frame", "com", "rotation", "mass", "inertia"});
    Body b;
    b.name = f["name"].name();
    if (!seen.insert(b.name).second) f["name"].fail(fmt::format("body '{}' is defined twice", b.name));
    b.meaning = f.optional("meaning") ? f["meaning"].text() : "";
    const int frame = frame_index(f["frame"]);
    b.frame = m_.frames[static_cast<std::size_t>(frame)].name;
    b.com = vector3(f["com"]);
    b.com_frame = m_.frames[static_cast<std::size_t>(frame)].frame.translated(b.com);
    // The principal axes, turned from the frame's (a URDF inertial's rpy, or the axes that
    // diagonalise its tensor): fixed turns of parameter expressions, applied in order.
    if (auto rotation = f.optional("rotation"))
      for (const Item& step : rotation->list()) {
        const std::string op = step.is_map() && step.size() == 1 ? step.node().begin()->first.Scalar() : "";
        if (op != "rx" && op != "ry" && op != "rz")
          step.fail("a rotation step is rx, ry or rz: <expression of parameters> (a fixed turn about the axes turned so far)");
        b.principal_turns.emplace_back(static_cast<Axis>(op[1] - 'x'), expression(step.child(op), false));
        b.com_frame = b.com_frame.turned(b.principal_turns.back().first, b.principal_turns.back().second);
      }
    b.mass = parameter(f["mass"], ParameterKind::mass).name;
    const Item inertia = f["inertia"];
    if (!inertia.is_sequence() || inertia.size() != 3)
      inertia.fail("must list the 3 principal moments about the CoM, in the frame's axes: [Ixx, Iyy, Izz]");
    for (std::size_t k = 0; k < 3; ++k) b.inertia[k] = parameter(inertia.element(k), ParameterKind::inertia).name;
    m_.bodies.push_back(std::move(b));
  });
}

// Two forms: a wheel on a hub (`hub`, `axle`: wlx-gen derives the contact frame `contact`,
// default contact_<name>), or a contact frame the file builds itself (`contact`, `forward`,
// `lateral`: virtual joints and level rows keep it on the rim's lowest point).
void Parser::wheels(const Item& list) {
  each(list, [&](const Item& it) {
    const bool on_hub = it.is_map() && it.has("hub");
    const Fields f(it, on_hub ? std::vector<std::string>{"name", "hub", "axle", "radius", "offset", "ground", "contact"}
                              : std::vector<std::string>{"name", "contact", "forward", "lateral", "radius", "ground"});
    NonholonomicWheel w;
    w.name = f["name"].name();
    for (const auto& other : m_.wheels)
      if (other.name == w.name) f["name"].fail(fmt::format("wheel '{}' is defined twice", w.name));
    // On a hub, a URDF's collision cylinder or sphere may give the radius and the offset (with_urdf).
    const auto shape = on_hub ? urdf_wheel_shape_.find(it.child("hub").text()) : urdf_wheel_shape_.end();
    w.radius = f.optional("radius") || shape == urdf_wheel_shape_.end() ? parameter(f["radius"], ParameterKind::length).name
                                                                        : shape->second.radius;
    if (auto o = f.optional("offset")) w.offset = parameter(*o, ParameterKind::offset).name;
    else if (shape != urdf_wheel_shape_.end() && !f.optional("radius")) w.offset = shape->second.offset;
    w.ground = coordinate_index(f["ground"], true);
    if (m_.coordinates[static_cast<std::size_t>(w.ground)].unit != "m")
      f["ground"].fail(fmt::format("'{}' is an angle; the ground level is a height (m)", m_.coordinates[static_cast<std::size_t>(w.ground)].name));
    if (!on_hub) {
      w.contact = m_.frames[static_cast<std::size_t>(frame_index(f["contact"]))].name;
      w.forward = axis_of(f["forward"]);
      w.lateral = axis_of(f["lateral"]);
      if (w.forward == w.lateral) f["lateral"].fail("the lateral axis must differ from the forward axis");
      m_.wheels.push_back(std::move(w));
      return;
    }
    const NamedFrame& hub = m_.frames[static_cast<std::size_t>(frame_index(f["hub"]))];
    if (hub.derived_from_wheel >= 0) f["hub"].fail(fmt::format("'{}' is a wheel's contact frame, not a hub", hub.name));
    w.hub = hub.name;
    w.axle = axis_of(f["axle"]);
    if (const auto u = urdf_axle_.find(w.hub); u != urdf_axle_.end() && u->second.axis != w.axle)
      f["axle"].fail(fmt::format("the URDF's joint '{}' ({}) turns the wheel about {} of '{}', not {}", u->second.joint,
                                 u->second.place, "xyz"[static_cast<int>(u->second.axis)], w.hub, "xyz"[static_cast<int>(w.axle)]));
    w.contact = f.optional("contact") ? f["contact"].name() : "contact_" + w.name;
    const Item& where = f.optional("contact") ? f["contact"] : f["name"];
    if (w.contact == "K0" || m_.frame_index(w.contact) >= 0)
      where.fail(fmt::format("the contact frame '{}' that wlx-gen derives for this wheel is already a frame: name it "
                             "with `contact:`",
                             w.contact));
    NamedFrame contact;
    contact.name = w.contact;
    contact.meaning = fmt::format("contact point of wheel {} (derived: the rim point nearest the ground)", w.name);
    contact.parent = hub.name;
    contact.frame = wheel_contact_frame(hub.frame, w.axle, m_.parameter(w.radius).symbol,
                                        w.offset.empty() ? ex(0) : ex(m_.parameter(w.offset).symbol), m_.coordinates);
    contact.derived_from_wheel = static_cast<int>(m_.wheels.size());
    m_.frames.push_back(std::move(contact));
    m_.wheels.push_back(std::move(w));
  });
}

}  // namespace wlx::codegen::model_file_detail

namespace wlx::codegen {

std::string parameter_value_problem(ParameterKind kind, double value) {
  if ((kind == ParameterKind::length || kind == ParameterKind::mass || kind == ParameterKind::inertia) && !(value > 0))
    return "must be positive";
  if (kind == ParameterKind::gravity && !(value >= 0)) return "must be non-negative";
  return {};
}

}  // namespace wlx::codegen
