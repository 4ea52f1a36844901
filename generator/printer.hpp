// Printing expression DAGs as C++ (internal to the emitters): the Printer turns graph nodes into
// expressions that use the CSE plan's temporaries by name and counts the operations it prints;
// batch_trig collects sin and cos of coordinates into one call of trig.hpp's sincos.
#pragma once

#include "emit.hpp"
#include "expr_graph.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <vector>

namespace wlx::codegen::detail {

inline bool integer_exponent(double e) { return e == static_cast<double>(static_cast<long>(e)); }

// The C++ function for a GiNaC function, called unqualified: the generated functions are templates
// on the scalar type and bring in `using std::sin;` ..., so a scalar type of the user's (an
// automatic-differentiation number) finds its own by argument-dependent lookup.
inline const char* call_name(const std::string& f) {
  static const char* const names[] = {"sin", "cos", "tan", "atan2", "atan", "asin", "acos", "abs", "exp", "log"};
  for (const char* c : names)
    if (f == c) return c;
  throw std::runtime_error("no C++ function for GiNaC function '" + f + "'");
}

// A number in a generated function body: of the function's scalar type, so float code stays float.
inline std::string scalar_literal(double v) { return "Scalar(" + literal(v) + ")"; }

// The coordinates and coordinate rates the body uses as local constants of the scalar type.
std::string coordinate_aliases(const Model& m, const std::set<std::string>& used);
// The parameters the body uses as local constants of the scalar type (baked ones as literals).
std::string parameter_aliases(const Model& m, const std::set<std::string>& used, const EmitOptions& opt);

// `using std::f;` for each function the body calls (sorted: deterministic output).
inline std::string using_declarations(const std::set<std::string>& calls) {
  std::string s;
  for (const auto& c : calls) s += fmt::format("  using std::{};\n", c);
  return s;
}

// Prints graph nodes as C++ expressions, replacing temporaries by their names, and counts the
// operations of exactly what it prints.
class Printer {
 public:
  enum class Context { Root, Term, Factor };

  // `precomputed`: nodes already held in named variables (sin/cos of the batched angles).
  // `prefix` names the temporaries (t0, t1, ...), distinct per function body.
  Printer(const ExprGraph& g, const CsePlan& plan, const std::map<int, std::string>& precomputed, std::string prefix = "t")
      : g_(g), plan_(plan), precomputed_(precomputed), prefix_(std::move(prefix)) {}

  std::string temp_name(int id) const { return fmt::format("{}{}", prefix_, plan_.temp_index.at(id)); }
  bool is_temp(int id) const { return plan_.temp_index.count(id) != 0; }

  // The definition of node `id` itself (temporaries among its arguments are used by name).
  std::string define(int id, OpCount& ops) { return node(id, Context::Root, ops, nullptr); }
  // Node `id` as an output's value: its variable if it has one, else its definition.
  std::string value(int id, OpCount& ops) { return use(id, Context::Root, ops, nullptr); }
  // The functions the printed code calls (sin, pow, ...): each needs `using std::name;`. (Square
  // roots are detail::square_root, types.hpp: errno-free for double and float.)
  const std::set<std::string>& calls() const { return calls_; }

 private:
  std::string use(int id, Context ctx, OpCount& ops, bool* negated) {
    if (auto it = precomputed_.find(id); it != precomputed_.end()) return it->second;
    if (is_temp(id)) return temp_name(id);
    return node(id, ctx, ops, negated);
  }

  std::string node(int id, Context ctx, OpCount& ops, bool* negated) {
    const Node& n = g_.node(id);
    switch (n.kind) {
      case NodeKind::Symbol: return n.text;
      case NodeKind::Number: {
        if (n.value < 0 && negated != nullptr) {
          *negated = true;
          return scalar_literal(-n.value);
        }
        return scalar_literal(n.value);
      }
      case NodeKind::Add: return sum(n, ctx, ops);
      case NodeKind::Mul: return product(n, ctx, ops, negated);
      case NodeKind::Pow: {
        std::string s = power(n, ops);
        return ctx == Context::Factor && s.find_first_of("*/") != std::string::npos ? "(" + s + ")" : s;
      }
      case NodeKind::Call: {
        std::string args;
        for (int a : n.args) args += (args.empty() ? "" : ", ") + use(a, Context::Root, ops, nullptr);
        ++ops.calls;
        calls_.insert(call_name(n.text));
        return fmt::format("{}({})", call_name(n.text), args);
      }
    }
    return {};
  }

  std::string sum(const Node& n, Context ctx, OpCount& ops) {
    std::vector<std::pair<bool, std::string>> terms;
    for (int a : n.args) {
      bool neg = false;
      std::string t = use(a, Context::Term, ops, &neg);
      terms.emplace_back(neg, std::move(t));
    }
    // Lead with a positive term where there is one, so no negation is needed.
    std::stable_partition(terms.begin(), terms.end(), [](const auto& t) { return !t.first; });
    std::string s = terms[0].first ? "-" + terms[0].second : terms[0].second;
    if (terms[0].first) ++ops.adds;
    for (std::size_t i = 1; i < terms.size(); ++i) {
      s += (terms[i].first ? " - " : " + ") + terms[i].second;
      ++ops.adds;
    }
    return ctx == Context::Factor ? "(" + s + ")" : s;
  }

