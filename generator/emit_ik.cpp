// ik.hpp: the closed-form inverse kinematics printed from the patterns' planned solves
// (ik_patterns.cpp): per limb a function ik_<limb>() with all its branches, every limb fused into
// ik_all(), the table kClosedForm and the two small solvers the solves call.
#include "emit.hpp"
#include "ik_internal.hpp"
#include "model_file.hpp"
#include "printer.hpp"

#include <fmt/format.h>

#include <cmath>
#include <regex>
#include <set>
#include <stdexcept>

namespace wlx::codegen {

namespace {

using namespace detail;
using namespace ik;

struct EmittedSolve {
  std::string text;
  OpCount ops;
};

// The joint angles from their cosines and sines in one batched atan2 pass (trig.hpp), after every
// solver stage: the stages themselves work with cosines and sines only (libm's atan2, one call per
// joint, was over half of a four-limb solve).
Stage angle_stage(const std::vector<Stage>& before, const std::vector<SolvedJoint>& joints) {
  for (const Stage& st : before)
    for (const auto& [sym, value] : st.locals)
      for (const SolvedJoint& j : joints)
        if (value.has(j.q))
          throw std::logic_error("wlx-gen: " + sym.get_name() + " uses the angle " + j.q.get_name() +
                                 " before the batched atan2 computes it");
  std::vector<std::string> sines, cosines;
  for (const SolvedJoint& j : joints) {
    sines.push_back(j.s.get_name());
    cosines.push_back(j.c.get_name());
  }
  Stage st;
  st.code = fmt::format("  const std::array<Scalar, {0}> ik_sines{{{{{1}}}}}, ik_cosines{{{{{2}}}}};\n"
                        "  std::array<Scalar, {0}> ik_angles;\n"
                        "  atan2(ik_sines, ik_cosines, ik_angles);\n",
                        joints.size(), fmt::join(sines, ", "), fmt::join(cosines, ", "));
  for (std::size_t i = 0; i < joints.size(); ++i) {
    st.code += fmt::format("  const Scalar {} = ik_angles[{}];\n", joints[i].q.get_name(), i);
    st.defines.push_back(joints[i].q.get_name());
  }
  return st;
}

// The joints a sum row fixes from joints the solve computes (a steering leg's last parallel joint),
// from the angles the batched atan2 computed: the sum row then holds exactly, where an atan2 of
// the joint's own sine and cosine would leave it off by a whole turn. Empty when every coupled
// joint is already a stage's local (a leveled lever's, fixed by inputs alone).
Stage coupled_stage(const Model& m, const std::vector<Stage>& before, const Solve& solve) {
  std::set<std::string> defined;
  for (const Stage& st : before) {
    for (const auto& [sym, value] : st.locals) defined.insert(sym.get_name());
    defined.insert(st.defines.begin(), st.defines.end());
  }
  GiNaC::lst angles;
  for (const SolvedJoint& j : solve.joints) angles.append(m.coordinates[static_cast<std::size_t>(j.coordinate)].q == j.q);
  Stage st;
  for (const auto& [k, value] : solve.coupled) {
    const realsymbol q = joint_symbols(m, k).q;
    if (!defined.count(q.get_name())) st.locals.emplace_back(q, value.subs(angles));
  }
  return st;
}

// The last stage of a limb's solve: its own closure rows at the solution, and the check.
Stage check_stage(const Model& m, const Limb& limb, const Solve& solve) {
  Stage check;
  std::vector<std::string> rows;
  for (std::size_t i = 0; i < limb.rows.size(); ++i) {
    const realsymbol r(fmt::format("ik_row{}", i));
    check.locals.emplace_back(r, in_results(m, closure_value(m, m.closure[static_cast<std::size_t>(limb.rows[i])]), solve));
    rows.push_back(fmt::format("std::abs({})", r.get_name()));
  }
  check.code = fmt::format(
      "  const Scalar ik_residual = std::max({{{}}});\n"
      "  if (!(ik_residual <= ik_tolerance<Scalar>())) {{\n"
      "    why = {{0, ik_residual, 0.0, ik_tolerance<Scalar>(), 0.0}};\n"
      "    return IkStatus::residual;\n"
      "  }}\n",
      fmt::join(rows, ", "));
  return check;
}

// The statements of a solve: input aliases, the batched sines and cosines, then every stage's
// temporaries, values and solver calls, then the outputs. One graph for all stages, so that
// temporaries are shared (across limbs, too, when several are fused) and placed in the first stage
// where everything they use exists.
std::string emit_body(const Model& m, const std::vector<Stage>& stages, const std::vector<std::pair<int, std::string>>& outputs,
                      const EmitOptions& opt, OpCount& ops) {
  ExprGraph g;
  std::map<std::string, int> symbol_stage;
  std::vector<std::vector<std::pair<std::string, int>>> locals(stages.size());
  std::vector<int> roots;
  for (std::size_t k = 0; k < stages.size(); ++k)
    for (const auto& [sym, value] : stages[k].locals) {
      const int id = g.add(value);
      locals[k].emplace_back(sym.get_name(), id);
      roots.push_back(id);
    }
  // What a stage defines (its locals, its solvers' results) is usable from the next stage on.
  for (std::size_t k = 0; k < stages.size(); ++k) {
    for (const auto& [sym, value] : stages[k].locals) symbol_stage[sym.get_name()] = static_cast<int>(k) + 1;
    for (const auto& n : stages[k].defines) symbol_stage[n] = static_cast<int>(k) + 1;
  }
  const CsePlan plan = eliminate_common_subexpressions(g, roots);
  const TrigBatch trig = batch_trig(m, g, roots);
  std::map<int, int> node_stage;
  std::function<int(int)> stage_of = [&](int id) -> int {
    if (auto it = node_stage.find(id); it != node_stage.end()) return it->second;
    const Node& n = g.node(id);
    int st = 0;
    if (n.kind == NodeKind::Symbol) {
      if (auto it = symbol_stage.find(n.text); it != symbol_stage.end()) st = it->second;
    }
    for (int a : n.args) st = std::max(st, stage_of(a));
    node_stage[id] = st;
    return st;
  };
  Printer pr(g, plan, trig.names, "ik_t");
  ops.calls += trig.calls;
  std::set<std::string> symbols;
  std::function<void(int)> collect = [&](int id) {
    const Node& n = g.node(id);
    if (n.kind == NodeKind::Symbol) symbols.insert(n.text);
    for (int a : n.args) collect(a);
  };
  for (int r : roots) collect(r);

  std::string body;
  body += coordinate_aliases(m, symbols) + parameter_aliases(m, symbols, opt);
  body += trig.prologue;
  const auto batched = [&](std::size_t k) { return trig.names.count(plan.temporaries[k]) != 0; };
  for (std::size_t k = 0; k < stages.size(); ++k) {
    for (std::size_t t = 0; t < plan.temporaries.size(); ++t)
      if (!batched(t) && stage_of(plan.temporaries[t]) == static_cast<int>(k))
        body += fmt::format("  const Scalar ik_t{} = {};\n", t, pr.define(plan.temporaries[t], ops));
    for (const auto& [n, id] : locals[k]) body += fmt::format("  const Scalar {} = {};\n", n, pr.value(id, ops));
    body += stages[k].code;
  }
  for (const auto& [k, name] : outputs) body += fmt::format("  out({}) = {};\n", k, name);
  return using_declarations(pr.calls()) + body + "  return IkStatus::ok;\n";
}

std::vector<std::pair<int, std::string>> solve_outputs(const Model& m, const Solve& solve) {
  std::vector<std::pair<int, std::string>> out;
  for (const SolvedJoint& j : solve.joints) out.emplace_back(j.coordinate, j.q.get_name());
  for (const auto& [k, value] : solve.coupled) out.emplace_back(k, joint_symbols(m, k).q.get_name());
  return out;
}

// One limb's stages (check included) with their local names made the limb's own (ik_<tag>_...),
// its branch read from `ik_<tag>_branch`, and a failure reporting `failed = index`: for fusing
// several limbs into one function. The solved joints keep their names (they are distinct already).
std::vector<Stage> fused_stages(const Model& m, const std::vector<Stage>& stages, const std::string& tag, int index) {
  std::set<std::string> keep = {"ik_solve_cos_sin", "ik_solve_two_axis", "ik_tolerance", "ik_reach_slack"};
  for (const auto& c : m.coordinates)
    for (const char* k : {"ik_q_", "ik_c_", "ik_s_"}) keep.insert(k + c.name);
  const auto renamed = [&](const std::string& name) { return keep.count(name) ? name : "ik_" + tag + "_" + name.substr(3); };
  const std::regex local(R"(\bik_[A-Za-z0-9_]+)"), branch(R"(\bbranch\b)");
  GiNaC::exmap symbols;
  const auto rename_symbols = [&](const ex& e) {
    for (GiNaC::const_preorder_iterator it = e.preorder_begin(); it != e.preorder_end(); ++it)
      if (GiNaC::is_a<GiNaC::symbol>(*it)) {
        const std::string n = GiNaC::ex_to<GiNaC::symbol>(*it).get_name();
        if (n.rfind("ik_", 0) == 0 && renamed(n) != n && !symbols.count(*it)) symbols[*it] = realsymbol(renamed(n));
      }
  };
  for (const Stage& st : stages)
    for (const auto& [sym, value] : st.locals) {
      rename_symbols(sym);
      rename_symbols(value);
    }
  std::vector<Stage> out;
  for (const Stage& st : stages) {
    Stage r;
    for (const auto& [sym, value] : st.locals)
      r.locals.emplace_back(GiNaC::ex_to<realsymbol>(symbols.count(sym) ? symbols[sym] : ex(sym)), value.subs(symbols));
    std::string code;
    std::sregex_iterator it(st.code.begin(), st.code.end(), local), end;
    std::size_t at = 0;
    for (; it != end; ++it) {
      code += st.code.substr(at, static_cast<std::size_t>(it->position()) - at) + renamed(it->str());
      at = static_cast<std::size_t>(it->position() + it->length());
    }
    code += st.code.substr(at);
    code = std::regex_replace(code, branch, "ik_" + tag + "_branch");
    r.code = std::regex_replace(code, std::regex(R"(return IkStatus::)"), fmt::format("failed = {};\n    return IkStatus::", index));
    for (const auto& n : st.defines) r.defines.push_back(renamed(n));
    out.push_back(std::move(r));
  }
  return out;
}

EmittedSolve emit_solve(const Model& m, const Limb& limb, Solve solve, const EmitOptions& opt) {
  std::vector<Stage> stages = solve.stages;
  stages.push_back(angle_stage(stages, solve.joints));
  if (Stage coupled = coupled_stage(m, solve.stages, solve); !coupled.locals.empty()) stages.push_back(std::move(coupled));
  stages.push_back(check_stage(m, limb, solve));
  OpCount ops;
  const std::string body = emit_body(m, stages, solve_outputs(m, solve), opt, ops);

  std::string t = fmt::format("// Closed-form inverse kinematics of limb {} ({}).\n//\n", limb.name, comment(limb.title));
  for (const auto& line : solve.doc) t += "// " + line + "\n";
  t += fmt::format("// Branches 0 to {}:\n", solve.branches - 1);
  for (const auto& b : solve.bits) t += "//   " + b + "\n";
  t += "// Writes the limb's joints (";
  std::vector<std::string> outs;
  for (int j : limb.joints) outs.push_back(m.coordinates[static_cast<std::size_t>(j)].name);
  t += fmt::format("{}) into out, which may be s itself; reads only the limb's inputs.\n", fmt::join(outs, ", "));
  t += "// On failure returns why, with the numbers in `why` (stage 1.. as in kClosedForm's failure texts;\n"
       "// stage 0: residual, the solution does not satisfy the closure rows).\n";
  t += fmt::format("// Operations: {} (adds {}, muls {}, divs {}, calls {}), plus the solver calls.\n", ops.total(), ops.adds,
                   ops.muls, ops.divs, ops.calls);
  t += "// Scalar: float or double (the branch choices and the reach diagnostics need real numbers).\n";
  t += fmt::format("template <typename Scalar>\n"
                   "inline IkStatus ik_{}(const CoordinatesOf<Scalar>& s, const Params& p, int branch, "
                   "detail::NonDeduced<CoordinatesOf<Scalar>>& out, IkDiagnostics& why) noexcept {{\n"
                   "  static_assert(std::is_floating_point_v<Scalar>, \"the closed-form IK is for float and double\");\n",
                   limb.name);
  t += fmt::format("  static_cast<void>(p);\n  if (branch < 0 || branch >= {}) return IkStatus::bad_branch;\n", solve.branches);
  t += body + "}\n\n";
  return {t, ops};
}

const char* kSupport = R"(// Why a closed-form solve gave no solution.
enum class IkStatus {
  ok = 0,
  out_of_reach,  // the target cannot be reached (why: stage, the target's value, the reachable range)
  bad_branch,    // no such branch
  residual,      // the solution does not satisfy the limb's closure rows (why.value: the residual)
};

struct IkDiagnostics {
  int stage = 0;      // which equation failed (the limb's failure texts, 1-based); 0: the residual check
  double value = 0;   // what the target asks for
  double low = 0;     // the reachable range
  double high = 0;
  double aux = 0;     // a joint angle that the range depends on, in degrees
};

// Targets this close outside the reach (relative) are rounding, not user error: they are clamped
// onto the boundary. For double; ik_reach_slack<Scalar>() scales it with the type's epsilon.
inline constexpr double kIkReachSlack = 1e-12;
// A closed-form solution must satisfy the limb's closure rows to this (m or rad); rounding leaves
// about 1e-15. For double; see ik_tolerance<Scalar>() for float.
inline constexpr double kIkTolerance = 1e-9;

// The two for scalar type Scalar. The slack is about 4500 rounding units, so it scales with the
// type's epsilon (float: 5.4e-4). The tolerance has to stay clear of rounding (n eps times the
// chain's length) and far below what a wrong solution leaves (millimetres and more); it scales
// with the square root of the epsilon ratio (float: 2.3e-5 m, where rounding leaves about 1e-6).
template <typename Scalar>
inline Scalar ik_reach_slack() noexcept {
  return Scalar(kIkReachSlack * (double(std::numeric_limits<Scalar>::epsilon()) / std::numeric_limits<double>::epsilon()));
}
template <typename Scalar>
inline Scalar ik_tolerance() noexcept {
  return Scalar(kIkTolerance * std::sqrt(double(std::numeric_limits<Scalar>::epsilon()) / std::numeric_limits<double>::epsilon()));
}

// cos x and sin x of the x with a cos x + b sin x = c: the root nearest zero (largest cos x; on a tie
// the positive one), or the other root with `other`. False when |c| exceeds sqrt(a^2 + b^2). The
// angles themselves come from one batched atan2 pass at the end of a solve.
template <typename Scalar>
inline bool ik_solve_cos_sin(Scalar a, Scalar b, Scalar c, bool other, Scalar& cos_x, Scalar& sin_x) noexcept {
  // sqrt, not std::hypot (several times slower): a and b are lengths or products of unit vectors
  // and lengths, nowhere near overflow.
  const Scalar r = detail::square_root(a * a + b * b);
  if (!(r > 0)) {
    // The joint does not move what it solves for: the reachable range is the one value c = 0
    // (reported as [v, v]), where every x solves; x = 0 is the root nearest zero.
    if (!(std::abs(c) <= ik_reach_slack<Scalar>())) return false;
    cos_x = 1;
    sin_x = 0;
    return true;
  }
  Scalar ratio = c / r;
  if (!(std::abs(ratio) <= 1)) {
    if (!(std::abs(ratio) <= 1 + ik_reach_slack<Scalar>())) return false;
    ratio = std::copysign(Scalar(1), ratio);
  }
  const Scalar cos_psi = a / r, sin_psi = b / r;  // x = psi +- delta
  const Scalar sin_delta = detail::square_root((1 - ratio) * (1 + ratio));
  Scalar sign = sin_psi > 0 ? Scalar(-1) : sin_psi < 0 ? Scalar(1) : (cos_psi >= 0 ? Scalar(1) : Scalar(-1));
  if (other) sign = -sign;
  cos_x = cos_psi * ratio - sign * sin_psi * sin_delta;
  sin_x = sin_psi * ratio + sign * cos_psi * sin_delta;
  return true;
}

// cos and sin of q1, q2 with R_A(q1) R_B(q2) v = d, for principal axes A != B (0 x, 1 y, 2 z) and |v| = |d|:
// the component of d along A fixes q2 (two roots: `flip` takes the one with cos q2 of the other sign
// than branch 0's), then q1 turns R_B(q2) v onto d. False (with how far d is off the plane normal to
// A, and how far it could be) when no q2 reaches d's component along A.
template <int A, int B, typename Scalar>
inline bool ik_solve_two_axis(const Scalar (&v)[3], const Scalar (&d)[3], bool flip, Scalar& c1, Scalar& s1, Scalar& c2,
                              Scalar& s2, Scalar& beside, Scalar& room) noexcept {
  static_assert(A != B && A >= 0 && A < 3 && B >= 0 && B < 3, "two different principal axes");
  constexpr int C = 3 - A - B;
  constexpr int i = (B + 1) % 3, j = (B + 2) % 3;    // R_B turns i towards j
  constexpr int i1 = (A + 1) % 3, j1 = (A + 2) % 3;  // R_A turns i1 towards j1
  const Scalar across = d[i1] * d[i1] + d[j1] * d[j1];  // |d|^2 off the axis A
  Scalar k2 = across - v[B] * v[B];
  if (k2 < 0) {
    if (-k2 > ik_reach_slack<Scalar>() * (across + v[B] * v[B])) {
      beside = std::abs(d[A]);
      room = detail::square_root(v[A] * v[A] + v[C] * v[C]);
      return false;
    }
    k2 = 0;
  }
  Scalar k = detail::square_root(k2);
  if ((v[C] < 0) != flip) k = -k;
  Scalar t[3] = {0, 0, 0};
  t[A] = d[A];
  t[C] = k;
  const Scalar y = v[i] * t[j] - v[j] * t[i], x = v[i] * t[i] + v[j] * t[j];
  const Scalar r = detail::square_root(x * x + y * y);
  c2 = r > 0 ? x / r : Scalar(1);
  s2 = r > 0 ? y / r : Scalar(0);
  Scalar w[3];
  w[B] = v[B];
  w[i] = c2 * v[i] - s2 * v[j];
  w[j] = s2 * v[i] + c2 * v[j];
  const Scalar y1 = w[i1] * d[j1] - w[j1] * d[i1], x1 = w[i1] * d[i1] + w[j1] * d[j1];
  const Scalar r1 = detail::square_root(x1 * x1 + y1 * y1);
  c1 = r1 > 0 ? x1 / r1 : Scalar(1);
  s1 = r1 > 0 ? y1 / r1 : Scalar(0);
  return true;
}

)";

// ik_all(): every limb's solver stages (`solved`: the limbs with a closed form), one atan2 pass
// for all their joints, then every limb's check.
std::string fused_ik(const Model& m, const std::vector<std::pair<const Limb*, Solve>>& solved, const EmitOptions& opt,
                     std::vector<std::string>& report) {
  std::vector<Stage> stages, coupled, checks;
  std::vector<SolvedJoint> joints;
  std::vector<std::pair<int, std::string>> outputs;
  std::string prologue, newton;
  for (std::size_t k = 0; k < solved.size(); ++k) {
    const auto& [limb, solve] = solved[k];
    const int index = static_cast<int>(limb - m.limbs.data());
    for (Stage& st : fused_stages(m, solve.stages, limb->name, index)) stages.push_back(std::move(st));
    if (Stage st = coupled_stage(m, solve.stages, solve); !st.locals.empty()) coupled.push_back(std::move(st));  // names kept
    for (Stage& st : fused_stages(m, {check_stage(m, *limb, solve)}, limb->name, index)) checks.push_back(std::move(st));
    joints.insert(joints.end(), solve.joints.begin(), solve.joints.end());
    for (const auto& o : solve_outputs(m, solve)) outputs.push_back(o);
    prologue += fmt::format("  const int ik_{0}_branch = branches[{1}];\n"
                            "  if (ik_{0}_branch < 0 || ik_{0}_branch >= {2}) {{\n    failed = {1};\n    return IkStatus::bad_branch;\n  }}\n",
                            limb->name, index, solve.branches);
  }
  for (const Limb& limb : m.limbs)
    if (std::none_of(solved.begin(), solved.end(), [&](const auto& sv) { return sv.first == &limb; }))
      newton += (newton.empty() ? "" : ", ") + limb.name;
  if (!joints.empty()) stages.push_back(angle_stage(stages, joints));
  stages.insert(stages.end(), coupled.begin(), coupled.end());
  stages.insert(stages.end(), checks.begin(), checks.end());
  OpCount ops;
  const std::string body = emit_body(m, stages, outputs, opt, ops);
  std::string t = fmt::format(
      "// The closed forms of the {0} limbs that have one{6} in one pass: what ik_<limb>() computes for each,\n"
      "// with the sines and cosines of every input angle and the subexpressions the limbs share computed once.\n"
      "// branches[k] is limb k's branch (kLimbs order). On failure returns the status of the first limb that\n"
      "// failed (every limb's reach is tested before any limb's residual check), `failed` its index and `why`\n"
      "// its numbers; out is written only when every limb succeeded.\n"
      "// Operations: {1} (adds {2}, muls {3}, divs {4}, calls {5}), plus the solver calls.\n"
      "// Scalar: float or double.\n"
      "template <typename Scalar>\n"
      "inline IkStatus ik_all(const CoordinatesOf<Scalar>& s, const Params& p, const std::array<int, {7}>& branches,\n"
      "                       detail::NonDeduced<CoordinatesOf<Scalar>>& out, int& failed, IkDiagnostics& why) noexcept {{\n"
      "  static_assert(std::is_floating_point_v<Scalar>, \"the closed-form IK is for float and double\");\n"
      "  static_cast<void>(s);\n  static_cast<void>(p);\n  static_cast<void>(branches);\n  static_cast<void>(out);\n"
      "  static_cast<void>(failed);\n  static_cast<void>(why);\n",
      solved.size(), ops.total(), ops.adds, ops.muls, ops.divs, ops.calls,
      newton.empty() ? "" : " (not " + newton + ": Newton's method at run time)", m.limbs.size());
  t += prologue + body + "}\n\n";
  t += double_overload(opt, "ik_all", "IkStatus",
                       {{"const Coordinates& s", ""},
                        {"const Params& p", ""},
                        {fmt::format("const std::array<int, {}>& branches", m.limbs.size()), ""},
                        {"Coordinates& out", ""},
                        {"int& failed", ""},
                        {"IkDiagnostics& why", ""}},
                       "what the runtime calls");
  report.push_back(fmt::format("all limbs fused: {} operations", ops.total()));
  return t;
}

}  // namespace

