// The composite pass' building blocks (composite_internal.hpp): the builder of its statements, the
// grouping of sibling limbs of one shape into rows of lanes, the projections by T, and the
// inertias and wrenches the pass is made of.
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

ValueId Builder::derived(Quantity what, const ValueId& from) {
  const auto key = std::pair{what, from};
  if (const auto it = derived_.find(key); it != derived_.end()) return it->second;
  const ValueId id = value_id(what, static_cast<int>(derived_.size()));
  derived_.emplace(key, id);
  program_.named_after.emplace(id, from);
  return id;
}

Builder::Builder(int width) {
  program_.width = width;
}

Signed Builder::scalar(const ValueId& id, const ex& value) {
  if (value.is_zero()) return {};
  if (value.is_equal(1)) return kUnit;
  if (value.is_equal(-1)) return -kUnit;
  // One lane scalar per value: a rotation's cosine on its diagonal twice, its sine and minus it.
  if (const auto it = scalar_of_value_.find(value); it != scalar_of_value_.end()) return it->second;
  if (const auto it = scalar_of_value_.find(-value); it != scalar_of_value_.end()) return -it->second;
  if (made_.insert(id).second) program_.scalar(id, value);
  scalar_of_value_[value] = {id, false};
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
  // Every lane the same exact zero or +-1: that value, which folds in products as a scalar's would.
  const Signed& first = lanes[0];
  if ((first.is_zero() || first.is_one()) &&
      std::all_of(lanes.begin(), lanes.end(), [&](const Signed& v) { return v.id == first.id && v.negate == first.negate; }))
    return out = first;
  // Every lane negated (-sin of the limbs' angles, say): the row of the values, read negated; a row
  // of the same lanes as one made before (a rotation's cosine on its diagonal twice): that row.
  const bool flip = std::all_of(lanes.begin(), lanes.end(), [](const Signed& v) { return v.is_zero() || v.negate; });
  std::vector<std::pair<ValueId, bool>> contents;
  for (const Signed& v : lanes) contents.emplace_back(v.id, flip ? false : v.negate);
  if (const auto it = rows_by_contents_.find(contents); it != rows_by_contents_.end())
    return out = flip ? -it->second : it->second;
  lane_code::LoadRow row{derived(Quantity::lanes_of, key), {}};
  for (std::size_t g = 0; g < lanes.size(); ++g)
    if (!lanes[g].is_zero()) row.lanes.emplace_back(static_cast<int>(g), holding(flip ? -lanes[g] : lanes[g]));
  const Signed made{row.target, false};
  rows_.insert(row.target);
  rows_by_contents_[contents] = made;
  add(std::move(row));
  return out = flip ? -made : made;
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
    if (p.lane >= 0 && !is_row(value)) throw std::logic_error("composite dynamics: a lane of a scalar");
    terms.push_back({factor.is_one() ? kOne : factor.id, value.id, p.lane, negate});
    row_term.push_back(is_row(factor) || (is_row(value) && p.lane < 0));
  }
  if (terms.empty()) return {};
  const bool row = std::any_of(row_term.begin(), row_term.end(), [](bool r) { return r; });
  if (row && !std::all_of(row_term.begin(), row_term.end(), [](bool r) { return r; })) {
    // Scalar terms in a row's sum (a limb's rotation that leaves its parent's omega_x alone, say):
    // their sum, in every lane, is one more term of the row's.
    std::vector<Term> rows;
    std::vector<Product> scalars;
    for (std::size_t t = 0; t < terms.size(); ++t) {
      if (row_term[t]) rows.push_back(terms[t]);
      else scalars.push_back({{terms[t].factor, false}, {terms[t].value, terms[t].negate}, terms[t].lane});
    }
    const Signed part = define(derived(Quantity::scalar_part, target), scalars);
    if (!part.is_zero()) {
      const ValueId all = derived(Quantity::everywhere, part.id);
      if (made_.insert(all).second) {
        lane_code::LoadRow load{all, {}};
        for (int g = 0; g < program_.width; ++g) load.lanes.emplace_back(g, part.id);
        rows_.insert(all);
        add(std::move(load));
      }
      rows.push_back({kOne, all, -1, part.negate});
    }
    terms = std::move(rows);
  }
  const bool all_negative = std::all_of(terms.begin(), terms.end(), [](const Term& t) { return t.negate; });
  if (all_negative)
    for (Term& t : terms) t.negate = false;
  std::stable_partition(terms.begin(), terms.end(), [](const Term& t) { return !t.negate; });
  if (terms.size() == 1 && terms[0].factor.what == Quantity::one && terms[0].lane < 0)
    return {terms[0].value, all_negative};
  add(lane_code::Define{target, row ? Layout::row : Layout::scalar, std::move(terms)});
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