  std::string product(const Node& n, Context ctx, OpCount& ops, bool* negated) {
    double coefficient = 1;
    std::vector<std::string> numer, denom;
    for (int a : n.args) {
      const Node& f = g_.node(a);
      if (f.kind == NodeKind::Number) {
        coefficient *= f.value;
      } else if (!is_temp(a) && f.kind == NodeKind::Pow && integer_exponent(f.value)) {
        const std::string base = use(f.args[0], Context::Factor, ops, nullptr);
        for (long k = 0; k < static_cast<long>(std::abs(f.value)); ++k) (f.value > 0 ? numer : denom).push_back(base);
      } else {
        numer.push_back(use(a, Context::Factor, ops, nullptr));
      }
    }
    const bool negative = coefficient < 0;
    if (std::abs(coefficient) != 1.0) numer.insert(numer.begin(), scalar_literal(std::abs(coefficient)));
    auto join = [](const std::vector<std::string>& v) {
      std::string s;
      for (const auto& x : v) s += (s.empty() ? "" : "*") + x;
      return s;
    };
    std::string s = numer.empty() ? "Scalar(1)" : join(numer);
    if (!numer.empty()) ops.muls += static_cast<long>(numer.size()) - 1;
    if (!denom.empty()) {
      s += denom.size() == 1 ? "/" + denom[0] : "/(" + join(denom) + ")";
      ops.muls += static_cast<long>(denom.size()) - 1;
      ++ops.divs;
    }
    if (negative) {
      if (negated != nullptr) {
        *negated = true;
      } else {
        s = "-" + s;
        ++ops.adds;
      }
    }
    return ctx == Context::Factor && (negative && negated == nullptr) ? "(" + s + ")" : s;
  }

  std::string power(const Node& n, OpCount& ops) {
    const std::string base = use(n.args[0], Context::Factor, ops, nullptr);
    if (integer_exponent(n.value)) {
      const long k = static_cast<long>(std::abs(n.value));
      std::string s = base;
      for (long i = 1; i < k; ++i) s += "*" + base;
      ops.muls += k - 1;
      if (n.value < 0) {
        ++ops.divs;
        return k == 1 ? "Scalar(1)/" + base : "Scalar(1)/(" + s + ")";
      }
      return s;
    }
    ++ops.calls;
    if (n.value == 0.5) {
      return fmt::format("detail::square_root({})", base);
    }
    if (n.value == -0.5) {
      ++ops.divs;
      return fmt::format("Scalar(1)/detail::square_root({})", base);
    }
    // x^(k + 1/2) = x^k sqrt(x) (a derived contact point's second derivatives have x^(-3/2)):
    // a multiply and a square root instead of pow, which number types need not have.
    if (integer_exponent(2 * n.value)) {
      const long k = static_cast<long>(std::abs(n.value));  // |v| = k + 1/2
      std::string s = fmt::format("detail::square_root({})", base);
      for (long i = 0; i < k; ++i) s = base + "*" + s;
      ops.muls += k;
      if (n.value > 0) return s;
      ++ops.divs;
      return "Scalar(1)/(" + s + ")";
    }
    calls_.insert("pow");
    return fmt::format("pow({}, {})", base, scalar_literal(n.value));
  }

  const ExprGraph& g_;
  const CsePlan& plan_;
  const std::map<int, std::string>& precomputed_;
  std::string prefix_;
  std::set<std::string> calls_;
};

// sin and cos of coordinates, batched into one trig.hpp pass: node id -> variable name, and
// the prologue computing them (angles in coordinate order, so the output is deterministic).
struct TrigBatch {
  std::map<int, std::string> names;
  std::string prologue;
  long calls = 0;
};

inline TrigBatch batch_trig(const Model& m, const ExprGraph& g, const std::vector<int>& roots) {
  std::map<std::string, std::map<std::string, int>> by_angle;  // angle -> {"sin"/"cos" -> node}
  std::set<std::string> coordinates;
  for (const auto& c : m.coordinates) coordinates.insert(c.name);
  std::unordered_set<int> seen;
  std::function<void(int)> visit = [&](int id) {
    if (!seen.insert(id).second) return;
    const Node& n = g.node(id);
    // Coordinates only: the sine of a fixed angle (a parameter) is computed once per call anyway.
    if (n.kind == NodeKind::Call && (n.text == "sin" || n.text == "cos") && n.args.size() == 1 &&
        g.node(n.args[0]).kind == NodeKind::Symbol && coordinates.count(g.node(n.args[0]).text))
      by_angle[g.node(n.args[0]).text][n.text] = id;
    for (int a : n.args) visit(a);
  };
  for (int r : roots) visit(r);
  TrigBatch b;
  std::vector<std::string> angles;
  for (const auto& c : m.coordinates)
    if (by_angle.count(c.name)) angles.push_back(c.name);
  if (angles.size() != by_angle.size()) throw std::runtime_error("sin/cos of a symbol that is not a coordinate");
  if (angles.empty()) return b;
  const std::size_t count = angles.size();
  std::string list, named;
  for (std::size_t k = 0; k < count; ++k) {
    list += (k ? ", " : "") + angles[k];
    for (const auto& [f, id] : by_angle[angles[k]]) {
      b.names[id] = fmt::format("{}_{}", f, angles[k]);
      named += fmt::format("  const Scalar {0}_{1} = {0}_angle[{2}];\n", f, angles[k], k);
      ++b.calls;
    }
  }
  b.prologue = fmt::format(
      "  // sin and cos of all {0} angles in one vectorized pass (trig.hpp).\n"
      "  const std::array<Scalar, {0}> angle{{{1}}};\n"
      "  std::array<Scalar, {0}> sin_angle, cos_angle;\n"
      "  sincos(angle, sin_angle, cos_angle);\n{2}",
      count, list, named);
  return b;
}

}  // namespace wlx::codegen::detail
