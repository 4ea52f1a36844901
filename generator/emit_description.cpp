// model.json: the model as data, beside the generated code (emit.hpp, emit_description()).
#include "emit.hpp"
#include "structure_facts.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

namespace wlx::codegen {

namespace {

using Json = nlohmann::ordered_json;  // keys in the order written: the file is byte-identical run to run

// FNV-1a over the files' names and texts, twice with different offsets (128 bits): a fingerprint of
// the code, the key a plugin's cache is found by. Not a signature: it names, it does not protect.
std::string code_fingerprint(const std::vector<EmittedFile>& code) {
  std::uint64_t a = 14695981039346656037ull, b = 1099511628211ull * 31 + 7;
  const auto add = [&](const std::string& text) {
    for (const unsigned char c : text) {
      a = (a ^ c) * 1099511628211ull;
      b = (b ^ c) * 1099511628211ull + 0x9e3779b97f4a7c15ull;
    }
    a = (a ^ 0xff) * 1099511628211ull;  // a separator: ("ab", "c") and ("a", "bc") differ
  };
  for (const auto& f : code) {
    add(f.path);
    add(f.text);
  }
  return fmt::format("{:016x}{:016x}", a, b);
}


// An expression of parameters as the number it is at the description's parameter values (the code's
// baked ones, else the defaults). The model file's reader has checked every such expression finite
// at the defaults; one that is not a number here is a generator error, said as such.
class Evaluator {
 public:
  Evaluator(const Model& m, const EmitOptions& opt) {
    for (const auto& p : m.parameters) {
      const auto baked = opt.baked.find(p.name);
      values_[p.symbol] = baked == opt.baked.end() ? p.default_value : baked->second;
    }
  }
  double operator()(const ex& e, const std::string& what) const {
    const ex v = GiNaC::evalf(e.subs(values_));
    if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_real())
      throw std::runtime_error(fmt::format("wlx-gen: {} is not a number at the parameters' values", what));
    const double x = GiNaC::ex_to<GiNaC::numeric>(v).to_double();
    if (!std::isfinite(x)) throw std::runtime_error(fmt::format("wlx-gen: {} is not finite at the parameters' values", what));
    return x;
  }
  Json vector(const Vec3& v, const std::string& what) const {
    return Json::array({(*this)(v.e[0], what), (*this)(v.e[1], what), (*this)(v.e[2], what)});
  }

 private:
  GiNaC::exmap values_;
};

// A frame's chain as data: each step with its numbers at the parameters' values (docs/model-format.md,
// "The description"): what a reader needs to build the tree (an MJCF export, a peer library) without
// the generated functions.
Json chain_of(const Model& m, const NamedFrame& f, const Evaluator& number) {
  Json chain = Json::array();
  const std::string where = "frame " + f.name;
  for (const ChainStep& step : f.chain) {
    switch (step.kind) {
      case ChainStep::Kind::Translate: chain.push_back({{"translate", number.vector(step.offset, where)}}); break;
      case ChainStep::Kind::Turn: chain.push_back({{"turn", axis_name(step.axis)}, {"angle", number(step.angle, where)}}); break;
      case ChainStep::Kind::Rotate:
      case ChainStep::Kind::Slide:
        chain.push_back({{step.kind == ChainStep::Kind::Rotate ? "revolute" : "prismatic", axis_name(step.axis)},
                         {"coordinate", m.coordinates[static_cast<std::size_t>(step.coordinate)].name},
                         {"sign", step.sign}});
        break;
    }
  }
  return chain;
}

// The rotation from a body's frame axes to its principal axes (columns: the principal axes in the
// frame's), from its fixed turns.
Json principal_axes(const Body& b, const Evaluator& number) {
  double R[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const auto& [axis, angle] : b.principal_turns) {
    const double a = number(angle, "body " + b.name + " rotation"), c = std::cos(a), s = std::sin(a);
    const int i = (static_cast<int>(axis) + 1) % 3, j = (static_cast<int>(axis) + 2) % 3;  // the turn takes i towards j
    for (auto& row : R) {
      const double ri = row[i], rj = row[j];
      row[i] = c * ri + s * rj;
      row[j] = -s * ri + c * rj;
    }
  }
  Json rows = Json::array();
  for (const auto& row : R) rows.push_back(Json::array({row[0], row[1], row[2]}));
  return rows;
}

// The wheels' dependent rates: the inputs whose rates may be chosen, one per wheel, the named
// choices and the default one (a model without wheels has one choice, of no rates).
template <class Name>
Json pairs_description(const Model& m, const StructureFacts& facts, const Name& coordinate) {
  Json candidates = Json::array(), named = Json::array();
  for (int k : m.pair_candidates) candidates.push_back(coordinate(k));
  for (const auto& p : facts.pairs) {
    Json rates = Json::array();
    for (int k : p.coordinates) rates.push_back(coordinate(k));
    named.push_back({{"name", p.name}, {"rates", rates}});
  }
  return {{"candidates", candidates}, {"named", named},
          {"default", facts.pairs.empty() ? Json(nullptr) : Json(facts.pairs[static_cast<std::size_t>(facts.default_pair)].name)}};
}

}  // namespace