Signed per_body(Builder& w, const Unit& u, std::size_t s, Quantity what, int a, int b, const std::function<ex(std::size_t)>& value) {
  std::vector<Signed> lanes;
  for (int i : u.bodies[s]) lanes.push_back(w.scalar(value_id(what, i, a, b), value(at(i))));
  return w.pack(value_id(what, u.bodies[s][0], a, b), lanes);
}

// Body slot s of unit u: J = R diag(I) R^T + m (|p|^2 1 - p p^T). With R's columns r_k
// orthonormal, R diag(I) R^T = I_1 1 + (I_2 - I_1) r_2 r_2^T + (I_3 - I_1) r_3 r_3^T, so
// J = sigma 1 + (I_2 - I_1) r_2 r_2^T + (I_3 - I_1) r_3 r_3^T - h p^T with sigma = I_1 + h . p
// (h = m p): two products per entry fewer than R diag(I) R^T written out.
Inertia body_inertia(const Model& m, const Unit& u, std::size_t s, const std::function<Vec3(std::size_t)>& p_of,
                                const std::function<Mat3(std::size_t)>& R_of, Builder& w) {
  const int index = u.bodies[s][0];  // the values' names: the first lane's body
  const auto per_lane = [&](Quantity what, int a, int b, const std::function<ex(std::size_t)>& value) {
    return per_body(w, u, s, what, a, b, value);
  };
  const auto moment = [&](std::size_t i, int k) { return m.parameter(m.bodies[i].inertia[at(k)]).symbol; };
  Inertia out;
  out.mass = per_lane(Quantity::mass, 0, 0, [&](std::size_t i) { return m.parameter(m.bodies[i].mass).symbol; });
  S3 p;
  for (int c = 0; c < 3; ++c) p[at(c)] = per_lane(Quantity::com_offset, c, 0, [&](std::size_t i) { return p_of(i)[c]; });
  const auto R = [&](int a, int k) {
    return per_lane(Quantity::com_rotation, a, k, [&](std::size_t i) { return R_of(i)(a, k); });
  };
  std::array<S3, 2> weighted;  // (I_k - I_1) r_k for k = 2, 3
  for (int k = 1; k < 3; ++k) {
    const Signed difference =
        per_lane(Quantity::inertia_difference, k, 0, [&](std::size_t i) { return moment(i, k) - moment(i, 0); });
    for (int a = 0; a < 3; ++a)
      weighted[at(k - 1)][at(a)] = w.define(value_id(Quantity::rotated_inertia, index, a, k), {{R(a, k), difference}});
  }
  for (int c = 0; c < 3; ++c)
    out.h[at(c)] = w.define(value_id(Quantity::first_moment, index, c), {{out.mass, p[at(c)]}});
  std::vector<Product> shift{{per_lane(Quantity::inertia, 0, 0, [&](std::size_t i) { return moment(i, 0); })}};
  for (int c = 0; c < 3; ++c) shift.push_back({out.h[at(c)], p[at(c)]});
  const Signed sigma = w.define(value_id(Quantity::inertia_shift, index), shift);
  for (std::size_t e = 0; e < kInertiaEntries.size(); ++e) {
    const auto [a, b] = kInertiaEntries[e];
    std::vector<Product> t;
    for (int k = 1; k < 3; ++k) t.push_back({weighted[at(k - 1)][at(a)], R(b, k)});
    t.push_back({-out.h[at(a)], p[at(b)]});
    if (a == b) t.push_back({sigma});
    out.J[e] = w.define(value_id(Quantity::origin_inertia, index, a, b), t);
  }
  return out;
}

std::vector<Inertia> composite_inertias(const Units& units,
                                                   const std::function<Inertia(std::size_t, std::size_t)>& own_inertia,
                                                   const std::function<Inertia(std::size_t, const Inertia&)>& carried,
                                                   Builder& w) {
  std::vector<Inertia> out(units.units.size()), moved(units.units.size());
  for (std::size_t u = units.units.size(); u-- > 0;) {
    const Unit& unit = units.units[u];
    std::vector<Inertia> own;
    for (std::size_t s = 0; s < unit.bodies.size(); ++s) own.push_back(own_inertia(u, s));
    const Summands sum{units, u};
    const int k = unit.nodes[0];
    const auto total = [&](const ValueId& target, const auto& pick) {
      return w.define(target, sum(
                                  [&] {
                                    std::vector<Product> t;
                                    for (const Inertia& x : own) t.push_back({pick(x)});
                                    return t;
                                  },
                                  [&](std::size_t child) { return pick(moved[child]); }));
    };
    out[u].mass = total(value_id(Quantity::composite_mass, k), [](const Inertia& x) { return x.mass; });
    for (int c = 0; c < 3; ++c)
      out[u].h[at(c)] =
          total(value_id(Quantity::composite_first_moment, k, c), [&](const Inertia& x) { return x.h[at(c)]; });
    for (std::size_t e = 0; e < kInertiaEntries.size(); ++e)
      out[u].J[e] = total(value_id(Quantity::composite_inertia, k, kInertiaEntries[e].first, kInertiaEntries[e].second),
                          [&](const Inertia& x) { return x.J[e]; });
    if (unit.parent >= 0) moved[u] = carried(u, out[u]);
  }
  return out;
}

