// generalized_forces: the bodies' inverse dynamics by the recursive Newton-Euler equations, derived
// as straight-line scalar code (lane_code.hpp, printed by lane_printer.hpp), projected onto the
// commanded speeds.
#include "derivations_internal.hpp"
#include "lane_printer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>

namespace wlx::codegen {

using namespace derivation;
using lane_code::kOne;
using lane_code::Layout;
using lane_code::Quantity;
using lane_code::Term;
using lane_code::value_id;
using lane_code::ValueId;

namespace {

// Builds the straight-line scalar code of the recursive Newton-Euler pass (lane_code.hpp), one
// definition per value. A value is zero (the zero ValueId) when it is exactly zero: products with a
// zero and zero terms are dropped, a sum of one plain term is that term (no statement, no
// operation).
class ScalarBuilder {
 public:
  struct Product {
    ValueId a, b;  // a * b; b one: a alone
    bool negate = false;
  };
  // A lane scalar (zero for an exact zero).
  ValueId scalar(const ValueId& id, const ex& value) { return program_.scalar(id, value); }
  ValueId define(const ValueId& target, const std::vector<Product>& products) {
    std::vector<Term> terms;
    for (const Product& p : products) {
      if (p.a.is_zero() || p.b.is_zero()) continue;
      if (p.b.what == Quantity::one) terms.push_back({kOne, p.a, -1, p.negate});
      else terms.push_back({p.a, p.b, -1, p.negate});
    }
    if (terms.empty()) return {};
    if (terms.size() == 1 && !terms[0].negate && terms[0].factor.what == Quantity::one) return terms[0].value;
    add(lane_code::Define{target, Layout::scalar, std::move(terms)});
    return target;
  }
  void add(lane_code::Step step) { program_.statements.push_back({std::move(step)}); }
  const lane_code::LaneProgram& program() const { return program_; }

