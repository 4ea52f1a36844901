// What the composite-rigid-body pass of reduced_dynamics (composite_dynamics.cpp) is built from
// (composite_units.cpp): signed values, a builder of its statements that folds zeros, ones and
// signs, the tree's joints as units (sibling limbs of one shape grouped into rows of lanes, one limb
// per lane), and the projections by T on T's pattern. Internal to the generator.
#pragma once

#include "derivations_internal.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>

namespace wlx::codegen::derivation::composite {

inline std::size_t at(int i) { return static_cast<std::size_t>(i); }

// A value or its negative; the value may be one (a unit entry of an axis, of a rotation or of T)
// or zero (an exact zero: products with it are dropped).
struct Signed {
  lane_code::ValueId id;
  bool negate = false;
  bool is_zero() const { return id.is_zero(); }
  bool is_one() const { return id.what == lane_code::Quantity::one; }
  Signed operator-() const { return {id, !negate}; }
};
inline const Signed kUnit{lane_code::kOne, false};

// a * b; with `lane` set, b is a row read at that lane (a scalar).
struct Product {
  Signed a, b = kUnit;
  int lane = -1;
};

// A scalar as scalar products plus the lanes of a row's sum of products.
struct Sum {
  std::vector<Product> scalar, row;
};

// Builds the code, one definition per value, each statement counted for `charge_to`. A value is a
// scalar or a row of `width` lanes (a row unit's, lane g for limb g); a sum is a row when any of
// its products has a row in it, its scalar products then added up and put in every lane. Exact zeros, ones and signs are
// folded while building: a sum of one plain product is no statement, a sum whose terms are all
// negative is defined positive and read negated.
class Builder {
 public:
  explicit Builder(int width);
  int charge_to = 0;
  // A lane scalar, made once however often it is asked for.
  Signed scalar(const lane_code::ValueId& id, const ex& value);
  // A row of the lanes' values (one lane: that value itself), made once per key.
  Signed pack(const lane_code::ValueId& key, const std::vector<Signed>& lanes);
  Signed define(const lane_code::ValueId& target, const std::vector<Product>& products);
  // A scalar: sum.scalar plus every lane of the row sum.row adds up to.
  Signed define_sum(const lane_code::ValueId& target, const Sum& sum);
  bool is_row(const Signed& v) const { return rows_.count(v.id) > 0; }
  void add(lane_code::Step step) { program_.statements.push_back({std::move(step), charge_to}); }
  lane_code::LaneProgram& program() { return program_; }

