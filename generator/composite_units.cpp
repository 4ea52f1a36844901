// The composite pass' building blocks (composite_internal.hpp): the builder of its statements, the
// grouping of sibling limbs of one shape into rows of lanes, and the projections by T.
#include "composite_internal.hpp"

#include <algorithm>
#include <functional>

namespace wlx::codegen::derivation::composite {

using lane_code::kOne;
using lane_code::Layout;
using lane_code::Quantity;
using lane_code::Term;
using lane_code::value_id;
using lane_code::ValueId;

namespace {

// A value named after another one (the first lane's value of a row, say): its quantity and
// indices, folded into three indices.
ValueId derived(Quantity what, const ValueId& from) {
  return value_id(what, static_cast<int>(from.what) * 1000 + from.index[0], from.index[1], from.index[2]);
}

}  // namespace

Builder::Builder(int width) {
  program_.kind = lane_code::LaneProgram::Kind::scalars;
  program_.width = program_.speeds = width;
}

Signed Builder::scalar(const ValueId& id, const ex& value) {
  if (value.is_zero()) return {};
  if (value.is_equal(1)) return kUnit;
  if (value.is_equal(-1)) return -kUnit;
  if (made_.insert(id).second) program_.scalar(id, value);
  return {id, false};
}

ValueId Builder::holding(const Signed& v) {
  if (v.is_one()) {
    const ValueId id = value_id(Quantity::constant, v.negate ? 1 : 0);
    if (made_.insert(id).second) program_.scalar(id, v.negate ? ex(-1) : ex(1));
    return id;
  }
  if (!v.negate) return v.id;
  const ValueId id = derived(Quantity::negated, v.id);
  if (made_.insert(id).second) add(lane_code::Define{id, Layout::scalar, {Term{kOne, v.id, -1, true}}});
  return id;
}

Signed Builder::pack(const ValueId& key, const std::vector<Signed>& lanes) {
  if (lanes.size() == 1) return lanes[0];
  if (const auto it = packed_.find(key); it != packed_.end()) return it->second;
  Signed& out = packed_[key];
  if (std::all_of(lanes.begin(), lanes.end(), [](const Signed& v) { return v.is_zero(); })) return out;
  lane_code::LoadRow row{derived(Quantity::lanes_of, key), 0, false, {}};
  for (std::size_t g = 0; g < lanes.size(); ++g)
    if (!lanes[g].is_zero()) row.lanes.emplace_back(static_cast<int>(g), holding(lanes[g]));
  out = {row.target, false};
  rows_.insert(row.target);
  add(std::move(row));
  return out;
}

Signed Builder::define(const ValueId& target, const std::vector<Product>& products) {
  std::vector<Term> terms;
  std::vector<bool> row_term;
  for (const Product& p : products) {
    if (p.a.is_zero() || p.b.is_zero()) continue;
    if (p.a.is_one() && p.b.is_one()) throw std::logic_error("composite dynamics: a constant term");
    const bool negate = p.a.negate != p.b.negate;
    // The factor first; a row factor of a scalar value goes second (Scalar * row).
    Signed factor = p.a, value = p.b;
    if (value.is_one() || (p.lane < 0 && is_row(factor) && !is_row(value))) std::swap(factor, value);
    if (p.lane >= 0 && is_row(factor)) throw std::logic_error("composite dynamics: a row factor of a lane");
    terms.push_back({factor.is_one() ? kOne : factor.id, value.id, p.lane, negate});
    row_term.push_back(is_row(factor) || (is_row(value) && p.lane < 0));
  }
  if (terms.empty()) return {};
  const bool row = std::any_of(row_term.begin(), row_term.end(), [](bool r) { return r; });
  if (row && !std::all_of(row_term.begin(), row_term.end(), [](bool r) { return r; }))
    throw std::logic_error("composite dynamics: a scalar term in a row's sum");
  const bool all_negative = std::all_of(terms.begin(), terms.end(), [](const Term& t) { return t.negate; });
  if (all_negative)
    for (Term& t : terms) t.negate = false;
  std::stable_partition(terms.begin(), terms.end(), [](const Term& t) { return !t.negate; });
  if (terms.size() == 1 && terms[0].factor.what == Quantity::one && terms[0].lane < 0)
    return {terms[0].value, all_negative};
  add(lane_code::Define{target, row ? Layout::narrow : Layout::scalar, std::move(terms)});
  if (row) rows_.insert(target);
  return {target, all_negative};
}

Signed Builder::define_sum(const ValueId& target, const Sum& sum) {
  std::vector<Product> t = sum.scalar;
  const Signed row = define(derived(Quantity::row_sum, target), sum.row);
  if (!row.is_zero())
    for (int g = 0; g < program_.width; ++g) t.push_back({row, kUnit, g});
  return define(target, t);
}

Units group_units(const TwistTree& tree, const RateRoles& roles) {
  const auto& nodes = tree.nodes;
  std::map<int, int> uses;  // coordinate -> its joints
  for (const TwistNode& n : nodes) ++uses[n.joint->coordinate];
  // A limb can take a lane when each of its joints has a dense coordinate of its own.
  const std::function<bool(int)> own_rows = [&](int n) {
    const int j = nodes[at(n)].joint->coordinate;
    if (!roles.dense[at(j)] || uses[j] != 1) return false;
    return std::all_of(nodes[at(n)].children.begin(), nodes[at(n)].children.end(), own_rows);
  };
  // Two limbs have one shape when their joints are of one kind with as many bodies, in the same
  // tree: their code differs only in the values it reads.
  const std::function<std::string(int)> shape = [&](int n) {
    std::string out = (nodes[at(n)].joint->revolute ? "r" : "p") + std::to_string(nodes[at(n)].bodies.size()) + "(";
    for (int c : nodes[at(n)].children) out += shape(c) + ",";
    return out + ")";
  };
  // Siblings of one shape, in order of first appearance; a limb that cannot take a lane alone.
  const auto same_shapes = [&](const std::vector<int>& siblings) {
    std::vector<std::vector<int>> out;
    std::vector<std::string> shapes;
    for (int n : siblings) {
      const std::string s = own_rows(n) ? shape(n) : "";
      const auto it = std::find(shapes.begin(), shapes.end(), s);
      if (s.empty() || it == shapes.end()) {
        out.push_back({n});
        shapes.push_back(s.empty() ? "-" + std::to_string(n) : s);
      } else {
        out[at(static_cast<int>(it - shapes.begin()))].push_back(n);
      }
    }
    return out;
  };
  std::vector<int> roots;
  for (std::size_t n = 0; n < nodes.size(); ++n)
    if (nodes[n].parent < 0) roots.push_back(static_cast<int>(n));
  Units out;
  for (const auto& siblings : [&] {
         std::vector<std::vector<int>> all{roots};
         for (const TwistNode& n : nodes) all.push_back(n.children);
         return all;
       }())
    for (const auto& group : same_shapes(siblings)) out.width = std::max(out.width, static_cast<int>(group.size()));
  const std::function<void(const std::vector<int>&, int)> make = [&](const std::vector<int>& lanes, int parent) {
    Unit u;
    u.nodes = lanes;
    u.parent = parent;
    for (int n : lanes) u.coordinates.push_back(nodes[at(n)].joint->coordinate);
    for (std::size_t s = 0; s < nodes[at(lanes[0])].bodies.size(); ++s) {
      u.bodies.emplace_back();
      for (int n : lanes) u.bodies.back().push_back(nodes[at(n)].bodies[s]);
    }
    const int index = static_cast<int>(out.units.size());
    out.units.push_back(std::move(u));
    if (parent >= 0) out.units[at(parent)].children.push_back(index);
    if (lanes.size() > 1) {
      for (std::size_t c = 0; c < nodes[at(lanes[0])].children.size(); ++c) {
        std::vector<int> next;
        for (int n : lanes) next.push_back(nodes[at(n)].children[c]);
        make(next, index);
      }
      return;
    }
    for (const auto& group : same_shapes(nodes[at(lanes[0])].children)) {
      if (out.width > 1 && static_cast<int>(group.size()) == out.width)
        make(group, index);
      else
        for (int n : group) make({n}, index);
    }
  };
  for (const auto& group : same_shapes(roots)) {
    if (out.width > 1 && static_cast<int>(group.size()) == out.width)
      make(group, -1);
    else
      for (int n : group) make({n}, -1);
  }
  return out;
}

std::vector<int> Projection::units_of_speed(int b) const {
  std::vector<int> out;
  for (std::size_t u = 0; u < units.units.size(); ++u)
    if (!units.units[u].row() && roles.speed_of[at(coordinate(static_cast<int>(u), 0))] == b)
      out.push_back(static_cast<int>(u));
  return out;
}

Signed Projection::T(int r, int l) const {
  if (roles.speed_of[at(r)] == l) return kUnit;
  const auto& speeds = speeds_of[at(r)];
  if (roles.dense[at(r)] && std::binary_search(speeds.begin(), speeds.end(), l))
    return {value_id(Quantity::rate_basis_entry, r, l)};
  return {};
}

Signed Projection::T_of(int u, int l, Builder& w) const {
  std::vector<Signed> lanes;
  for (int r : units.units[at(u)].coordinates) lanes.push_back(T(r, l));
  return w.pack(value_id(Quantity::rate_basis_entry, coordinate(u, 0), l), lanes);
}

void Projection::times_T(Sum& sum, const Signed& value, int u, int b, Builder& w) const {
  if (value.is_zero()) return;
  const Unit& unit = units.units[at(u)];
  if (!unit.row()) {
    sum.scalar.push_back({value, T(coordinate(u, 0), b)});
    return;
  }
  // A row of T with one entry in it (a limb's own speed): that lane alone, as a scalar.
  std::vector<int> lanes;
  for (int g = 0; g < static_cast<int>(unit.nodes.size()); ++g)
    if (!T(coordinate(u, g), b).is_zero()) lanes.push_back(g);
  if (lanes.size() == 1)
    sum.scalar.push_back({T(coordinate(u, lanes[0]), b), value, lanes[0]});
  else if (!lanes.empty())
    sum.row.push_back({value, T_of(u, b, w)});
}

Signed Projection::transposed(const ValueId& target, int l, const std::vector<Signed>& per_unit, Builder& w) const {
  Sum sum;
  for (std::size_t u = 0; u < units.units.size(); ++u) times_T(sum, per_unit[u], static_cast<int>(u), l, w);
  return w.define_sum(target, sum);
}

Signed Projection::projected(const ValueId& target, int l, int u, const std::map<std::pair<int, int>, Signed>& M,
                             Builder& w) const {
  Sum sum;
  add_projected(sum, l, u, M, w);
  if (units.units[at(u)].row()) return w.define(target, sum.row);
  return w.define_sum(target, sum);
}

void Projection::add_projected(Sum& sum, int l, int u, const std::map<std::pair<int, int>, Signed>& M,
                               Builder& w) const {
  const auto entry = [&](int a, int b) {  // a an ancestor of b, or b itself
    const auto it = M.find({a, b});
    return it == M.end() ? Signed{} : it->second;
  };
  const bool row = units.units[at(u)].row();
  // The units on u's chain, and those beyond u.
  for (int r = u; r >= 0; r = units.units[at(r)].parent) {
    if (row)
      sum.row.push_back({T_of(r, l, w), entry(r, u)});
    else
      sum.scalar.push_back({T(coordinate(r, 0), l), entry(r, u)});
  }
  const std::function<void(int)> beyond = [&](int r) {
    for (int c : units.units[at(r)].children) {
      if (row)
        sum.row.push_back({T_of(c, l, w), entry(u, c)});
      else
        times_T(sum, entry(u, c), c, l, w);
      beyond(c);
    }
  };
  beyond(u);
}

}  // namespace wlx::codegen::derivation::composite