S6 momentum(const Inertia& I, const S6& S, int node, Builder& w) {
  const S3 a{S[0], S[1], S[2]}, b{S[3], S[4], S[5]};
  S6 out;
  for (int c = 0; c < 3; ++c) {
    std::vector<Product> force{{I.mass, b[at(c)]}};
    append(force, cross(a, I.h, c));
    out[at(c)] = w.define(value_id(Quantity::joint_momentum, node, c), force);
    std::vector<Product> moment;
    for (int d = 0; d < 3; ++d) moment.push_back({I.Jab(c, d), a[at(d)]});
    append(moment, cross(I.h, b, c));
    out[at(c + 3)] = w.define(value_id(Quantity::joint_momentum, node, c + 3), moment);
  }
  return out;
}

std::vector<Product> power(const S6& S, const S6& wrench) {
  std::vector<Product> t;
  for (int c = 0; c < 3; ++c) {
    t.push_back({S[at(c)], wrench[at(c + 3)]});
    t.push_back({S[at(c + 3)], wrench[at(c)]});
  }
  return t;
}

void store(Builder& w, const std::string& output, int row, int column, bool mirrored, const Signed& v,
                      const Signed& factor, int lane) {
  std::vector<Term> terms;
  if (!v.is_zero()) terms.push_back({factor.id, v.id, lane, v.negate != factor.negate});
  w.add(lane_code::Store{output, row, column, mirrored, std::move(terms)});
}

// M* = T^T M T on T's pattern: P = T^T M (its columns of the dense coordinates are B_bias's), then
// M*(l, b) = P(l, b's coordinate) + sum over the dense c of P(l, c) T(c, b), for l <= b.
void project_mass(const Projection& pr, const std::map<std::pair<int, int>, Signed>& M, Builder& w) {
  // P(l, c) for each dense coordinate c, as a value per unit (a row for a row unit).
  std::map<std::pair<int, int>, Signed> bias;  // (l, unit) -> P(l, the unit's coordinates)
  w.charge_to = kB_bias;
  for (int l = 0; l < pr.nu; ++l)
    for (std::size_t u = 0; u < pr.units.units.size(); ++u)
      if (pr.units.units[u].row() || pr.dense_plain(static_cast<int>(u)))
        bias[{l, static_cast<int>(u)}] = pr.projected(value_id(Quantity::projected_mass, l, pr.units.units[u].nodes[0]),
                                                      l, static_cast<int>(u), M, w);
  // Every value M and B_bias read before their blocks: the code a value needs is placed before its
  // first reader (emit_function.cpp), and a reader after the block of the first would compute it
  // again.
  w.charge_to = kM;
  std::map<std::pair<int, int>, Signed> reduced;
  for (int l = 0; l < pr.nu; ++l)
    for (int b = l; b < pr.nu; ++b) {
      Sum sum;
      for (int u : pr.units_of_speed(b)) pr.add_projected(sum, l, u, M, w);
      for (const auto& [key, p] : bias)
        if (key.first == l) pr.times_T(sum, p, key.second, b, w);
      reduced[{l, b}] = w.define_sum(value_id(Quantity::reduced_mass, l, b), sum);
    }
  w.add(lane_code::OpenOutput{"M", "the upper triangle, mirrored: M is symmetric to the last bit"});
  for (const auto& [lb, v] : reduced) store(w, "M", lb.first, lb.second, lb.first != lb.second, v);
  w.add(lane_code::CloseOutput{});
  w.charge_to = kB_bias;
  // B_bias(l, c): the sum over c's joints (a lane of a row unit's).
  std::map<std::pair<int, int>, std::vector<Term>> entries;  // (coordinate, l)
  for (const auto& [key, p] : bias) {
    if (p.is_zero()) continue;
    const Unit& unit = pr.units.units[at(key.second)];
    for (int g = 0; g < static_cast<int>(unit.nodes.size()); ++g)
      entries[{pr.coordinate(key.second, g), key.first}].push_back({kOne, p.id, unit.row() ? g : -1, p.negate});
  }
  w.add(lane_code::OpenOutput{"B_bias", "", lane_code::OpenOutput::Prologue::zero_if_asked});
  for (auto& [key, terms] : entries) {
    std::stable_partition(terms.begin(), terms.end(), [](const Term& t) { return !t.negate; });
    w.add(lane_code::Store{"B_bias", key.second, key.first, false, std::move(terms)});
  }
  w.add(lane_code::CloseOutput{});
}

}  // namespace wlx::codegen::derivation::composite