 private:
  lane_code::ValueId holding(const Signed& v);  // a value equal to v: v itself, a one, a negation
  // A value of the builder's own named after another one (a row of the first lane's value, the
  // scalar part of a row's sum), one per (what, from).
  lane_code::ValueId derived(lane_code::Quantity what, const lane_code::ValueId& from);
  std::map<std::pair<lane_code::Quantity, lane_code::ValueId>, lane_code::ValueId> derived_;
  lane_code::LaneProgram program_;
  std::set<lane_code::ValueId> made_, rows_;
  std::map<lane_code::ValueId, Signed> packed_;
  std::map<std::vector<std::pair<lane_code::ValueId, bool>>, Signed> rows_by_contents_;
  std::map<ex, Signed, GiNaC::ex_is_less> scalar_of_value_;
};

using S3 = std::array<Signed, 3>;
using S6 = std::array<Signed, 6>;  // (angular; linear) of a motion, (force; moment) of a wrench

// (x cross y)_c as two products.
inline std::vector<Product> cross(const S3& x, const S3& y, int c) {
  const std::size_t c1 = at((c + 1) % 3), c2 = at((c + 2) % 3);
  return {{x[c1], y[c2]}, {-x[c2], y[c1]}};
}
inline void append(std::vector<Product>& to, const std::vector<Product>& more) {
  to.insert(to.end(), more.begin(), more.end());
}

// The rotational inertia's six entries (a <= b), in this order.
constexpr std::array<std::pair<int, int>, 6> kInertiaEntries{{{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}}};
inline std::size_t entry_of(int a, int b) {
  for (std::size_t e = 0; e < kInertiaEntries.size(); ++e)
    if (kInertiaEntries[e] == std::pair{std::min(a, b), std::max(a, b)}) return e;
  throw std::logic_error("inertia entry");
}

// A spatial inertia in a joint's frame: mass, first moment h = m p (p the CoM from the frame's
// origin), rotational inertia J about the origin.
struct Inertia {
  Signed mass;
  S3 h;
  std::array<Signed, 6> J;
  const Signed& Jab(int a, int b) const { return J[entry_of(a, b)]; }
};


// A joint of the tree, or the joints at one place of G sibling limbs of one shape (a row unit: lane
// g is limb g). A row unit's joints each have their own coordinate, dense (a row of T), that no
// other joint has.
struct Unit {
  std::vector<int> nodes, coordinates;  // per lane
  int parent = -1;
  std::vector<int> children;
  std::vector<std::vector<int>> bodies;  // per body at the joint: the body in each lane
  bool row() const { return nodes.size() > 1; }
};
struct Units {
  std::vector<Unit> units;  // parents first
  int width = 1;            // the lanes of a row: the largest set of sibling limbs of one shape
};
Units group_units(const TwistTree& tree, const RateRoles& roles);

// The projections by T (s' = T u) of values per unit.
struct Projection {
  const Units& units;
  RateRoles roles;
  std::vector<std::vector<int>> speeds_of;
  int nu = 0;
  std::vector<std::array<Signed, 6>> axis;  // per unit: its joints' axes in their own frames
  int coordinate(int u, int lane) const { return units.units[at(u)].coordinates[at(lane)]; }
  bool dense_plain(int u) const { return !units.units[at(u)].row() && roles.dense[at(coordinate(u, 0))]; }
  // The plain units of speed b's coordinate.
  std::vector<int> units_of_speed(int b) const;
  // T(r, l) of a coordinate: one, an entry of T's pattern, or zero.
  Signed T(int r, int l) const;
  // T(u's coordinates, l): a scalar, or a row unit's row.
  Signed T_of(int u, int l, Builder& w) const;
  // sum += value * T(u's coordinates, b), value being u's (a row for a row unit).
  void times_T(Sum& sum, const Signed& value, int u, int b, Builder& w) const;
  // sum over the units of T(u's coordinates, l) * value_u: a scalar.
  Signed transposed(const lane_code::ValueId& target, int l, const std::vector<Signed>& per_unit, Builder& w) const;
  // (T^T M)(l, u's coordinates) from M between units (keyed (ancestor, unit)): u's kind of value;
  // for a plain unit, added to a sum instead.
  Signed projected(const lane_code::ValueId& target, int l, int u, const std::map<std::pair<int, int>, Signed>& M,
                   Builder& w) const;
  void add_projected(Sum& sum, int l, int u, const std::map<std::pair<int, int>, Signed>& M, Builder& w) const;
};


// A unit's parts summed: its own values and its children's (a row unit's children in the same
// lanes; a plain unit's row children lane by lane).
struct Summands {
  const Units& units;
  std::size_t u;
  template <class Own, class OfChild>
  std::vector<Product> operator()(const Own& own, const OfChild& of_child) const {
    std::vector<Product> t = own();
    for (int child : units.units[u].children) {
      const Signed v = of_child(at(child));
      if (units.units[at(child)].row() && !units.units[u].row())
        for (int g = 0; g < units.width; ++g) t.push_back({v, kUnit, g});
      else
        t.push_back({v});
    }
    return t;
  }
};

// A row of body slot s of unit u's per-body values (value(body)), named after the first lane's body.
Signed per_body(Builder& w, const Unit& u, std::size_t s, lane_code::Quantity what, int a, int b,
                const std::function<ex(std::size_t)>& value);
// Body slot s of unit u as an Inertia about a point: its CoM at p_of(body) from the point, its
// principal axes R_of(body) in the axes the inertia is written in.
Inertia body_inertia(const Model& m, const Unit& u, std::size_t s, const std::function<Vec3(std::size_t)>& p_of,
                     const std::function<Mat3(std::size_t)>& R_of, Builder& w);
// The composite inertias beyond each unit, from the leaves in: its bodies' (own(u, s)) and its
// children's as `carried` puts them in its axes.
std::vector<Inertia> composite_inertias(const Units& units, const std::function<Inertia(std::size_t, std::size_t)>& own,
                                        const std::function<Inertia(std::size_t, const Inertia&)>& carried, Builder& w);
// I S for a composite inertia and a joint's axis S = (a; b), in the inertia's axes and about its
// point: the momentum of the bodies beyond per unit rate, (force m b + a x h; moment J a + h x b),
// named joint_momentum (node, c).
S6 momentum(const Inertia& I, const S6& S, int node, Builder& w);
// S_j . W as products: the angular part against the moment, the linear against the force.
std::vector<Product> power(const S6& S, const S6& wrench);
// The outputs' entries (Store) of M, b_velocity, Q_gravity and B_bias: factor times v (v's lane
// `lane` of a row).
void store(Builder& w, const std::string& output, int row, int column, bool mirrored, const Signed& v,
           const Signed& factor = kUnit, int lane = -1);
// M* = T^T M T on T's pattern (and B_bias, T^T M's columns of the dense coordinates), from M between
// units keyed (ancestor, unit).
void project_mass(const Projection& pr, const std::map<std::pair<int, int>, Signed>& M, Builder& w);

}  // namespace wlx::codegen::derivation::composite