 private:
  lane_code::LaneProgram program_;
};
using Product = ScalarBuilder::Product;

// (x cross y)_c as two products.
std::vector<Product> cross_terms(const std::array<ValueId, 3>& x, const std::array<ValueId, 3>& y, int c) {
  const auto c1 = static_cast<std::size_t>((c + 1) % 3), c2 = static_cast<std::size_t>((c + 2) % 3);
  return {{x[c1], y[c2]}, {x[c2], y[c1], true}};
}

using V3 = std::array<ValueId, 3>;
using V6 = std::array<ValueId, 6>;
V3 head(const V6& v) { return V3{v[0], v[1], v[2]}; }
V3 tail(const V6& v) { return V3{v[3], v[4], v[5]}; }

// generalized_forces as declared: its documentation and its inputs s'' and T.
FunctionSpec generalized_forces_spec() {
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
  return fn;
}

// Per node of the tree: its joint's spatial axis, and the spatial velocity and acceleration there.
struct SpatialMotion {
  std::vector<V6> axis, velocity, acceleration;
};

// Out along the chains: a joint's spatial axis S = (a; o x a) (revolute, axis a through o) or
// (0; a) (prismatic), in K0; V = V_parent + S s'_j; A = A_parent + S s''_j + (V_parent x S) s'_j
// (the axis moves with the parent: d/dt S = V_parent x S, the motion cross product).
SpatialMotion spatial_motion(const TwistTree& tree, ScalarBuilder& w) {
  SpatialMotion motion{std::vector<V6>(tree.nodes.size()), std::vector<V6>(tree.nodes.size()), std::vector<V6>(tree.nodes.size())};
  std::vector<V6>&axis = motion.axis, &velocity = motion.velocity, &acceleration = motion.acceleration;
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    const TwistNode& node = tree.nodes[k];
    const JointRecord& joint = *node.joint;
    const std::array<ex, 6> S = spatial_axis(joint);
    const int kk = static_cast<int>(k);
    for (std::size_t c = 0; c < 6; ++c) axis[k][c] = w.scalar(value_id(Quantity::joint_axis, kk, static_cast<int>(c)), S[c]);
    const ValueId sd = value_id(Quantity::rate, joint.coordinate), sdd = value_id(Quantity::acceleration, joint.coordinate);
    const V6 V0 = node.parent < 0 ? V6{} : velocity[static_cast<std::size_t>(node.parent)];
    const V6 A0 = node.parent < 0 ? V6{} : acceleration[static_cast<std::size_t>(node.parent)];
    // V_parent x S = (w x a; w x b + v x a).
    V6 X;
    for (int c = 0; c < 3; ++c) {
      X[static_cast<std::size_t>(c)] = w.define(value_id(Quantity::motion_cross, kk, c), cross_terms(head(V0), head(axis[k]), c));
      std::vector<Product> lin = cross_terms(head(V0), tail(axis[k]), c);
      for (const Product& t : cross_terms(tail(V0), head(axis[k]), c)) lin.push_back(t);
      X[static_cast<std::size_t>(c + 3)] = w.define(value_id(Quantity::motion_cross, kk, c + 3), lin);
    }
    for (std::size_t c = 0; c < 6; ++c) {
      const int cc = static_cast<int>(c);
      velocity[k][c] = w.define(value_id(Quantity::spatial_velocity, kk, cc), {{V0[c], kOne}, {axis[k][c], sd}});
      acceleration[k][c] = w.define(value_id(Quantity::spatial_acceleration, kk, cc), {{A0[c], kOne}, {axis[k][c], sdd}, {X[c], sd}});
    }
  }
  return motion;
}

// Body i (V, A: the spatial velocity and acceleration at its node; g: the lane scalar g): its CoM's
// velocity v = V_lin + omega x p and acceleration a = A_lin + alpha x p + omega x v; force
// F = m (a + g e_z); moment in body axes N = I alpha_b + omega_b x I omega_b; returns its wrench
// about K0's origin (F; R N + p x F).
V6 body_wrench(const Model& m, std::size_t i, const V6& V, const V6& A, const ValueId& g, ScalarBuilder& w) {
  const Body& body = m.bodies[i];
  const Frame& f = body.com_frame;
  const int index = static_cast<int>(i);
  const auto id = [&](Quantity what, int c) { return value_id(what, index, c); };
  w.add(lane_code::Comment{fmt::format("body {}: {}", body.name, body.meaning)});
  V3 p, v, a, F, wb, ab, Iw, N, M;
  std::array<ValueId, 9> R;
  for (int c = 0; c < 3; ++c) p[static_cast<std::size_t>(c)] = w.scalar(id(Quantity::com_offset, c), f.r[c]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R[static_cast<std::size_t>(3 * r + c)] = w.scalar(value_id(Quantity::com_rotation, index, r, c), f.R(r, c));
  const auto Rrc = [&](int r, int c) -> const ValueId& { return R[static_cast<std::size_t>(3 * r + c)]; };
  const ValueId mass = w.scalar(value_id(Quantity::mass, index), m.parameter(body.mass).symbol);
  V3 I;
  for (int c = 0; c < 3; ++c)
    I[static_cast<std::size_t>(c)] = w.scalar(id(Quantity::inertia, c), m.parameter(body.inertia[static_cast<std::size_t>(c)]).symbol);
  for (int c = 0; c < 3; ++c) {
    std::vector<Product> t = cross_terms(head(V), p, c);
    t.insert(t.begin(), {V[static_cast<std::size_t>(c + 3)], kOne});
    v[static_cast<std::size_t>(c)] = w.define(id(Quantity::com_velocity, c), t);
  }
  for (int c = 0; c < 3; ++c) {
    std::vector<Product> t = cross_terms(head(A), p, c);
    for (const Product& x : cross_terms(head(V), v, c)) t.push_back(x);
    t.insert(t.begin(), {A[static_cast<std::size_t>(c + 3)], kOne});
    if (c == 2) t.push_back({g, kOne});
    a[static_cast<std::size_t>(c)] = w.define(id(Quantity::com_acceleration, c), t);
    F[static_cast<std::size_t>(c)] = w.define(id(Quantity::force, c), {{mass, a[static_cast<std::size_t>(c)]}});
  }
  for (int c = 0; c < 3; ++c) {
    wb[static_cast<std::size_t>(c)] = w.define(id(Quantity::body_rate, c), {{Rrc(0, c), V[0]}, {Rrc(1, c), V[1]}, {Rrc(2, c), V[2]}});
    ab[static_cast<std::size_t>(c)] = w.define(id(Quantity::body_angular_acceleration, c), {{Rrc(0, c), A[0]}, {Rrc(1, c), A[1]}, {Rrc(2, c), A[2]}});
  }
  for (int c = 0; c < 3; ++c)
    Iw[static_cast<std::size_t>(c)] = w.define(id(Quantity::angular_momentum, c), {{I[static_cast<std::size_t>(c)], wb[static_cast<std::size_t>(c)]}});
  for (int c = 0; c < 3; ++c) {
    std::vector<Product> t = cross_terms(wb, Iw, c);
    t.insert(t.begin(), {I[static_cast<std::size_t>(c)], ab[static_cast<std::size_t>(c)]});
    N[static_cast<std::size_t>(c)] = w.define(id(Quantity::body_moment, c), t);
  }
  for (int c = 0; c < 3; ++c) {
    std::vector<Product> t = cross_terms(p, F, c);
    for (int k = 0; k < 3; ++k) t.push_back({Rrc(c, k), N[static_cast<std::size_t>(k)]});
    M[static_cast<std::size_t>(c)] = w.define(id(Quantity::moment, c), t);
  }
  return {F[0], F[1], F[2], M[0], M[1], M[2]};
}

// Back along the chains: the wrenches beyond each joint, tau_j = S . (moment; force). Returns each
// moving coordinate's generalized force (the sum of its joints' taus) that is not exactly zero.
std::map<int, ValueId> joint_forces(const TwistTree& tree, const std::vector<V6>& axis, const std::vector<V6>& wrench, ScalarBuilder& w) {
  w.add(lane_code::Comment{"Back along the chains: the wrenches beyond each joint and the joints' generalized forces."});
  std::vector<V6> beyond(tree.nodes.size());
  // A component of a joint's wrench sum is read by its tau where the axis has the matching component
  // (force with the linear part, moment with the angular), and by the joints before it that read it.
  std::vector<std::array<bool, 6>> read(tree.nodes.size());
  for (std::size_t k = 0; k < tree.nodes.size(); ++k)
    for (std::size_t c = 0; c < 6; ++c)
      read[k][c] = !axis[k][c < 3 ? c + 3 : c - 3].is_zero() ||
                   (tree.nodes[k].parent >= 0 && read[static_cast<std::size_t>(tree.nodes[k].parent)][c]);
  std::map<int, std::vector<Product>> tau_terms;  // coordinate -> its joints' taus
  for (std::size_t k = tree.nodes.size(); k-- > 0;) {
    const TwistNode& node = tree.nodes[k];
    for (std::size_t c = 0; c < 6; ++c) {
      if (!read[k][c]) continue;
      std::vector<Product> parts;
      for (int i : node.bodies) parts.push_back({wrench[static_cast<std::size_t>(i)][c], kOne});
      for (int child : node.children) parts.push_back({beyond[static_cast<std::size_t>(child)][c], kOne});
      beyond[k][c] = w.define(value_id(Quantity::wrench, static_cast<int>(k), static_cast<int>(c)), parts);
    }
    std::vector<Product> t;
    for (std::size_t c = 0; c < 3; ++c) t.push_back({axis[k][c], beyond[k][c + 3]});
    for (std::size_t c = 0; c < 3; ++c) t.push_back({axis[k][c + 3], beyond[k][c]});
    const ValueId tau = w.define(value_id(Quantity::joint_force, static_cast<int>(k)), t);
    if (!tau.is_zero()) tau_terms[node.joint->coordinate].push_back({tau, kOne});
  }
  std::map<int, ValueId> tau_of;
  for (const auto& [j, terms] : tau_terms) {
    const ValueId t = w.define(value_id(Quantity::coordinate_force, j), terms);
    if (!t.is_zero()) tau_of[j] = t;
  }
  return tau_of;
}

// ---- the same pass in the joints' own frames ---------------------------------------------------
// Each node's motion in the axes of the frame just after its joint, carried from its parent's by
// the placement between them (TwistNode::placement_R, placement_r): an axis-aligned joint then
// adds its rate to one component, and a placement's zero and unit entries cost nothing. The world
// frame's pass instead recomputes every joint's axis and origin in K0 from s (a third of its
// operations on the wheeled quadruped).

// A lane scalar that may be an exact 0 or +-1 (a placement's entries): as a product's factor, a
// zero drops the product and a unit leaves the value alone.
struct Coefficient {
  ValueId id;  // zero: 0; kOne: +-1
  bool negate = false;
};
using C3 = std::array<Coefficient, 3>;
using C33 = std::array<Coefficient, 9>;  // row-major

Coefficient coefficient(ScalarBuilder& w, const ValueId& id, const ex& value) {
  if (value.is_zero()) return {};
  if (value.is_equal(1)) return {kOne, false};
  if (value.is_equal(-1)) return {kOne, true};
  return {w.scalar(id, value), false};
}
// c * v (negated when `negate`).
Product times(const Coefficient& c, const ValueId& v, bool negate = false) { return {v, c.id, c.negate != negate}; }
// (x cross v)_c and (v cross x)_c for coefficients x and values v.
std::vector<Product> cross_cv(const C3& x, const V3& v, int c) {
  const auto c1 = static_cast<std::size_t>((c + 1) % 3), c2 = static_cast<std::size_t>((c + 2) % 3);
  return {times(x[c1], v[c2]), times(x[c2], v[c1], true)};
}
std::vector<Product> cross_vc(const V3& v, const C3& x, int c) {
  const auto c1 = static_cast<std::size_t>((c + 1) % 3), c2 = static_cast<std::size_t>((c + 2) % 3);
  return {times(x[c2], v[c1]), times(x[c1], v[c2], true)};
}
std::vector<Product> join(std::vector<Product> a, const std::vector<Product>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}
C33 coefficients(ScalarBuilder& w, Quantity what, int index, const Mat3& R) {
  C33 out;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) out[static_cast<std::size_t>(3 * a + b)] = coefficient(w, value_id(what, index, a, b), R(a, b));
  return out;
}
C3 coefficients(ScalarBuilder& w, Quantity what, int index, const Vec3& r) {
  C3 out;
  for (int c = 0; c < 3; ++c) out[static_cast<std::size_t>(c)] = coefficient(w, value_id(what, index, c), r[c]);
  return out;
}
const Coefficient& at(const C33& R, int a, int b) { return R[static_cast<std::size_t>(3 * a + b)]; }
// (R^T v)_a and (R v)_a.
std::vector<Product> turned_back(const C33& R, const V3& v, int a) {
  return {times(at(R, 0, a), v[0]), times(at(R, 1, a), v[1]), times(at(R, 2, a), v[2])};
}
std::vector<Product> turned(const C33& R, const V3& v, int a) {
  return {times(at(R, a, 0), v[0]), times(at(R, a, 1), v[1]), times(at(R, a, 2), v[2])};
}

struct LocalMotion {
  // At each node's origin, in its axes. (The origin's velocity is not needed: a body's
  // acceleration and moment take omega, alpha and the origin's acceleration.)
  std::vector<V3> omega, alpha, acceleration;
  std::vector<C33> R;
  std::vector<C3> r;
};

// Out along the chains: omega_k = R^T omega_p + e s'_k, alpha_k = R^T alpha_p + e s''_k +
// (R^T omega_p) x e s'_k, a_k = R^T (a_p + alpha_p x r + omega_p x (omega_p x r)) for a revolute
// joint of axis e (a prismatic one adds e s''_k + 2 omega_k x e s'_k to a instead). K0's acceleration is g e_z upwards, which puts
// gravity into every body's force.
LocalMotion local_motion(const TwistTree& tree, const ValueId& g, ScalarBuilder& w) {
  const std::size_t n = tree.nodes.size();
  LocalMotion m{std::vector<V3>(n), std::vector<V3>(n), std::vector<V3>(n), std::vector<C33>(n), std::vector<C3>(n)};
  for (std::size_t k = 0; k < n; ++k) {
    const TwistNode& node = tree.nodes[k];
    const JointRecord& joint = *node.joint;
    const int kk = static_cast<int>(k);
    const auto id = [&](Quantity what, int c) { return value_id(what, kk, c); };
    m.R[k] = coefficients(w, Quantity::local_rotation, kk, node.placement_R);
    m.r[k] = coefficients(w, Quantity::local_offset, kk, node.placement_r);
    const C33& R = m.R[k];
    const C3& r = m.r[k];
    const auto p = static_cast<std::size_t>(node.parent);
    const V3 w0 = node.parent < 0 ? V3{} : m.omega[p], al0 = node.parent < 0 ? V3{} : m.alpha[p];
    const V3 a0 = node.parent < 0 ? V3{ValueId{}, ValueId{}, g} : m.acceleration[p];
    V3 wr, ca, w_in, al_in, a_in;
    for (int c = 0; c < 3; ++c) wr[static_cast<std::size_t>(c)] = w.define(id(Quantity::offset_velocity, c), cross_vc(w0, r, c));
    for (int c = 0; c < 3; ++c)
      ca[static_cast<std::size_t>(c)] = w.define(id(Quantity::carried_acceleration, c),
                                                 join(join({{a0[static_cast<std::size_t>(c)], kOne}}, cross_vc(al0, r, c)), cross_terms(w0, wr, c)));
    for (int a = 0; a < 3; ++a) {
      const auto aa = static_cast<std::size_t>(a);
      w_in[aa] = w.define(id(Quantity::incoming_motion, a), turned_back(R, w0, a));
      al_in[aa] = w.define(id(Quantity::incoming_motion, a + 3), turned_back(R, al0, a));
      a_in[aa] = w.define(id(Quantity::incoming_motion, a + 6), turned_back(R, ca, a));
    }
    const ValueId sd = value_id(Quantity::rate, joint.coordinate), sdd = value_id(Quantity::acceleration, joint.coordinate);
    const int i = static_cast<int>(joint.local_axis);
    const bool minus = joint.sign < 0;
    // (x cross e s')_c for the joint's axis e = sign e_i: x_{i+2} s' at c = i+1, -x_{i+1} s' at
    // c = i+2, zero along the axis.
    const auto cross_axis = [&](const V3& x, int c) -> std::vector<Product> {
      if (c == (i + 1) % 3) return {{x[static_cast<std::size_t>((i + 2) % 3)], sd, minus}};
      if (c == (i + 2) % 3) return {{x[static_cast<std::size_t>((i + 1) % 3)], sd, !minus}};
      return {};
    };
    for (int c = 0; c < 3; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      std::vector<Product> wt{{w_in[cc], kOne}}, alt{{al_in[cc], kOne}}, at_{{a_in[cc], kOne}};
      if (joint.revolute) {
        if (c == i) {
          wt.push_back({sd, kOne, minus});
          alt.push_back({sdd, kOne, minus});
        }
        alt = join(alt, cross_axis(w_in, c));
      } else {
        if (c == i) at_.push_back({sdd, kOne, minus});
        const std::vector<Product> coriolis = cross_axis(w_in, c);
        at_ = join(join(at_, coriolis), coriolis);  // 2 omega x e s'
      }
      m.omega[k][cc] = w.define(value_id(Quantity::spatial_velocity, kk, c), wt);
      m.alpha[k][cc] = w.define(value_id(Quantity::spatial_acceleration, kk, c), alt);
      m.acceleration[k][cc] = w.define(value_id(Quantity::spatial_acceleration, kk, c + 3), at_);
    }
  }
  return m;
}

// Body i at node k (its CoM frame at (Rc, c) in the node's frame): a_c = a + alpha x c +
// omega x (omega x c), F = m a_c; in body axes N = I alpha_b + omega_b x I omega_b; its wrench
// (F; Rc N + c x F) about the node's origin, in the node's axes.
V6 local_body_wrench(const Model& m, const TwistTree& tree, std::size_t i, const LocalMotion& motion, ScalarBuilder& w) {
  const Body& body = m.bodies[i];
  const auto k = static_cast<std::size_t>(tree.body_node[i]);
  const int index = static_cast<int>(i);
  const auto id = [&](Quantity what, int c) { return value_id(what, index, c); };
  w.add(lane_code::Comment{fmt::format("body {}: {}", body.name, body.meaning)});
  const C33 Rc = coefficients(w, Quantity::com_rotation, index, tree.body_R[i]);
  const C3 c = coefficients(w, Quantity::com_offset, index, tree.body_r[i]);
  const ValueId mass = w.scalar(value_id(Quantity::mass, index), m.parameter(body.mass).symbol);
  V3 I;
  for (int a = 0; a < 3; ++a)
    I[static_cast<std::size_t>(a)] = w.scalar(id(Quantity::inertia, a), m.parameter(body.inertia[static_cast<std::size_t>(a)]).symbol);
  const V3 &om = motion.omega[k], &al = motion.alpha[k], &acc = motion.acceleration[k];
  V3 wc, ac, F, wb, ab, Iw, N, M;
  for (int a = 0; a < 3; ++a) wc[static_cast<std::size_t>(a)] = w.define(id(Quantity::com_velocity, a), cross_vc(om, c, a));
  for (int a = 0; a < 3; ++a) {
    const auto aa = static_cast<std::size_t>(a);
    ac[aa] = w.define(id(Quantity::com_acceleration, a), join(join({{acc[aa], kOne}}, cross_vc(al, c, a)), cross_terms(om, wc, a)));
    F[aa] = w.define(id(Quantity::force, a), {{mass, ac[aa]}});
  }
  for (int a = 0; a < 3; ++a) {
    wb[static_cast<std::size_t>(a)] = w.define(id(Quantity::body_rate, a), turned_back(Rc, om, a));
    ab[static_cast<std::size_t>(a)] = w.define(id(Quantity::body_angular_acceleration, a), turned_back(Rc, al, a));
  }
  for (int a = 0; a < 3; ++a)
    Iw[static_cast<std::size_t>(a)] = w.define(id(Quantity::angular_momentum, a), {{I[static_cast<std::size_t>(a)], wb[static_cast<std::size_t>(a)]}});
  for (int a = 0; a < 3; ++a)
    N[static_cast<std::size_t>(a)] = w.define(id(Quantity::body_moment, a), join({{I[static_cast<std::size_t>(a)], ab[static_cast<std::size_t>(a)]}}, cross_terms(wb, Iw, a)));
  for (int a = 0; a < 3; ++a) M[static_cast<std::size_t>(a)] = w.define(id(Quantity::moment, a), join(turned(Rc, N, a), cross_cv(c, F, a)));
  return {F[0], F[1], F[2], M[0], M[1], M[2]};
}

// Back along the chains, in each node's axes: f_k = the bodies' forces + sum R_j f_j over the
// children j, n_k = the bodies' moments + sum (R_j n_j + r_j x R_j f_j); tau_k = e . n_k
// (revolute) or e . f_k (prismatic).
std::map<int, ValueId> local_joint_forces(const TwistTree& tree, const LocalMotion& motion, const std::vector<V6>& wrench, ScalarBuilder& w) {
  w.add(lane_code::Comment{"Back along the chains, in each joint's frame: the wrenches beyond each joint and the joints' generalized forces."});
  const std::size_t n = tree.nodes.size();
  std::vector<V3> f(n), moment(n), transmitted(n);
  std::map<int, std::vector<Product>> tau_terms;
  for (std::size_t k = n; k-- > 0;) {
    const TwistNode& node = tree.nodes[k];
    const int kk = static_cast<int>(k);
    for (int c = 0; c < 3; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      std::vector<Product> ft, nt;
      for (int i : node.bodies) {
        ft.push_back({wrench[static_cast<std::size_t>(i)][cc], kOne});
        nt.push_back({wrench[static_cast<std::size_t>(i)][cc + 3], kOne});
      }
      for (int child : node.children) {
        const auto ch = static_cast<std::size_t>(child);
        ft.push_back({transmitted[ch][cc], kOne});
        nt = join(join(nt, turned(motion.R[ch], moment[ch], c)), cross_cv(motion.r[ch], transmitted[ch], c));
      }
      f[k][cc] = w.define(value_id(Quantity::wrench, kk, c), ft);
      moment[k][cc] = w.define(value_id(Quantity::wrench, kk, c + 3), nt);
    }
    if (node.parent >= 0)
      for (int c = 0; c < 3; ++c) transmitted[k][static_cast<std::size_t>(c)] = w.define(value_id(Quantity::transmitted_force, kk, c), turned(motion.R[k], f[k], c));
    const JointRecord& joint = *node.joint;
    const auto i = static_cast<std::size_t>(joint.local_axis);
    const ValueId tau = w.define(value_id(Quantity::joint_force, kk), {{joint.revolute ? moment[k][i] : f[k][i], kOne, joint.sign < 0}});
    if (!tau.is_zero()) tau_terms[joint.coordinate].push_back({tau, kOne});
  }
  std::map<int, ValueId> tau_of;
  for (const auto& [j, terms] : tau_terms) {
    const ValueId t = w.define(value_id(Quantity::coordinate_force, j), terms);
    if (!t.is_zero()) tau_of[j] = t;
  }
  return tau_of;
}

// A printed pass' operations: its own, and its lane scalars' (the world frame's pass spends a
// third of its operations there).
long operations(const lane_code::PrintedCode& printed) { return printed.ops[0].total() + lane_code::scalar_operations(printed); }

// The outputs: Q*_l = sum_j T(j, l) tau_j: a commanded speed's coordinate adds its tau to its row;
// a dense coordinate's, times T(j, l), to the rows of the speeds its rate depends on
// (kRateBasisPattern); and tau itself.
void write_outputs(const Model& m, const RateRoles& roles, const std::map<int, ValueId>& tau_of, ScalarBuilder& w) {
  using lane_code::CloseOutput, lane_code::OpenOutput, lane_code::Store;
  const int nu = static_cast<int>(m.dynamics->commanded.size());
  const std::vector<std::vector<int>> speeds_of = rate_speeds(m, roles);
  // Q*'s entries are defined inside its block, at the level of the code before it.
  w.add(OpenOutput{"Qstar", "", OpenOutput::Prologue::none, false});
  for (int l = 0; l < nu; ++l) {
    std::vector<Product> t;
    for (const auto& [j, tau] : tau_of) {
      if (roles.speed_of[static_cast<std::size_t>(j)] == l) t.push_back({tau, kOne});
      else if (roles.dense[static_cast<std::size_t>(j)] &&
               std::binary_search(speeds_of[static_cast<std::size_t>(j)].begin(), speeds_of[static_cast<std::size_t>(j)].end(), l))
        t.push_back({value_id(Quantity::rate_basis_entry, j, l), tau});
    }
    const ValueId q = w.define(value_id(Quantity::commanded_force, l), t);
    w.add(Store{"Qstar", l, -1, false, q.is_zero() ? std::vector<Term>{} : std::vector<Term>{{kOne, q}}});
  }
  w.add(CloseOutput{});
  w.add(OpenOutput{"tau", "", OpenOutput::Prologue::zero});
  for (const auto& [j, t] : tau_of) w.add(Store{"tau", j, -1, false, {{kOne, t}}});
  w.add(CloseOutput{});
}

}  // namespace