EmittedFile emit_description(const Model& m, const EmitOptions& opt, const std::vector<EmittedFile>& code) {
  const auto coordinate = [&](int k) { return m.coordinates[static_cast<std::size_t>(k)].name; };
  Json d;
  d["format"] = "wlx model description 1";
  d["model"] = m.name;
  d["description"] = m.description;
  d["generated_by"] = "wlx-gen " + opt.generator_version;
  d["source"] = m.source;
  d["code_key"] = code_fingerprint(code);
  d["data_at_run_time"] = opt.data_at_run_time;

  // Structure: names and what refers to what (the code's indices, by name).
  Json params = Json::array();
  for (std::size_t k = 0; k < m.parameters.size(); ++k) {
    const auto& p = m.parameters[k];
    const auto baked = opt.baked.find(p.name);  // a baked value is the one the code uses
    params.push_back({{"name", p.name}, {"value", baked == opt.baked.end() ? p.default_value : baked->second}, {"unit", p.unit},
                      {"kind", kind_name(m.parameter_kinds[k])}, {"meaning", p.meaning}});
  }
  d["parameters"] = params;
  Json coordinates = Json::array();
  for (const auto& c : m.coordinates)
    coordinates.push_back({{"name", c.name}, {"unit", c.unit}, {"input", c.index < m.input_count}, {"meaning", c.meaning}});
  d["coordinates"] = coordinates;
  const Evaluator number(m, opt);
  Json frames = Json::array();
  for (const auto& f : m.frames) {
    Json frame = {{"name", f.name}, {"parent", f.parent}, {"meaning", f.meaning}};
    if (f.derived_from_wheel >= 0) frame["derived_from_wheel"] = m.wheels[static_cast<std::size_t>(f.derived_from_wheel)].name;
    else frame["chain"] = chain_of(m, f, number);
    frames.push_back(frame);
  }
  d["frames"] = frames;
  Json bodies = Json::array();
  for (const auto& b : m.bodies)
    bodies.push_back({{"name", b.name}, {"frame", b.frame}, {"mass", b.mass}, {"inertia", b.inertia},
                      {"com", number.vector(b.com, "body " + b.name + " com")}, {"principal_axes", principal_axes(b, number)},
                      {"meaning", b.meaning}});
  d["bodies"] = bodies;
  Json wheels = Json::array();
  for (const auto& w : m.wheels)
    wheels.push_back({{"name", w.name}, {"contact", w.contact}, {"hub", w.hub}, {"radius", w.radius},
                      {"offset", w.offset.empty() ? Json(nullptr) : Json(w.offset)}, {"axle", axis_name(w.axle)},
                      {"forward", axis_name(w.forward)}, {"lateral", axis_name(w.lateral)},
                      {"ground", w.ground >= 0 ? coordinate(w.ground) : ""}});
  d["wheels"] = wheels;
  Json limbs = Json::array();
  const StructureFacts facts = structure_facts(m);
  for (std::size_t k = 0; k < m.limbs.size(); ++k) {
    const auto& l = m.limbs[k];
    Json joints = Json::array(), rows = Json::array(), inputs = Json::array();
    for (int j : l.joints) joints.push_back(coordinate(j));
    for (int r : l.rows) rows.push_back(m.closure[static_cast<std::size_t>(r)].name);
    // The inputs its closure rows read: what must be finite before the limb is solved.
    for (int i : facts.limb_inputs[k]) inputs.push_back(coordinate(i));
    limbs.push_back({{"name", l.name}, {"title", l.title}, {"joints", joints}, {"closure", rows}, {"inputs", inputs}});
  }
  d["limbs"] = limbs;
  d["pairs"] = pairs_description(m, facts, coordinate);
  const std::vector<GroundContact> contacts = ground_contacts(m);
  Json contact_list = Json::array();
  for (const auto& c : contacts)
    contact_list.push_back({{"name", c.name}, {"frame", m.frames[static_cast<std::size_t>(c.frame)].name},
                            {"kind", c.wheel >= 0 ? "wheel" : "foot"}, {"supports", c.point[2] >= 0}});
  d["contacts"] = contact_list;
  Json actuators = Json::array(), commanded = Json::array();
  if (m.dynamics) {
    for (const auto& a : m.dynamics->actuated) actuators.push_back(a.name);
    for (int k : m.dynamics->commanded) commanded.push_back(coordinate(k));
  }
  d["actuators"] = actuators;
  d["commanded"] = commanded;
  // What each actuator drives (a joint's coordinate, or a wheel on a hub), and gravity's parameter
  // (acting along -z of K0): for a reader that builds the machine elsewhere (wlx export mjcf).
  Json actuated = Json::array();
  if (m.dynamics)
    for (const auto& a : m.dynamics->actuated)
      actuated.push_back(a.wheel >= 0 ? Json{{"name", a.name}, {"wheel", m.wheels[static_cast<std::size_t>(a.wheel)].name}}
                                      : Json{{"name", a.name}, {"coordinate", coordinate(a.coordinate)}});
  d["actuated"] = actuated;
  d["gravity"] = m.dynamics ? Json(m.dynamics->gravity) : Json(nullptr);
  // The closure rows as the model file gives them.
  Json closure = Json::array();
  for (const auto& c : m.closure) {
    using K = ClosureCondition::Kind;
    if (c.kind == K::PointEqualsCoordinate)
      closure.push_back({{"name", c.name}, {"type", "point"}, {"frame", c.frame}, {"component", axis_name(c.axis)}, {"equals", coordinate(c.target)}});
    else if (c.kind == K::AttachedDirectionLevel)
      closure.push_back({{"name", c.name}, {"type", "level"}, {"frame", c.frame}, {"axis", axis_name(c.axis)}});
    else {
      Json sum = Json::array();
      for (int k : c.coordinates) sum.push_back(coordinate(k));
      closure.push_back({{"name", c.name}, {"type", "sum"}, {"coordinates", sum}});
    }
  }
  d["closure"] = closure;
  if (m.clearance) {
    Json size = Json::array();
    for (const auto& e : m.clearance->size) {
      std::ostringstream text;
      text << e;
      size.push_back(text.str());
    }
    d["clearance"] = {{"frame", m.clearance->frame}, {"size", size}};
  } else {
    d["clearance"] = nullptr;
  }

  // Settings: the model file's numbers that no generated function holds (with the parameters'
  // values above). A plugin's runtime reads them from here; settings.hpp compiles them in.
  Json settings;
  Json nominal = Json::object(), start = Json::object(), sweep_start = Json::object();
  for (int k = 0; k < static_cast<int>(m.nominal.size()); ++k)
    (k < m.input_count ? nominal : start)[coordinate(k)] = m.nominal[static_cast<std::size_t>(k)];
  for (int k = 0; k < static_cast<int>(m.sweep_start.size()); ++k) sweep_start[coordinate(k)] = m.sweep_start[static_cast<std::size_t>(k)];
  settings["nominal"] = nominal;
  settings["dependent_start"] = start;
  settings["sweep_start"] = sweep_start;
  Json sweeps = Json::array();
  for (const auto& sw : m.sweeps)
    sweeps.push_back({{"id", sw.id}, {"input", coordinate(sw.input)}, {"from", sw.from}, {"to", sw.to}, {"step", sw.step},
                      {"degrees", sw.degrees}, {"limb", m.limbs[static_cast<std::size_t>(sw.limb)].name},
                      {"branch", sw.branch >= 0 ? Json(sw.branch) : Json(nullptr)}});
  settings["ik_sweeps"] = sweeps;
  settings["weights"] = m.dynamics ? Json(m.dynamics->weights) : Json::array();
  settings["torque_limits"] = m.dynamics && !m.dynamics->torque_limits.empty() ? Json(m.dynamics->torque_limits) : Json(nullptr);
  Json friction = Json::array();
  for (const auto& c : contacts) friction.push_back(c.friction);
  settings["friction"] = friction;
  // The joints' limits (only those with one; JSON has no infinity): range, effort, speed.
  Json limits = Json::array();
  for (int k = 0; k < static_cast<int>(m.coordinates.size()); ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (std::isinf(m.lower[kk]) && m.effort[kk] == 0 && m.velocity[kk] == 0) continue;
    Json l = {{"coordinate", coordinate(k)}};
    l["lower"] = std::isinf(m.lower[kk]) ? Json(nullptr) : Json(m.lower[kk]);
    l["upper"] = std::isinf(m.upper[kk]) ? Json(nullptr) : Json(m.upper[kk]);
    l["effort"] = m.effort[kk] > 0 ? Json(m.effort[kk]) : Json(nullptr);
    l["velocity"] = m.velocity[kk] > 0 ? Json(m.velocity[kk]) : Json(nullptr);
    limits.push_back(l);
  }
  settings["limits"] = limits;
  Json branches = Json::object();
  for (const auto& l : m.limbs)
    if (l.branch >= 0) branches[l.name] = l.branch;
  settings["branches"] = branches;
  d["settings"] = settings;
  return {"wlx/gen/model.json", d.dump(1) + "\n"};
}

}  // namespace wlx::codegen
