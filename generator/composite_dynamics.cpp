// reduced_dynamics by composite rigid bodies in the joints' own frames: the composite inertias are
// carried from each joint's frame into its parent's by the placement between them (TwistNode::
// placement_R, placement_r), a joint's I S walks up its chain the same way, and b_velocity comes
// from the Newton-Euler recursion at zero u' in the same frames. An axis-aligned joint's S is then a
// signed unit vector (I S is a column of I, S . W one component), and a placement's zero and unit
// entries cost nothing; the same pass in K0, and Kane's sums over the bodies, both gone, needed
// every joint's axis and every body's pose in K0 from s first, which on a legged machine cost more
// than the pass itself (docs/architecture.md). Sibling limbs of one shape run side by side, one
// lane each (composite_units.cpp).
#include "composite_internal.hpp"

namespace wlx::codegen::derivation {

using lane_code::Quantity;
using lane_code::value_id;
using lane_code::ValueId;
using namespace composite;

namespace {

// Each unit's joints' placements in their parents' frames (lane g: limb g's).
struct Placement {
  std::array<Signed, 9> R;  // row-major
  S3 r;
  const Signed& at(int a, int b) const { return R[composite::at(3 * a + b)]; }
};

// A row of a unit's per-joint values (value(node)): lane g for limb g.
Signed per_joint(Builder& w, const Unit& u, Quantity what, int a, int b, const std::function<ex(int)>& value) {
  std::vector<Signed> lanes;
  for (int node : u.nodes) lanes.push_back(w.scalar(value_id(what, node, a, b), value(node)));
  return w.pack(value_id(what, u.nodes[0], a, b), lanes);
}

// (R^T v)_a and (R v)_a as products.
std::vector<Product> turned_back(const Placement& X, const S3& v, int a) {
  return {{X.at(0, a), v[0]}, {X.at(1, a), v[1]}, {X.at(2, a), v[2]}};
}
std::vector<Product> turned(const Placement& X, const S3& v, int a) {
  return {{X.at(a, 0), v[0]}, {X.at(a, 1), v[1]}, {X.at(a, 2), v[2]}};
}
std::vector<Product> joined(std::vector<Product> a, const std::vector<Product>& b) {
  append(a, b);
  return a;
}
S3 head(const S6& v) { return {v[0], v[1], v[2]}; }
S3 tail(const S6& v) { return {v[3], v[4], v[5]}; }

// Unit u's composite inertia I in its parent's frame: h' = R h + m r, and about the parent's origin
// J' = R J R^T + sigma 1 - r h'^T - (R h) r^T with sigma = r . h' + r . R h (the parallel-axis
// shift of the bodies' m |x|^2 1 - x x^T for x = r + R y).
Inertia carried(const Inertia& I, const Placement& X, int node, Builder& w) {
  S3 hr, hp;
  for (int a = 0; a < 3; ++a) hr[at(a)] = w.define(value_id(Quantity::turned_first_moment, node, a), turned(X, I.h, a));
  for (int a = 0; a < 3; ++a)
    hp[at(a)] = w.define(value_id(Quantity::carried_first_moment, node, a), {{hr[at(a)]}, {I.mass, X.r[at(a)]}});
  std::array<S3, 3> RJ;  // rows of R J
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      RJ[at(a)][at(b)] = w.define(value_id(Quantity::turned_inertia, node, a, b),
                                  {{X.at(a, 0), I.Jab(0, b)}, {X.at(a, 1), I.Jab(1, b)}, {X.at(a, 2), I.Jab(2, b)}});
  std::vector<Product> shift;
  for (int c = 0; c < 3; ++c) {
    shift.push_back({X.r[at(c)], hp[at(c)]});
    shift.push_back({X.r[at(c)], hr[at(c)]});
  }
  const Signed sigma = w.define(value_id(Quantity::carried_shift, node), shift);
  Inertia out;
  out.mass = I.mass;
  out.h = hp;
  for (std::size_t e = 0; e < kInertiaEntries.size(); ++e) {
    const auto [a, b] = kInertiaEntries[e];
    std::vector<Product> t{{RJ[at(a)][0], X.at(b, 0)}, {RJ[at(a)][1], X.at(b, 1)}, {RJ[at(a)][2], X.at(b, 2)},
                           {-X.r[at(a)], hp[at(b)]},   {-hr[at(a)], X.r[at(b)]}};
    if (a == b) t.push_back({sigma});
    out.J[e] = w.define(value_id(Quantity::carried_inertia, node, a, b), t);
  }
  return out;
}

// A wrench (force; moment) in unit u's frame, in its parent's: (R f; R n + r x R f).
S6 carried_wrench(const S6& W, const Placement& X, int to_node, int of_node, Builder& w) {
  S6 out;
  for (int a = 0; a < 3; ++a) out[at(a)] = w.define(value_id(Quantity::carried_momentum, to_node, of_node, a), turned(X, head(W), a));
  for (int a = 0; a < 3; ++a)
    out[at(a + 3)] = w.define(value_id(Quantity::carried_momentum, to_node, of_node, a + 3),
                              joined(turned(X, tail(W), a), cross(X.r, head(out), a)));
  return out;
}

// M between units, keyed (j, k): I_k S_k in k's frame, carried up the chain, S_j . (I_k S_k) at
// each unit j on it.
std::map<std::pair<int, int>, Signed> unit_mass(const Projection& pr, const std::vector<Placement>& X,
                                                const std::vector<Inertia>& composite, Builder& w) {
  std::map<std::pair<int, int>, Signed> out;
  const auto& units = pr.units.units;
  for (std::size_t k = 0; k < units.size(); ++k) {
    const int node = units[k].nodes[0];
    S6 F = momentum(composite[k], pr.axis[k], node, w);
    for (int j = static_cast<int>(k);;) {
      const int j_node = units[at(j)].nodes[0];
      const Signed v = w.define(value_id(Quantity::joint_mass, j_node, node), power(pr.axis[at(j)], F));
      if (!v.is_zero()) out[{j, static_cast<int>(k)}] = v;
      const int parent = units[at(j)].parent;
      if (parent < 0) break;
      F = carried_wrench(F, X[at(j)], units[at(parent)].nodes[0], node, w);
      j = parent;
    }
  }
  return out;
}

// Q_gravity = -g T^T tau with tau = S . (m up; h x up) of each composite (up: K0's z axis in the
// unit's frame, a lane scalar).
void gravity_forces(const Model& m, const TwistTree& tree, const Projection& pr, const std::vector<Inertia>& composite, Builder& w) {
  w.charge_to = kQ_gravity;
  std::vector<Vec3> up(tree.nodes.size());
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    const TwistNode& node = tree.nodes[k];
    const Vec3 above = node.parent < 0 ? Vec3(0, 0, 1) : up[at(node.parent)];
    for (int a = 0; a < 3; ++a)
      up[k][a] = node.placement_R(0, a) * above[0] + node.placement_R(1, a) * above[1] + node.placement_R(2, a) * above[2];
  }
  std::vector<Signed> per_unit(pr.units.units.size());
  for (std::size_t u = 0; u < pr.units.units.size(); ++u) {
    const Unit& unit = pr.units.units[u];
    const Inertia& I = composite[u];
    const int node = unit.nodes[0];
    S3 z;
    for (int c = 0; c < 3; ++c)
      z[at(c)] = per_joint(w, unit, Quantity::up_direction, c, 0, [&](int n) { return up[at(n)][c]; });
    S6 W;
    for (int c = 0; c < 3; ++c) W[at(c)] = w.define(value_id(Quantity::gravity_wrench, node, c), {{I.mass, z[at(c)]}});
    for (int c = 0; c < 3; ++c) W[at(c + 3)] = w.define(value_id(Quantity::gravity_wrench, node, c + 3), cross(I.h, z, c));
    per_unit[u] = w.define(value_id(Quantity::gravity_force, node), power(pr.axis[u], W));
  }
  const Signed minus_g = w.scalar(value_id(Quantity::minus_gravity), -m.parameter(m.dynamics->gravity).symbol);
  std::vector<Signed> Q;
  for (int l = 0; l < pr.nu; ++l) Q.push_back(pr.transposed(value_id(Quantity::commanded_gravity, l), l, per_unit, w));
  w.add(lane_code::OpenOutput{"Q_gravity", ""});
  for (int l = 0; l < pr.nu; ++l) store(w, "Q_gravity", l, -1, false, Q[at(l)], minus_g);
  w.add(lane_code::CloseOutput{});
}

// The motion at each unit's origin, in its axes, at zero u' and without gravity: omega, alpha, a.
struct Motion {
  S3 omega, alpha, acceleration;
};

// Out along the chains: omega_k = R^T omega_p + e s'_k, alpha_k = R^T alpha_p + (R^T omega_p) x e s'_k,
// a_k = R^T (a_p + alpha_p x r + omega_p x (omega_p x r)) for a revolute joint (a prismatic one
// adds 2 (R^T omega_p) x e s'_k to a_k, its own e s'_k none to omega), e s'_k from the joint's axis S.
std::vector<Motion> bias_motion(const Projection& pr, const std::vector<Placement>& X, Builder& w) {
  const auto& units = pr.units.units;
  std::vector<Motion> out(units.size());
  for (std::size_t u = 0; u < units.size(); ++u) {
    const Unit& unit = units[u];
    const int node = unit.nodes[0];
    const auto id = [&](Quantity what, int c) { return value_id(what, node, c); };
    const Motion above = unit.parent < 0 ? Motion{} : out[at(unit.parent)];
    const Placement& P = X[u];
    std::vector<Signed> lanes;
    for (int c : unit.coordinates) lanes.push_back({value_id(Quantity::rate, c)});
    const Signed sd = w.pack(value_id(Quantity::rate, unit.coordinates[0]), lanes);
    S3 e_rate_angular, e_rate_linear;  // e s'_k
    for (int c = 0; c < 3; ++c) {
      e_rate_angular[at(c)] = w.define(id(Quantity::motion_cross, c), {{pr.axis[u][at(c)], sd}});
      e_rate_linear[at(c)] = w.define(id(Quantity::motion_cross, c + 3), {{pr.axis[u][at(c + 3)], sd}});
    }
    S3 wr, ca, w_in, al_in, a_in;
    for (int c = 0; c < 3; ++c) wr[at(c)] = w.define(id(Quantity::offset_velocity, c), cross(above.omega, P.r, c));
    for (int c = 0; c < 3; ++c)
      ca[at(c)] = w.define(id(Quantity::carried_acceleration, c),
                           joined(joined({{above.acceleration[at(c)]}}, cross(above.alpha, P.r, c)), cross(above.omega, wr, c)));
    for (int a = 0; a < 3; ++a) {
      w_in[at(a)] = w.define(id(Quantity::incoming_motion, a), turned_back(P, above.omega, a));
      al_in[at(a)] = w.define(id(Quantity::incoming_motion, a + 3), turned_back(P, above.alpha, a));
      a_in[at(a)] = w.define(id(Quantity::incoming_motion, a + 6), turned_back(P, ca, a));
    }
    Motion& here = out[u];
    for (int c = 0; c < 3; ++c) {
      const std::vector<Product> coriolis = cross(w_in, e_rate_linear, c);
      here.omega[at(c)] = w.define(value_id(Quantity::spatial_velocity, node, c), {{w_in[at(c)]}, {e_rate_angular[at(c)]}});
      here.alpha[at(c)] =
          w.define(value_id(Quantity::spatial_acceleration, node, c), joined({{al_in[at(c)]}}, cross(w_in, e_rate_angular, c)));
      here.acceleration[at(c)] =
          w.define(value_id(Quantity::spatial_acceleration, node, c + 3), joined(joined({{a_in[at(c)]}}, coriolis), coriolis));
    }
  }
  return out;
}

// Body slot s of unit u (its CoM frame at (Rc, c) in the unit's frame): a_c = a + alpha x c +
// omega x (omega x c), F = m a_c; in body axes N = I alpha_b + omega_b x I omega_b; its wrench
// (F; Rc N + c x F) about the unit's origin, in the unit's axes.
S6 body_bias_wrench(const Model& m, const TwistTree& tree, const Unit& u, std::size_t s, const Motion& motion, Builder& w) {
  const int index = u.bodies[s][0];
  const auto id = [&](Quantity what, int c) { return value_id(what, index, c); };
  const auto per_lane = [&](Quantity what, int a, int b, const std::function<ex(std::size_t)>& value) {
    return per_body(w, u, s, what, a, b, value);
  };
  Placement Rc;  // the body's axes in the unit's, and its CoM
  for (int a = 0; a < 3; ++a) {
    Rc.r[at(a)] = per_lane(Quantity::com_offset, a, 0, [&](std::size_t i) { return tree.body_r[i][a]; });
    for (int b = 0; b < 3; ++b)
      Rc.R[at(3 * a + b)] = per_lane(Quantity::com_rotation, a, b, [&](std::size_t i) { return tree.body_R[i](a, b); });
  }
  const Signed mass = per_lane(Quantity::mass, 0, 0, [&](std::size_t i) { return m.parameter(m.bodies[i].mass).symbol; });
  S3 I;
  for (int a = 0; a < 3; ++a)
    I[at(a)] = per_lane(Quantity::inertia, a, 0, [&](std::size_t i) { return m.parameter(m.bodies[i].inertia[at(a)]).symbol; });
  S3 wc, ac, F, wb, ab, Iw, N;
  for (int a = 0; a < 3; ++a) wc[at(a)] = w.define(id(Quantity::com_velocity, a), cross(motion.omega, Rc.r, a));
  for (int a = 0; a < 3; ++a) {
    ac[at(a)] = w.define(id(Quantity::com_acceleration, a),
                         joined(joined({{motion.acceleration[at(a)]}}, cross(motion.alpha, Rc.r, a)), cross(motion.omega, wc, a)));
    F[at(a)] = w.define(id(Quantity::force, a), {{mass, ac[at(a)]}});
  }
  for (int a = 0; a < 3; ++a) {
    wb[at(a)] = w.define(id(Quantity::body_rate, a), turned_back(Rc, motion.omega, a));
    ab[at(a)] = w.define(id(Quantity::body_angular_acceleration, a), turned_back(Rc, motion.alpha, a));
  }
  for (int a = 0; a < 3; ++a) Iw[at(a)] = w.define(id(Quantity::angular_momentum, a), {{I[at(a)], wb[at(a)]}});
  for (int a = 0; a < 3; ++a) N[at(a)] = w.define(id(Quantity::body_moment, a), joined({{I[at(a)], ab[at(a)]}}, cross(wb, Iw, a)));
  S6 out{F[0], F[1], F[2]};
  for (int a = 0; a < 3; ++a) out[at(a + 3)] = w.define(id(Quantity::moment, a), joined(turned(Rc, N, a), cross(Rc.r, F, a)));
  return out;
}

// b_velocity = T^T tau, in its output's block: the bodies' bias wrenches summed back along the chains in each unit's frame
// (a child's carried by its placement), tau = S . W.
void velocity_forces(const Model& m, const TwistTree& tree, const Projection& pr, const std::vector<Placement>& X, Builder& w) {
  w.charge_to = kB_velocity;
  w.add(lane_code::OpenOutput{"b_velocity", ""});
  const std::vector<Motion> motion = bias_motion(pr, X, w);
  const Units& units = pr.units;
  std::vector<S6> beyond(units.units.size()), passed(units.units.size());
  std::vector<Signed> per_unit(units.units.size());
  for (std::size_t u = units.units.size(); u-- > 0;) {
    const Unit& unit = units.units[u];
    const int node = unit.nodes[0];
    std::vector<S6> own;
    for (std::size_t s = 0; s < unit.bodies.size(); ++s) own.push_back(body_bias_wrench(m, tree, unit, s, motion[u], w));
    const Summands sum{units, u};
    for (int c = 0; c < 6; ++c)
      beyond[u][at(c)] = w.define(value_id(Quantity::wrench, node, c), sum(
                                                                            [&] {
                                                                              std::vector<Product> t;
                                                                              for (const S6& x : own) t.push_back({x[at(c)]});
                                                                              return t;
                                                                            },
                                                                            [&](std::size_t child) { return passed[child][at(c)]; }));
    per_unit[u] = w.define(value_id(Quantity::joint_force, node), power(pr.axis[u], beyond[u]));
    if (unit.parent < 0) continue;
    for (int a = 0; a < 3; ++a) passed[u][at(a)] = w.define(value_id(Quantity::transmitted_force, node, a), turned(X[u], head(beyond[u]), a));
    for (int a = 0; a < 3; ++a)
      passed[u][at(a + 3)] = w.define(value_id(Quantity::transmitted_force, node, a + 3),
                                      joined(turned(X[u], tail(beyond[u]), a), cross(X[u].r, head(passed[u]), a)));
  }
  std::vector<Signed> b;
  for (int l = 0; l < pr.nu; ++l) b.push_back(pr.transposed(value_id(Quantity::commanded_force, l), l, per_unit, w));
  for (int l = 0; l < pr.nu; ++l) store(w, "b_velocity", l, -1, false, b[at(l)]);
  w.add(lane_code::CloseOutput{});
}

}  // namespace