EmittedFile emit_ik_header(const Model& m, const EmitOptions& opt, std::vector<std::string>& report) {
  std::string t = banner(m, opt, "Closed-form inverse kinematics of the limbs, derived from the model's chains.");
  t += "//\n// Each limb whose chain matches a solvable pattern gets a function ik_<limb>() with all its\n"
       "// branches; kClosedForm lists them (solve == nullptr: no pattern applies, use Newton's method).\n";
  t += "#pragma once\n\n#include <algorithm>\n#include <array>\n#include <cmath>\n#include <limits>\n#include <string_view>\n#include <type_traits>\n\n"
       "#include \"params.hpp\"\n#include \"structure.hpp\"\n#include \"trig.hpp\"\n#include \"types.hpp\"\n\n" +
       namespace_open(opt) + "\n" + kSupport;
  std::vector<std::string> entries;
  std::vector<std::pair<const Limb*, Solve>> solved;
  for (const Limb& limb : m.limbs) {
    std::optional<Solve> solve;
    std::vector<std::string> reasons;
    for (auto plan : {plan_point3, plan_wheel_leg, plan_lever, plan_steering_leg}) {
      try {
        solve = plan(m, limb);
        break;
      } catch (const Unsolvable& u) {
        reasons.push_back(u.reason);
      }
    }
    // A default branch the closed form does not have is the model file's mistake, named there.
    const int branches = solve ? solve->branches : 1;
    if (limb.branch >= branches)
      throw ModelFileError(fmt::format("{}: limb '{}' has {} (0 to {}), not {}{}", limb.branch_place, limb.name,
                                       branches == 1 ? "one branch" : fmt::format("{} branches", branches), branches - 1, limb.branch,
                                       solve ? "" : ": wlx-gen found no closed form for it, and Newton's method has no branches"));
    if (!solve) {
      report.push_back(fmt::format("{}: no closed form ({}); Newton's method at run time", limb.name, fmt::join(reasons, "; ")));
      entries.push_back(fmt::format("    {{nullptr, 0, \"none\", {{}}, {{}}}},  // {}: {}", limb.name, comment(fmt::format("{}", fmt::join(reasons, "; ")))));
      continue;
    }
    const EmittedSolve e = emit_solve(m, limb, *solve, opt);
    t += e.text;
    solved.emplace_back(&limb, *solve);
    report.push_back(fmt::format("{}: {} ({} branches, {} operations)", limb.name, solve->summary, solve->branches, e.ops.total()));
    std::vector<std::string> bits, failures;
    for (const auto& b : solve->bits) bits.push_back("\"" + b + "\"");
    for (const auto& f : solve->failures) failures.push_back("\"" + f + "\"");
    entries.push_back(fmt::format("    {{&ik_{}<double>, {}, \"{}\", {{{{{}}}}}, {{{{{}}}}}}},", limb.name, solve->branches, solve->pattern,
                                  fmt::join(bits, ", "), fmt::join(failures, ", ")));
  }
  t += "using IkFunction = IkStatus (*)(const Coordinates& s, const Params& p, int branch, Coordinates& out,\n"
       "                                IkDiagnostics& why) noexcept;\n\n"
       "struct ClosedFormInfo {\n"
       "  IkFunction solve;  // nullptr: no closed form\n"
       "  int branches;\n"
       "  std::string_view pattern;\n"
       "  std::array<std::string_view, 3> bits;      // what each branch bit selects\n"
       "  std::array<std::string_view, 2> failures;  // message of each failing stage (IkDiagnostics::stage 1, 2),\n"
       "                                             // with {value}, {low}, {high}, {aux} to fill in\n"
       "};\n\n";
  t += fmt::format("// Per limb, in the order of kLimbs.\ninline constexpr std::array<ClosedFormInfo, {}> kClosedForm{{{{\n{}\n}}}};\n\n",
                   m.limbs.size(), fmt::join(entries, "\n"));

  // Every limb with a closed form in one function: one pass of sines and cosines for all input
  // angles, and the subexpressions the limbs share (the body's pose) computed once. Emitted for
  // every model, so that the runtime compiles for any mix: the limbs without a closed form are left
  // to Newton's method (their joints in out are not written).
  const bool all = solved.size() == m.limbs.size();
  t += fmt::format("// Whether every limb has a closed form (ik_all then solves them all).\ninline constexpr bool kHasFusedIk = {};\n\n",
                   all ? "true" : "false");
  t += fused_ik(m, solved, opt, report);
  t += namespace_close(opt);
  return {"wlx/gen/ik.hpp", t};
}

}  // namespace wlx::codegen
