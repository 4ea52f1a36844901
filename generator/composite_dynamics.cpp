// reduced_dynamics by composite rigid bodies: straight-line code (lane_code.hpp) that forms M on the
// coordinates from the composite inertias beyond each joint, projects it onto the commanded speeds
// on T's pattern, and gets b_velocity and Q_gravity from one backward sum each. Kane's sums
// (reduced_dynamics.cpp) carry a row of lanes per commanded speed through every body; here each
// body's inertia is added once, to the composite of its node, so the cost grows with the pairs of
// joints on a chain rather than with bodies times speeds. Sibling limbs of one shape (a walking
// machine's legs) run side by side, one lane each (composite_units.cpp).
#include "composite_internal.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>

namespace wlx::codegen::derivation {

using lane_code::kOne;
using lane_code::Layout;
using lane_code::Quantity;
using lane_code::Term;
using lane_code::value_id;
using lane_code::ValueId;
using namespace composite;

namespace {

using S3 = std::array<Signed, 3>;
using S6 = std::array<Signed, 6>;  // (angular; linear) of a motion, (force; moment) of a wrench

// (x cross y)_c as two products.
std::vector<Product> cross(const S3& x, const S3& y, int c) {
  const std::size_t c1 = at((c + 1) % 3), c2 = at((c + 2) % 3);
  return {{x[c1], y[c2]}, {-x[c2], y[c1]}};
}
void append(std::vector<Product>& to, const std::vector<Product>& more) {
  to.insert(to.end(), more.begin(), more.end());
}

// The rotational inertia's six entries (a <= b), in this order.
constexpr std::array<std::pair<int, int>, 6> kInertiaEntries{{{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}}};
std::size_t entry_of(int a, int b) {
  for (std::size_t e = 0; e < kInertiaEntries.size(); ++e)
    if (kInertiaEntries[e] == std::pair{std::min(a, b), std::max(a, b)}) return e;
  throw std::logic_error("inertia entry");
}

// A spatial inertia about the reference point (Projection::origin), in K0: mass, first moment
// h = m p (p the CoM from the reference point), rotational inertia J.
struct Inertia {
  Signed mass;
  S3 h;
  std::array<Signed, 6> J;
  const Signed& Jab(int a, int b) const { return J[entry_of(a, b)]; }
};

// Body slot s of unit u about the reference point: J = R diag(I) R^T + m (|p|^2 1 - p p^T). With R's
// columns r_k orthonormal, R diag(I) R^T = I_1 1 + (I_2 - I_1) r_2 r_2^T + (I_3 - I_1) r_3 r_3^T, so
// J = sigma 1 + (I_2 - I_1) r_2 r_2^T + (I_3 - I_1) r_3 r_3^T - h p^T with sigma = I_1 + h . p
// (h = m p): two products per entry fewer than R diag(I) R^T written out.
Inertia body_inertia(const Model& m, const Unit& u, std::size_t s, const Vec3& origin, Builder& w) {
  const int index = u.bodies[s][0];  // the values' names: the first lane's body
  const auto per_lane = [&](Quantity what, int a, int b, const auto& value) {
    std::vector<Signed> lanes;
    for (int i : u.bodies[s]) lanes.push_back(w.scalar(value_id(what, i, a, b), value(m.bodies[at(i)])));
    return w.pack(value_id(what, index, a, b), lanes);
  };
  const auto moment = [&](const Body& b, int k) { return m.parameter(b.inertia[at(k)]).symbol; };
  Inertia out;
  out.mass = per_lane(Quantity::mass, 0, 0, [&](const Body& b) { return m.parameter(b.mass).symbol; });
  S3 p;
  for (int c = 0; c < 3; ++c)
    p[at(c)] = per_lane(Quantity::com_offset, c, 0, [&](const Body& b) { return b.com_frame.r[c] - origin[c]; });
  const auto R = [&](int a, int k) {
    return per_lane(Quantity::com_rotation, a, k, [&](const Body& b) { return b.com_frame.R(a, k); });
  };
  std::array<S3, 2> weighted;  // (I_k - I_1) r_k for k = 2, 3
  for (int k = 1; k < 3; ++k) {
    const Signed difference =
        per_lane(Quantity::inertia_difference, k, 0, [&](const Body& b) { return moment(b, k) - moment(b, 0); });
    for (int a = 0; a < 3; ++a)
      weighted[at(k - 1)][at(a)] = w.define(value_id(Quantity::rotated_inertia, index, a, k), {{R(a, k), difference}});
  }
  for (int c = 0; c < 3; ++c)
    out.h[at(c)] = w.define(value_id(Quantity::first_moment, index, c), {{out.mass, p[at(c)]}});
  std::vector<Product> shift{{per_lane(Quantity::inertia, 0, 0, [&](const Body& b) { return moment(b, 0); })}};
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

// The composite inertias, from the leaves in.
std::vector<Inertia> composite_inertias(const Model& m, const Units& units, const Vec3& origin, Builder& w) {
  std::vector<Inertia> out(units.units.size());
  for (std::size_t u = units.units.size(); u-- > 0;) {
    const Unit& unit = units.units[u];
    std::vector<Inertia> own;
    for (std::size_t s = 0; s < unit.bodies.size(); ++s) own.push_back(body_inertia(m, unit, s, origin, w));
    const Summands sum{units, u};
    const int k = unit.nodes[0];
    const auto total = [&](const ValueId& target, const auto& pick) {
      return w.define(target, sum(
                                  [&] {
                                    std::vector<Product> t;
                                    for (const Inertia& x : own) t.push_back({pick(x)});
                                    return t;
                                  },
                                  [&](std::size_t child) { return pick(out[child]); }));
    };
    out[u].mass = total(value_id(Quantity::composite_mass, k), [](const Inertia& x) { return x.mass; });
    for (int c = 0; c < 3; ++c)
      out[u].h[at(c)] =
          total(value_id(Quantity::composite_first_moment, k, c), [&](const Inertia& x) { return x.h[at(c)]; });
    for (std::size_t e = 0; e < kInertiaEntries.size(); ++e)
      out[u].J[e] = total(value_id(Quantity::composite_inertia, k, kInertiaEntries[e].first, kInertiaEntries[e].second),
                          [&](const Inertia& x) { return x.J[e]; });
  }
  return out;
}

// I S for a composite inertia and a joint's axis S = (a; b): the momentum of the bodies beyond per
// unit rate, (force m b + a x h; moment about the reference point J a + h x b).
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

// S_j . W as products: the angular part against the moment, the linear against the force.
std::vector<Product> power(const S6& S, const S6& wrench) {
  std::vector<Product> t;
  for (int c = 0; c < 3; ++c) {
    t.push_back({S[at(c)], wrench[at(c + 3)]});
    t.push_back({S[at(c + 3)], wrench[at(c)]});
  }
  return t;
}

// M between units: S_j . (I_k S_k) for each unit k and each unit j on its chain up to k (a row
// where k is a row unit: lane g pairs the joints of lane g), keyed (j, k).
std::map<std::pair<int, int>, Signed> unit_mass(const Projection& pr, const std::vector<Inertia>& composite,
                                                Builder& w) {
  std::map<std::pair<int, int>, Signed> out;
  for (std::size_t k = 0; k < pr.units.units.size(); ++k) {
    const S6 F = momentum(composite[k], pr.axis[k], pr.units.units[k].nodes[0], w);
    for (int j = static_cast<int>(k); j >= 0; j = pr.units.units[at(j)].parent) {
      const Signed v =
          w.define(value_id(Quantity::joint_mass, pr.units.units[at(j)].nodes[0], pr.units.units[k].nodes[0]),
                   power(pr.axis[at(j)], F));
      if (!v.is_zero()) out[{j, static_cast<int>(k)}] = v;
    }
  }
  return out;
}

// The outputs' entries (Store) of M, b_velocity, Q_gravity and B_bias: factor times v (v's lane
// `lane` of a row).
void store(Builder& w, const std::string& output, int row, int column, bool mirrored, const Signed& v,
           const Signed& factor = kUnit, int lane = -1) {
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
  // Every value before the outputs' blocks, none inside one: the code a value needs is placed
  // before its first reader (emit_function.cpp), which must not be in a block a later reader is not.
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

// Q_gravity = T^T tau_g: gravity's wrench beyond a joint is (force -g m e_z; moment -g h x e_z) of
// its composite, so tau_g = -g (b_z m + a_x h_y - a_y h_x) for the axis (a; b).
void gravity_forces(const Model& m, const Projection& pr, const std::vector<Inertia>& composite, Builder& w) {
  w.charge_to = kQ_gravity;
  std::vector<Signed> per_unit(pr.units.units.size());
  for (std::size_t u = 0; u < pr.units.units.size(); ++u) {
    const S6& S = pr.axis[u];
    const Inertia& I = composite[u];
    per_unit[u] = w.define(value_id(Quantity::gravity_force, pr.units.units[u].nodes[0]),
                           {{S[5], I.mass}, {S[0], I.h[1]}, {-S[1], I.h[0]}});
  }
  const Signed minus_g = w.scalar(value_id(Quantity::minus_gravity), -m.parameter(m.dynamics->gravity).symbol);
  std::vector<Signed> Q;
  for (int l = 0; l < pr.nu; ++l) Q.push_back(pr.transposed(value_id(Quantity::commanded_gravity, l), l, per_unit, w));
  w.add(lane_code::OpenOutput{"Q_gravity", ""});
  for (int l = 0; l < pr.nu; ++l) store(w, "Q_gravity", l, -1, false, Q[at(l)], minus_g);
  w.add(lane_code::CloseOutput{});
}

// Body slot s of unit u: its wrench at zero u' without gravity (force m a_bias; moment p x force +
// R N, N = I alpha_b + omega_b x I omega_b in body axes), as Kane's sums weigh it.
S6 bias_wrench(const Model& m, const Unit& u, std::size_t s, const Vec3& origin, Builder& w) {
  const int index = u.bodies[s][0];
  const auto per_lane = [&](Quantity what, int a, int b, const auto& value) {
    std::vector<Signed> lanes;
    for (int i : u.bodies[s]) lanes.push_back(w.scalar(value_id(what, i, a, b), value(m.bodies[at(i)])));
    return w.pack(value_id(what, index, a, b), lanes);
  };
  const auto torque = [&](const Body& body) {
    const Frame& f = body.com_frame;
    const auto to_body = [&](const Vec3& v) {
      Vec3 out;
      for (int a = 0; a < 3; ++a) out[a] = f.R(0, a) * v[0] + f.R(1, a) * v[1] + f.R(2, a) * v[2];
      return out;
    };
    Vec3 I;
    for (int a = 0; a < 3; ++a) I[a] = m.parameter(body.inertia[at(a)]).symbol;
    const auto inertia_times = [&](const Vec3& v) { return Vec3(I[0] * v[0], I[1] * v[1], I[2] * v[2]); };
    const Vec3 omega = to_body(f.omega);
    return inertia_times(to_body(f.alpha_bias)) + wlx::codegen::cross(omega, inertia_times(omega));
  };
  const Signed mass = per_lane(Quantity::mass, 0, 0, [&](const Body& b) { return m.parameter(b.mass).symbol; });
  S3 p, F, N;
  for (int c = 0; c < 3; ++c) {
    p[at(c)] = per_lane(Quantity::com_offset, c, 0, [&](const Body& b) { return b.com_frame.r[c] - origin[c]; });
    N[at(c)] = per_lane(Quantity::bias_torque, c, 0, [&](const Body& b) { return torque(b)[c]; });
    const Signed a = per_lane(Quantity::bias_acceleration, c, 0, [&](const Body& b) { return b.com_frame.a_bias[c]; });
    F[at(c)] = w.define(value_id(Quantity::force, index, c), {{mass, a}});
  }
  S6 out{F[0], F[1], F[2]};
  for (int c = 0; c < 3; ++c) {
    std::vector<Product> t = cross(p, F, c);
    for (int k = 0; k < 3; ++k)
      t.push_back(
          {per_lane(Quantity::com_rotation, c, k, [&](const Body& b) { return b.com_frame.R(c, k); }), N[at(k)]});
    out[at(c + 3)] = w.define(value_id(Quantity::moment, index, c), t);
  }
  return out;
}

// b_velocity = T^T tau_bias: the bodies' bias wrenches summed back along the chains, tau = S . W.
void velocity_forces(const Model& m, const Projection& pr, Builder& w) {
  w.charge_to = kB_velocity;
  const Units& units = pr.units;
  std::vector<S6> beyond(units.units.size());
  std::vector<Signed> per_unit(units.units.size());
  for (std::size_t u = units.units.size(); u-- > 0;) {
    std::vector<S6> own;
    for (std::size_t s = 0; s < units.units[u].bodies.size(); ++s)
      own.push_back(bias_wrench(m, units.units[u], s, pr.origin, w));
    const Summands sum{units, u};
    for (int c = 0; c < 6; ++c)
      beyond[u][at(c)] = w.define(value_id(Quantity::wrench, units.units[u].nodes[0], c),
                                  sum(
                                      [&] {
                                        std::vector<Product> t;
                                        for (const S6& x : own) t.push_back({x[at(c)]});
                                        return t;
                                      },
                                      [&](std::size_t child) { return beyond[child][at(c)]; }));
    per_unit[u] = w.define(value_id(Quantity::joint_force, units.units[u].nodes[0]), power(pr.axis[u], beyond[u]));
  }
  std::vector<Signed> b;
  for (int l = 0; l < pr.nu; ++l) b.push_back(pr.transposed(value_id(Quantity::commanded_force, l), l, per_unit, w));
  w.add(lane_code::OpenOutput{"b_velocity", ""});
  for (int l = 0; l < pr.nu; ++l) store(w, "b_velocity", l, -1, false, b[at(l)]);
  w.add(lane_code::CloseOutput{});
}

// The point the spatial quantities are taken about: the first revolute joint's (a floating base's
// position, a fixed base's first joint), so that the inertias about it stay of the machine's size
// wherever it stands (about K0's origin, m |p|^2 would cancel in M to the square of its distance
// over its size), and a rotation at the base has no linear part. K0's origin without one.
Vec3 reference_point(const TwistTree& tree) {
  for (const TwistNode& node : tree.nodes)
    if (node.joint->revolute) return node.joint->origin;
  return Vec3(0, 0, 0);
}

// A joint's twist per unit rate about `origin`: (a; (o - origin) x a) for a revolute joint (axis a
// through o), (0; a) for a prismatic one.
std::array<ex, 6> axis_about(const JointRecord& joint, const Vec3& origin) {
  const Vec3 arm(joint.origin[0] - origin[0], joint.origin[1] - origin[1], joint.origin[2] - origin[2]);
  const Vec3 linear = joint.revolute ? wlx::codegen::cross(arm, joint.axis) : joint.axis;
  std::array<ex, 6> S;
  for (int c = 0; c < 3; ++c) {
    S[at(c)] = joint.revolute ? joint.axis[c] : ex(0);
    S[at(c + 3)] = linear[c];
  }
  return S;
}

}  // namespace

lane_code::LaneProgram composite_rigid_body_program(const Model& m) {
  const RateRoles roles = rate_roles(m);
  const TwistTree tree = twist_tree(m, roles);
  const Units units = group_units(tree, roles);
  Builder w(units.width);
  Projection pr{
      units, roles, rate_speeds(m, roles), static_cast<int>(m.dynamics->commanded.size()), {}, reference_point(tree)};
  w.charge_to = kM;
  if (units.width > 1) w.add(lane_code::LaneTypes{});
  for (const Unit& u : units.units) {
    const int k = u.nodes[0];
    S6 S;
    for (int c = 0; c < 6; ++c) {
      std::vector<Signed> lanes;
      for (int node : u.nodes)
        lanes.push_back(w.scalar(value_id(Quantity::joint_axis, node, c),
                                 axis_about(*tree.nodes[at(node)].joint, pr.origin)[at(c)]));
      S[at(c)] = w.pack(value_id(Quantity::joint_axis, k, c), lanes);
    }
    pr.axis.push_back(S);
  }
  w.add(lane_code::Comment{
      "The bodies' inertias about the first revolute joint's origin, in K0, and their composites beyond each joint."});
  const std::vector<Inertia> composite = composite_inertias(m, units, pr.origin, w);
  w.add(lane_code::Comment{"M on the coordinates: S_j . (I_k S_k) for each joint k and each joint j on its chain."});
  const auto M = unit_mass(pr, composite, w);
  w.add(lane_code::Comment{"M on the commanded speeds: T^T M T on T's pattern (T^T M's dense columns are B_bias)."});
  project_mass(pr, M, w);
  w.add(lane_code::Comment{"b_velocity: the bodies' bias wrenches summed back along the chains, projected by T^T."});
  velocity_forces(m, pr, w);
  w.add(lane_code::Comment{"Q_gravity from the composites' masses and first moments, projected by T^T."});
  gravity_forces(m, pr, composite, w);
  return std::move(w.program());
}

}  // namespace wlx::codegen::derivation