lane_code::LaneProgram composite_rigid_body_program(const Model& m) {
  const RateRoles roles = rate_roles(m);
  const TwistTree tree = twist_tree(m, roles);
  const Units units = group_units(tree, roles);
  Builder w(units.width);
  Projection pr{units, roles, rate_speeds(m, roles), static_cast<int>(m.dynamics->commanded.size()), {}};
  w.charge_to = kM;
  if (units.width > 1) w.add(lane_code::LaneTypes{});
  std::vector<Placement> X;
  for (const Unit& u : units.units) {
    const auto node_of = [&](int n) -> const TwistNode& { return tree.nodes[at(n)]; };
    // The joint's axis in its own frame: (sign e_i; 0) revolute, (0; sign e_i) prismatic.
    S6 S;
    for (int c = 0; c < 6; ++c)
      S[at(c)] = per_joint(w, u, Quantity::joint_axis, c, 0, [&](int n) {
        const JointRecord& joint = *node_of(n).joint;
        const bool angular = c < 3;
        return angular == joint.revolute && c % 3 == static_cast<int>(joint.local_axis) ? ex(joint.sign) : ex(0);
      });
    pr.axis.push_back(S);
    Placement P;
    for (int a = 0; a < 3; ++a) {
      P.r[at(a)] = per_joint(w, u, Quantity::local_offset, a, 0, [&](int n) { return node_of(n).placement_r[a]; });
      for (int b = 0; b < 3; ++b)
        P.R[at(3 * a + b)] = per_joint(w, u, Quantity::local_rotation, a, b, [&](int n) { return node_of(n).placement_R(a, b); });
    }
    X.push_back(P);
  }
  w.add(lane_code::Comment{"The bodies' inertias in their joints' frames, and the composites beyond each joint carried in."});
  const std::vector<Inertia> composite = composite_inertias(
      units,
      [&](std::size_t u, std::size_t s) {
        return body_inertia(
            m, units.units[u], s, [&](std::size_t i) { return tree.body_r[i]; }, [&](std::size_t i) { return tree.body_R[i]; }, w);
      },
      [&](std::size_t u, const Inertia& I) { return carried(I, X[u], units.units[u].nodes[0], w); }, w);
  w.add(lane_code::Comment{"M on the coordinates: I_k S_k carried up the chain, S_j . (I_k S_k) at each joint j on it."});
  const auto M = unit_mass(pr, X, composite, w);
  w.add(lane_code::Comment{"M on the commanded speeds: T^T M T on T's pattern (T^T M's dense columns are B_bias)."});
  project_mass(pr, M, w);
  w.add(lane_code::Comment{"Q_gravity from the composites' masses and first moments, projected by T^T."});
  gravity_forces(m, tree, pr, composite, w);
  // Last, in a block of its own: nothing after it reads its values, and a call for M alone skips it.
  w.add(lane_code::Comment{"b_velocity: the bodies' bias wrenches summed back along the chains, projected by T^T."});
  velocity_forces(m, tree, pr, X, w);
  return std::move(w.program());
}

}  // namespace wlx::codegen::derivation
