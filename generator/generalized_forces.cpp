// generalized_forces: the bodies' inverse dynamics by the recursive Newton-Euler equations, written
// as straight-line scalar code, projected onto the commanded speeds.
#include "derivations_internal.hpp"

#include <fmt/format.h>
#include <wlx/support/text.hpp>

#include <algorithm>
#include <map>
#include <set>
#include <sstream>

namespace wlx::codegen {

using namespace derivation;

namespace {

// Straight-line scalar code, one `const Scalar name = ...;` per value, for the recursive
// Newton-Euler pass. A value is a name, or empty for an exact zero: products with a zero and zero
// terms are dropped, a sum of one plain term is that term (no line, no operation).
class ScalarWriter {
 public:
  struct Term {
    std::string a, b;  // a * b; b == kOne: a alone; an empty factor: zero
    bool negate = false;
  };
  static inline const std::string kOne = "1";
  std::string define(const std::string& name, const std::vector<Term>& terms) {
    std::vector<const Term*> live;
    for (const Term& t : terms)
      if (!t.a.empty() && !t.b.empty()) live.push_back(&t);
    if (live.empty()) return {};
    if (live.size() == 1 && !live[0]->negate && live[0]->b == kOne) return live[0]->a;
    std::string line = "    const Scalar " + name + " = ";
    for (std::size_t k = 0; k < live.size(); ++k) {
      const Term& t = *live[k];
      if (k > 0) line += t.negate ? " - " : " + ";
      else if (t.negate) line += "-";
      if (k > 0 || t.negate) ++ops.adds;
      line += t.b == kOne ? t.a : t.a + " * " + t.b;
      if (t.b != kOne) ++ops.muls;
    }
    code += line + ";\n";
    return name;
  }
  // The code without the values nothing reads (a link turning about one axis: of its I omega only
  // the component along that axis, which the cross product omega x I omega never reads), over and
  // over until each value left is read; their operations are taken off `ops`.
  std::string finish() {
    std::vector<std::string> lines;
    std::istringstream in(code);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    const std::string prefix = "    const Scalar ";
    for (bool dropped = true; dropped;) {
      dropped = false;
      std::map<std::string, int> uses;
      for (const auto& l : lines)
        for (const auto& w : identifiers(l)) ++uses[w];
      for (auto it = lines.begin(); it != lines.end();) {
        const std::size_t eq = it->find(" = ");
        if (it->rfind(prefix, 0) != 0 || eq == std::string::npos || uses[it->substr(prefix.size(), eq - prefix.size())] > 1) {
          ++it;
          continue;
        }
        const std::string value = it->substr(eq + 3);
        const auto count = [&](const std::string& what) {
          int n = 0;
          for (auto at = value.find(what); at != std::string::npos; at = value.find(what, at + 1)) ++n;
          return n;
        };
        ops.adds -= count(" + ") + count(" - ") + (value.rfind('-', 0) == 0 ? 1 : 0);
        ops.muls -= count(" * ");
        it = lines.erase(it);
        dropped = true;
      }
    }
    std::string out;
    for (const auto& l : lines) out += l + "\n";
    return out;
  }
  std::string code;
  OpCount ops;
};
using Term = ScalarWriter::Term;

// (x cross y)_c as two terms.
std::vector<Term> cross_terms(const std::array<std::string, 3>& x, const std::array<std::string, 3>& y, int c) {
  const auto c1 = static_cast<std::size_t>((c + 1) % 3), c2 = static_cast<std::size_t>((c + 2) % 3);
  return {{x[c1], y[c2]}, {x[c2], y[c1], true}};
}

using V3 = std::array<std::string, 3>;
using V6 = std::array<std::string, 6>;
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
SpatialMotion spatial_motion(FunctionSpec& fn, const TwistTree& tree, ScalarWriter& w) {
  const std::string one = ScalarWriter::kOne;
  SpatialMotion motion{std::vector<V6>(tree.nodes.size()), std::vector<V6>(tree.nodes.size()), std::vector<V6>(tree.nodes.size())};
  std::vector<V6>&axis = motion.axis, &velocity = motion.velocity, &acceleration = motion.acceleration;
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    const TwistNode& node = tree.nodes[k];
    const JointRecord& joint = *node.joint;
    const std::array<ex, 6> S = spatial_axis(joint);
    for (std::size_t c = 0; c < 6; ++c) axis[k][c] = lane_scalar(fn, fmt::format("kane_S_{}_{}", k, c), S[c]);
    const std::string sd = fmt::format("sdot({})", joint.coordinate), sdd = fmt::format("sddot({})", joint.coordinate);
    const V6 V0 = node.parent < 0 ? V6{} : velocity[static_cast<std::size_t>(node.parent)];
    const V6 A0 = node.parent < 0 ? V6{} : acceleration[static_cast<std::size_t>(node.parent)];
    // V_parent x S = (w x a; w x b + v x a).
    V6 X;
    for (int c = 0; c < 3; ++c) {
      X[static_cast<std::size_t>(c)] = w.define(fmt::format("kane_X{}_{}", k, c), cross_terms(head(V0), head(axis[k]), c));
      std::vector<Term> lin = cross_terms(head(V0), tail(axis[k]), c);
      for (const Term& t : cross_terms(tail(V0), head(axis[k]), c)) lin.push_back(t);
      X[static_cast<std::size_t>(c + 3)] = w.define(fmt::format("kane_X{}_{}", k, c + 3), lin);
    }
    for (std::size_t c = 0; c < 6; ++c) {
      velocity[k][c] = w.define(fmt::format("kane_V{}_{}", k, c), {{V0[c], one}, {axis[k][c], sd}});
      acceleration[k][c] = w.define(fmt::format("kane_A{}_{}", k, c), {{A0[c], one}, {axis[k][c], sdd}, {X[c], sd}});
    }
  }
  return motion;
}

// Body i (V, A: the spatial velocity and acceleration at its node; g: the lane scalar g): its CoM's
// velocity v = V_lin + omega x p and acceleration a = A_lin + alpha x p + omega x v; force
// F = m (a + g e_z); moment in body axes N = I alpha_b + omega_b x I omega_b; returns its wrench
// about K0's origin (F; R N + p x F).
V6 body_wrench(const Model& m, std::size_t i, const V6& V, const V6& A, const std::string& g, FunctionSpec& fn, ScalarWriter& w) {
  const auto scalar = [&](const std::string& name, const ex& value) { return lane_scalar(fn, name, value); };
  const std::string one = ScalarWriter::kOne;
  const Body& body = m.bodies[i];
  const Frame& f = body.com_frame;
  const auto name = [&](const char* what, int c) { return fmt::format("kane_{}{}_{}", what, i, c); };
  w.code += "    // " + text::cpp_comment(fmt::format("body {}: {}", body.name, body.meaning)) + "\n";
  V3 p, v, a, F, wb, ab, Iw, N, M;
  std::array<std::string, 9> R;
  for (int c = 0; c < 3; ++c) p[static_cast<std::size_t>(c)] = scalar(fmt::format("kane_p_{}_{}", i, c), f.r[c]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R[static_cast<std::size_t>(3 * r + c)] = scalar(fmt::format("kane_R_{}_{}_{}", i, r, c), f.R(r, c));
  const auto Rrc = [&](int r, int c) -> const std::string& { return R[static_cast<std::size_t>(3 * r + c)]; };
  const std::string mass = scalar(fmt::format("kane_mass_{}", i), m.parameter(body.mass).symbol);
  V3 I;
  for (int c = 0; c < 3; ++c)
    I[static_cast<std::size_t>(c)] = scalar(fmt::format("kane_inertia_{}_{}", i, c), m.parameter(body.inertia[static_cast<std::size_t>(c)]).symbol);
  for (int c = 0; c < 3; ++c) {
    std::vector<Term> t = cross_terms(head(V), p, c);
    t.insert(t.begin(), {V[static_cast<std::size_t>(c + 3)], one});
    v[static_cast<std::size_t>(c)] = w.define(name("v", c), t);
  }
  for (int c = 0; c < 3; ++c) {
    std::vector<Term> t = cross_terms(head(A), p, c);
    for (const Term& x : cross_terms(head(V), v, c)) t.push_back(x);
    t.insert(t.begin(), {A[static_cast<std::size_t>(c + 3)], one});
    if (c == 2) t.push_back({g, one});
    a[static_cast<std::size_t>(c)] = w.define(name("a", c), t);
    F[static_cast<std::size_t>(c)] = w.define(name("F", c), {{mass, a[static_cast<std::size_t>(c)]}});
  }
  for (int c = 0; c < 3; ++c) {
    wb[static_cast<std::size_t>(c)] = w.define(name("wb", c), {{Rrc(0, c), V[0]}, {Rrc(1, c), V[1]}, {Rrc(2, c), V[2]}});
    ab[static_cast<std::size_t>(c)] = w.define(name("ab", c), {{Rrc(0, c), A[0]}, {Rrc(1, c), A[1]}, {Rrc(2, c), A[2]}});
  }
  for (int c = 0; c < 3; ++c) Iw[static_cast<std::size_t>(c)] = w.define(name("Iw", c), {{I[static_cast<std::size_t>(c)], wb[static_cast<std::size_t>(c)]}});
  for (int c = 0; c < 3; ++c) {
    std::vector<Term> t = cross_terms(wb, Iw, c);
    t.insert(t.begin(), {I[static_cast<std::size_t>(c)], ab[static_cast<std::size_t>(c)]});
    N[static_cast<std::size_t>(c)] = w.define(name("N", c), t);
  }
  for (int c = 0; c < 3; ++c) {
    std::vector<Term> t = cross_terms(p, F, c);
    for (int k = 0; k < 3; ++k) t.push_back({Rrc(c, k), N[static_cast<std::size_t>(k)]});
    M[static_cast<std::size_t>(c)] = w.define(name("M", c), t);
  }
  return {F[0], F[1], F[2], M[0], M[1], M[2]};
}

// Back along the chains: the wrenches beyond each joint, tau_j = S . (moment; force). Returns each
// moving coordinate's generalized force (the sum of its joints' taus) that is not exactly zero.
std::map<int, std::string> joint_forces(const TwistTree& tree, const std::vector<V6>& axis, const std::vector<V6>& wrench, ScalarWriter& w) {
  const std::string one = ScalarWriter::kOne;
  w.code += "    // Back along the chains: the wrenches beyond each joint and the joints' generalized forces.\n";
  std::vector<V6> beyond(tree.nodes.size());
  // A component of a joint's wrench sum is read by its tau where the axis has the matching component
  // (force with the linear part, moment with the angular), and by the joints before it that read it.
  std::vector<std::array<bool, 6>> read(tree.nodes.size());
  for (std::size_t k = 0; k < tree.nodes.size(); ++k)
    for (std::size_t c = 0; c < 6; ++c)
      read[k][c] = !axis[k][c < 3 ? c + 3 : c - 3].empty() ||
                   (tree.nodes[k].parent >= 0 && read[static_cast<std::size_t>(tree.nodes[k].parent)][c]);
  std::map<int, std::vector<Term>> tau_terms;  // coordinate -> its joints' taus
  for (std::size_t k = tree.nodes.size(); k-- > 0;) {
    const TwistNode& node = tree.nodes[k];
    for (std::size_t c = 0; c < 6; ++c) {
      if (!read[k][c]) continue;
      std::vector<Term> parts;
      for (int i : node.bodies) parts.push_back({wrench[static_cast<std::size_t>(i)][c], one});
      for (int child : node.children) parts.push_back({beyond[static_cast<std::size_t>(child)][c], one});
      beyond[k][c] = w.define(fmt::format("kane_W{}_{}", k, c), parts);
    }
    std::vector<Term> t;
    for (std::size_t c = 0; c < 3; ++c) t.push_back({axis[k][c], beyond[k][c + 3]});
    for (std::size_t c = 0; c < 3; ++c) t.push_back({axis[k][c + 3], beyond[k][c]});
    const std::string tau = w.define(fmt::format("kane_tau{}", k), t);
    if (!tau.empty()) tau_terms[node.joint->coordinate].push_back({tau, one});
  }
  std::map<int, std::string> tau_of;
  for (const auto& [j, terms] : tau_terms) {
    const std::string t = w.define(fmt::format("kane_tau_s{}", j), terms);
    if (!t.empty()) tau_of[j] = t;
  }
  return tau_of;
}

// The outputs: Q*_l = sum_j T(j, l) tau_j: a commanded speed's coordinate adds its tau to its row;
// a dense coordinate's, times T(j, l), to the rows of the speeds its rate depends on
// (kRateBasisPattern); and tau itself.
void write_outputs(const Model& m, const RateRoles& roles, const std::map<int, std::string>& tau_of, ScalarWriter& w) {
  const std::string one = ScalarWriter::kOne;
  const int nu = static_cast<int>(m.dynamics->commanded.size());
  const std::vector<std::vector<int>> speeds_of = rate_speeds(m, roles);
  w.code += "    if (Qstar != nullptr) {\n";
  for (int l = 0; l < nu; ++l) {
    std::vector<Term> t;
    for (const auto& [j, tau] : tau_of) {
      if (roles.speed_of[static_cast<std::size_t>(j)] == l) t.push_back({tau, one});
      else if (roles.dense[static_cast<std::size_t>(j)] &&
               std::binary_search(speeds_of[static_cast<std::size_t>(j)].begin(), speeds_of[static_cast<std::size_t>(j)].end(), l))
        t.push_back({fmt::format("T({}, {})", j, l), tau});
    }
    const std::string q = w.define(fmt::format("kane_Q{}", l), t);
    w.code += fmt::format("    (*Qstar)({}) = {};\n", l, q.empty() ? "Scalar(0)" : q);
  }
  w.code += "    }\n    if (tau != nullptr) {\n      tau->setZero();\n";
  for (const auto& [j, t] : tau_of) w.code += fmt::format("      (*tau)({}) = {};\n", j, t);
  w.code += "    }\n";
}

}  // namespace

FunctionSpec derive_generalized_forces(const Model& m) {
  FunctionSpec fn = generalized_forces_spec();
  const RateRoles roles = rate_roles(m);
  const TwistTree tree = twist_tree(m, roles);
  ScalarWriter w;
  const SpatialMotion motion = spatial_motion(fn, tree, w);
  const std::string g = lane_scalar(fn, "kane_g", m.parameter(m.dynamics->gravity).symbol);
  std::vector<V6> wrench(m.bodies.size());
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const int at_node = tree.body_node[i];
    if (at_node < 0) continue;
    wrench[i] = body_wrench(m, i, motion.velocity[static_cast<std::size_t>(at_node)], motion.acceleration[static_cast<std::size_t>(at_node)], g,
                            fn, w);
  }
  write_outputs(m, roles, joint_forces(tree, motion.axis, wrench, w), w);
  fn.lane_code = w.finish();
  // A body whose rotation or offset the recursion never reads (one link on a fixed joint: its
  // wrench needs only p and the mass) leaves those scalars unread: they are not computed.
  const auto words = identifiers(fn.lane_code);
  const std::set<std::string> lane_words(words.begin(), words.end());
  std::erase_if(fn.lane_scalars, [&](const auto& named) { return !lane_words.count(named.first); });
  // The pass runs for either output: its operations are Q*'s (tau adds no operation of its own).
  OutputSpec Qo{"Qstar", "CommandVector", "M u' + b - Q_gravity for s'' = sddot: T^T tau, the forces the actuators must supply on u", "", {}};
  OutputSpec to{"tau", "Coordinates", "the bodies' generalized inertia, velocity and gravity forces on each coordinate (0 on the held inputs; computed with Qstar)", "", {}};
  Qo.from_lanes = to.from_lanes = true;
  Qo.lane_ops = w.ops;
  fn.outputs = {Qo, to};
  return fn;
}

}  // namespace wlx::codegen
