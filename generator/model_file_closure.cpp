// The model file's closure: its rows, the limbs that group them with the dependent joints, and the
// wheels' non-holonomic rates and pairs.
#include "model_file_internal.hpp"

#include <algorithm>

namespace wlx::codegen::model_file_detail {

void Parser::closure(const Item& list) {
  std::set<std::string> seen;
  each(list, [&](const Item& it) {
    const Item type_item = it.is_map() && it.has("type") ? it.child("type") : it;
    const std::string type = it.is_map() && it.has("type") ? type_item.text() : "";
    ClosureCondition c;
    using K = ClosureCondition::Kind;
    if (type == "point") {
      const Fields f(it, {"name", "type", "frame", "component", "equals"});
      c.name = f["name"].name();
      c.kind = K::PointEqualsCoordinate;
      c.frame = m_.frames[static_cast<std::size_t>(frame_index(f["frame"]))].name;
      c.axis = axis_of(f["component"]);
      c.target = coordinate_index(f["equals"], true);
      if (m_.coordinates[static_cast<std::size_t>(c.target)].unit != "m")
        f["equals"].fail(fmt::format("'{}' is an angle; a point's component equals a length coordinate (m)",
                                     m_.coordinates[static_cast<std::size_t>(c.target)].name));
    } else if (type == "level") {
      const Fields f(it, {"name", "type", "frame", "axis"});
      c.name = f["name"].name();
      c.kind = K::AttachedDirectionLevel;
      const NamedFrame& frame = m_.frames[static_cast<std::size_t>(frame_index(f["frame"]))];
      if (frame.derived_from_wheel >= 0)
        f["frame"].fail(fmt::format("'{}' is the contact frame of wheel '{}', level by construction: a level row on it "
                                    "would fix nothing",
                                    frame.name, m_.wheels[static_cast<std::size_t>(frame.derived_from_wheel)].name));
      c.frame = frame.name;
      c.axis = axis_of(f["axis"]);
    } else if (type == "sum") {
      const Fields f(it, {"name", "type", "coordinates"});
      c.name = f["name"].name();
      c.kind = K::CoordinateSum;
      for (const Item& ci : f["coordinates"].list()) c.coordinates.push_back(coordinate_index(ci));
      if (c.coordinates.empty()) f["coordinates"].fail("must name at least one coordinate");
    } else {
      (it.is_map() && it.has("type") ? type_item : it)
          .fail(fmt::format("a closure condition needs `type: point`, `level` or `sum`{}",
                            type.empty() ? "" : fmt::format(", not '{}'{}", excerpt(type), suggestion(type, {"point", "level", "sum"}))));
    }
    if (!seen.insert(c.name).second) it.child("name").fail(fmt::format("closure condition '{}' is defined twice", c.name));
    m_.closure.push_back(std::move(c));
  });
  rows_item_ = list;
}

// The dependent coordinates a closure row involves (structurally, without differentiating).
std::set<int> Parser::row_dependents(const ClosureCondition& c) const {
  std::set<int> out;
  if (c.kind == ClosureCondition::Kind::CoordinateSum) {
    out.insert(c.coordinates.begin(), c.coordinates.end());
  } else {
    for (const auto& j : m_.frame(c.frame).joints) out.insert(j.coordinate);
    if (c.target >= 0) out.insert(c.target);
  }
  std::set<int> dependents;
  for (int k : out)
    if (k >= m_.input_count) dependents.insert(k);
  return dependents;
}

void Parser::limbs(const std::optional<Item>& list, const Item& top) {
  const int dependents = static_cast<int>(m_.coordinates.size()) - m_.input_count;
  if (static_cast<int>(m_.closure.size()) != dependents)
    (rows_item_ ? *rows_item_ : top)
        .fail(fmt::format("{} closure conditions for {} dependent joints: the closure needs exactly one equation per "
                          "dependent joint",
                          m_.closure.size(), dependents));
  if (!list) {
    if (dependents > 0) top.fail("missing field 'limbs': group the closure rows and dependent joints into limbs");
    return;
  }
  std::map<int, std::string> row_owner, joint_owner;
  each(*list, [&](const Item& it) {
    const Fields f(it, {"name", "title", "closure", "joints", "start", "branch"});
    Limb limb;
    // The branch of its closed form every command takes unless told otherwise (checked against
    // the branches wlx-gen finds, which come later: emit_ik.cpp).
    if (auto b = f.optional("branch")) {
      limb.branch = b->branch();
      const YAML::Mark mark = b->mark();
      limb.branch_place = fmt::format("{}:{}:{}: {}", src_.name, mark.line + 1, mark.column + 1, b->path());
    }
    limb.name = f["name"].name();
    for (const auto& l : m_.limbs)
      if (l.name == limb.name) f["name"].fail(fmt::format("limb '{}' is defined twice", limb.name));
    limb.title = f.optional("title") ? f["title"].text() : limb.name;
    for (const Item& r : f["closure"].list()) {
      const std::string n = r.name();
      int row = -1;
      std::vector<std::string> names;
      for (std::size_t k = 0; k < m_.closure.size(); ++k) {
        names.push_back(m_.closure[k].name);
        if (m_.closure[k].name == n) row = static_cast<int>(k);
      }
      if (row < 0) r.fail(fmt::format("no closure condition '{}'{}", n, suggestion(n, names)));
      if (row_owner.count(row)) r.fail(fmt::format("closure condition '{}' already belongs to limb '{}'", n, row_owner[row]));
      row_owner[row] = limb.name;
      limb.rows.push_back(row);
    }
    for (const Item& j : f["joints"].list()) {
      const int k = coordinate_index(j, false, true);
      if (joint_owner.count(k))
        j.fail(fmt::format("joint '{}' already belongs to limb '{}'", m_.coordinates[static_cast<std::size_t>(k)].name, joint_owner[k]));
      joint_owner[k] = limb.name;
      limb.joints.push_back(k);
    }
    // Where Newton's method starts for this limb's joints (a bent knee, not a straight leg).
    if (auto start = f.optional("start")) {
      if (!start->is_map()) start->fail("must map the limb's joints to start values");
      for (const auto& kv : start->node()) {
        const Item key(src_, kv.first, start->path(), start->env());  // keys may name <variables> too
        const int k = coordinate_index(key, false, true);
        if (std::find(limb.joints.begin(), limb.joints.end(), k) == limb.joints.end())
          key.fail(fmt::format("'{}' is not one of limb '{}''s joints", m_.coordinates[static_cast<std::size_t>(k)].name, limb.name));
        limb_start_[k] = start->child(kv.first.Scalar()).number(true);  // <sign>*0.6 too, as in ik_sweeps
      }
    }
    if (limb.rows.size() != limb.joints.size() || limb.rows.empty())
      it.fail(fmt::format("limb '{}' has {} closure conditions and {} joints: a limb's block of dPhi/ds must be square and "
                          "non-empty",
                          limb.name, limb.rows.size(), limb.joints.size()));
    for (int row : limb.rows)
      for (int k : row_dependents(m_.closure[static_cast<std::size_t>(row)]))
        if (std::find(limb.joints.begin(), limb.joints.end(), k) == limb.joints.end())
          f["closure"].fail(fmt::format("closure condition '{}' depends on joint '{}', which is not one of limb '{}''s joints: "
                                        "the limbs must decouple",
                                        m_.closure[static_cast<std::size_t>(row)].name,
                                        m_.coordinates[static_cast<std::size_t>(k)].name, limb.name));
    m_.limbs.push_back(std::move(limb));
  });
  for (std::size_t k = 0; k < m_.closure.size(); ++k)
    if (!row_owner.count(static_cast<int>(k)))
      list->fail(fmt::format("closure condition '{}' belongs to no limb", m_.closure[k].name));
  for (int k = m_.input_count; k < static_cast<int>(m_.coordinates.size()); ++k)
    if (!joint_owner.count(k)) list->fail(fmt::format("dependent joint '{}' belongs to no limb", m_.coordinates[static_cast<std::size_t>(k)].name));
}

void Parser::nonholonomic(const std::optional<Item>& section, const Item& top) {
  if (m_.wheels.empty()) {
    if (section) section->fail("the model has no wheels, so it has no non-holonomic section");
    return;
  }
  if (!section) top.fail("missing field 'nonholonomic': a model with wheels names the candidate dependent rates and pairs");
  const Fields f(*section, {"pair_candidates", "pairs", "default_pair"});
  if (f["pair_candidates"].list().size() < m_.wheels.size())
    f["pair_candidates"].fail(fmt::format("{} wheels need at least {} candidate dependent rates, one per wheel", m_.wheels.size(),
                                          m_.wheels.size()));
  for (const Item& c : f["pair_candidates"].list()) {
    const int k = coordinate_index(c, true);
    if (std::count(m_.pair_candidates.begin(), m_.pair_candidates.end(), k)) c.fail("listed twice");
    m_.pair_candidates.push_back(k);
  }
  const Item pairs = f["pairs"];
  if (!pairs.is_map() || pairs.size() == 0) pairs.fail("must map pair names to lists of dependent rates");
  for (const auto& kv : pairs.node()) {
    DependentPair p;
    p.name = kv.first.Scalar();
    const Item list = pairs.child(p.name);
    if (!is_identifier(p.name)) list.fail(fmt::format("'{}' is not a name", excerpt(p.name)));
    if (!list.is_sequence() || list.size() != m_.wheels.size())
      list.fail(fmt::format("a dependent pair lists {} rates, one per wheel", m_.wheels.size()));
    for (std::size_t k = 0; k < list.size(); ++k) {
      const int c = coordinate_index(list.element(k), true);
      if (!std::count(m_.pair_candidates.begin(), m_.pair_candidates.end(), c))
        list.element(k).fail(fmt::format("'{}' is not one of pair_candidates", m_.coordinates[static_cast<std::size_t>(c)].name));
      if (std::count(p.coordinates.begin(), p.coordinates.end(), c))
        list.element(k).fail(fmt::format("'{}' is listed twice: the dependent rates must differ", m_.coordinates[static_cast<std::size_t>(c)].name));
      p.coordinates.push_back(c);
    }
    m_.pairs.push_back(p);
  }
  const Item def = f["default_pair"];
  m_.default_pair = def.name();
  bool found = false;
  for (const auto& p : m_.pairs) found = found || p.name == m_.default_pair;
  if (!found) def.fail(fmt::format("no pair '{}' under pairs", m_.default_pair));
}

}  // namespace wlx::codegen::model_file_detail