FunctionSpec derive_generalized_forces(const Model& m) {
  FunctionSpec fn = generalized_forces_spec();
  const RateRoles roles = rate_roles(m);
  const TwistTree tree = twist_tree(m, roles);
  // The pass in K0, and the same in the joints' own frames: the one with fewer operations.
  ScalarBuilder world;
  {
    const SpatialMotion motion = spatial_motion(tree, world);
    const ValueId g = world.scalar(value_id(Quantity::gravity), m.parameter(m.dynamics->gravity).symbol);
    std::vector<V6> wrench(m.bodies.size());
    for (std::size_t i = 0; i < m.bodies.size(); ++i) {
      const int at_node = tree.body_node[i];
      if (at_node < 0) continue;
      wrench[i] = body_wrench(m, i, motion.velocity[static_cast<std::size_t>(at_node)], motion.acceleration[static_cast<std::size_t>(at_node)], g, world);
    }
    write_outputs(m, roles, joint_forces(tree, motion.axis, wrench, world), world);
  }
  ScalarBuilder local;
  {
    const ValueId g = local.scalar(value_id(Quantity::gravity), m.parameter(m.dynamics->gravity).symbol);
    const LocalMotion motion = local_motion(tree, g, local);
    std::vector<V6> wrench(m.bodies.size());
    for (std::size_t i = 0; i < m.bodies.size(); ++i)
      if (tree.body_node[i] >= 0) wrench[i] = local_body_wrench(m, tree, i, motion, local);
    write_outputs(m, roles, local_joint_forces(tree, motion, wrench, local), local);
  }
  // Unread values are left out (a link turning about one axis: of its I omega only the component
  // along that axis, which omega x I omega never reads), and so are the scalars only they read (a
  // body whose rotation or offset the recursion never reads, one link on a fixed joint: its
  // wrench needs only p and the mass).
  lane_code::PrintedCode printed = lane_code::print(world.program(), 1);
  lane_code::PrintedCode printed_local = lane_code::print(local.program(), 1);
  if (operations(printed_local) < operations(printed)) printed = std::move(printed_local);
  fn.lane_code = std::move(printed.code);
  fn.lane_scalars = std::move(printed.scalars);
  // The pass runs for either output: its operations are Q*'s (tau adds no operation of its own).
  OutputSpec Qo{"Qstar", "CommandVector", "M u' + b - Q_gravity for s'' = sddot: T^T tau, the forces the actuators must supply on u", "", {}};
  OutputSpec to{"tau", "Coordinates", "the bodies' generalized inertia, velocity and gravity forces on each coordinate (0 on the held inputs; computed with Qstar)", "", {}};
  Qo.from_lanes = to.from_lanes = true;
  Qo.lane_ops = printed.ops[0];
  fn.outputs = {Qo, to};
  return fn;
}

}  // namespace wlx::codegen
