#include "expr_graph.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>

#include <fmt/format.h>
#include <functional>
#include <limits>
#include <stdexcept>
#include <unordered_set>

namespace wlx::codegen {

namespace {

std::uint64_t fnv(std::uint64_t h, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) {
    h ^= (v >> (8 * i)) & 0xffu;
    h *= 0x100000001b3ull;
  }
  return h;
}

std::uint64_t fnv(std::uint64_t h, const std::string& s) {
  for (unsigned char ch : s) {
    h ^= ch;
    h *= 0x100000001b3ull;
  }
  return fnv(h, s.size());
}

bool is_integer_exponent(double e) { return e == static_cast<double>(static_cast<long>(e)); }

}  // namespace

int ExprGraph::add(const GiNaC::ex& e) {
  if (auto it = memo_.find(e); it != memo_.end()) return it->second;
  int id = -1;
  std::vector<int> args;
  for (std::size_t i = 0; i < e.nops(); ++i) args.push_back(add(e.op(i)));
  if (GiNaC::is_a<GiNaC::numeric>(e)) {
    const auto& num = GiNaC::ex_to<GiNaC::numeric>(e);
    if (!num.is_real()) throw std::runtime_error("complex number in a model expression");
    id = number(num.to_double());
  } else if (GiNaC::is_a<GiNaC::symbol>(e)) {
    id = make(NodeKind::Symbol, GiNaC::ex_to<GiNaC::symbol>(e).get_name(), 0, {});
  } else if (GiNaC::is_a<GiNaC::add>(e)) {
    id = sum(args);
  } else if (GiNaC::is_a<GiNaC::mul>(e)) {
    id = product(std::move(args));
  } else if (GiNaC::is_a<GiNaC::power>(e)) {
    if (!GiNaC::is_a<GiNaC::numeric>(e.op(1))) throw std::runtime_error("symbolic exponent in a model expression");
    id = power(args[0], GiNaC::ex_to<GiNaC::numeric>(e.op(1)).to_double());
  } else if (GiNaC::is_a<GiNaC::function>(e)) {
    id = make(NodeKind::Call, GiNaC::ex_to<GiNaC::function>(e).get_name(), 0, std::move(args));
  } else {
    std::ostringstream text;
    text << e;
    throw std::runtime_error("unsupported expression kind in the model: " + text.str());
  }
  memo_.emplace(e, id);
  return id;
}

int ExprGraph::number(double v) {
  if (v == 0) v = 0;  // no negative zero
  return make(NodeKind::Number, fmt::format("{}", v), v, {});
}

std::pair<double, int> ExprGraph::split_coefficient(int id) {
  const Node& n = node(id);
  if (n.kind == NodeKind::Number) return {n.value < 0 ? -1.0 : 1.0, number(std::abs(n.value))};
  if (n.kind != NodeKind::Mul) return {1.0, id};
  double c = 1;
  std::vector<int> rest;
  for (int a : n.args) {
    if (node(a).kind == NodeKind::Number) c *= node(a).value;
    else rest.push_back(a);
  }
  if (c >= 0) return {1.0, id};
  if (c != -1.0) rest.push_back(number(-c));
  return {-1.0, rest.size() == 1 ? rest[0] : make(NodeKind::Mul, "", 0, std::move(rest))};
}

int ExprGraph::product(std::vector<int> factors) {
  double c = 1;
  std::vector<int> rest;
  std::vector<int> work = std::move(factors);
  for (std::size_t i = 0; i < work.size(); ++i) {
    const Node& f = node(work[i]);
    if (f.kind == NodeKind::Number) c *= f.value;
    else if (f.kind == NodeKind::Mul) work.insert(work.end(), f.args.begin(), f.args.end());
    else rest.push_back(work[i]);
  }
  if (c == 0 || rest.empty()) return number(c);
  if (c == 1 && rest.size() == 1) return rest[0];
  if (c != 1) rest.push_back(number(c));
  return make(NodeKind::Mul, "", 0, std::move(rest));
}

int ExprGraph::sum(const std::vector<int>& terms) {
  std::vector<std::pair<int, double>> parts;  // (magnitude, sign)
  for (int t : terms) {
    const auto [sign, magnitude] = split_coefficient(t);
    parts.emplace_back(magnitude, sign);
  }
  std::sort(parts.begin(), parts.end(), [this](const auto& p, const auto& q) { return less(p.first, q.first); });
  const double overall = parts.front().second;
  std::vector<int> signed_terms;
  for (const auto& [magnitude, sign] : parts)
    signed_terms.push_back(sign * overall > 0 ? magnitude : product({number(-1), magnitude}));
  const int s = make(NodeKind::Add, "", 0, std::move(signed_terms));
  return overall > 0 ? s : product({number(-1), s});
}

int ExprGraph::power(int base, double exponent) {
  const auto [sign, magnitude] = split_coefficient(base);
  if (sign < 0 && is_integer_exponent(exponent)) {
    const int p = make(NodeKind::Pow, fmt::format("{}", exponent), exponent, {magnitude});
    return static_cast<long>(exponent) % 2 == 0 ? p : product({number(-1), p});
  }
  return make(NodeKind::Pow, fmt::format("{}", exponent), exponent, {base});
}

bool ExprGraph::less(int a, int b) const {
  if (a == b) return false;
  const Node& x = node(a);
  const Node& y = node(b);
  if (x.hash != y.hash) return x.hash < y.hash;
  if (x.kind != y.kind) return x.kind < y.kind;
  if (x.text != y.text) return x.text < y.text;
  if (x.value != y.value) return x.value < y.value;
  return std::lexicographical_compare(x.args.begin(), x.args.end(), y.args.begin(), y.args.end(),
                                      [this](int p, int q) { return less(p, q); });
}

int ExprGraph::make(NodeKind kind, std::string text, double value, std::vector<int> args) {
  if (kind == NodeKind::Add || kind == NodeKind::Mul)
    std::sort(args.begin(), args.end(), [this](int p, int q) { return less(p, q); });
  Node n{kind, std::move(text), value, std::move(args), 0};
  std::uint64_t h = 0xcbf29ce484222325ull;
  h = fnv(h, static_cast<std::uint64_t>(kind));
  h = fnv(h, n.text);
  h = fnv(h, std::bit_cast<std::uint64_t>(n.value));
  for (int a : n.args) h = fnv(h, node(a).hash);
  n.hash = h;
  return intern(std::move(n));
}

int ExprGraph::intern(Node n) {
  auto& bucket = by_hash_[n.hash];
  for (int id : bucket) {
    const Node& o = node(id);
    if (o.kind == n.kind && o.text == n.text && o.value == n.value && o.args == n.args) return id;
  }
  nodes_.push_back(std::move(n));
  const int id = static_cast<int>(nodes_.size()) - 1;
  bucket.push_back(id);
  return id;
}

OpCount ExprGraph::own_ops(int id) const {
  const Node& n = node(id);
  OpCount c;
  switch (n.kind) {
    case NodeKind::Symbol:
    case NodeKind::Number: break;
    case NodeKind::Add: c.adds = static_cast<long>(n.args.size()) - 1; break;
    case NodeKind::Mul: {
      long numer = 0, denom = 0;
      for (int a : n.args) {
        const Node& f = node(a);
        if (f.kind == NodeKind::Number) {
          if (f.value != 1.0 && f.value != -1.0) ++numer;
        } else if (f.kind == NodeKind::Pow && is_integer_exponent(f.value)) {
          (f.value > 0 ? numer : denom) += static_cast<long>(std::abs(f.value));
        } else {
          ++numer;
        }
      }
      c.muls = std::max(numer - 1, 0L) + std::max(denom - 1, 0L);
      c.divs = denom > 0 ? 1 : 0;
      break;
    }
    case NodeKind::Pow:
      if (is_integer_exponent(n.value)) {
        c.muls = static_cast<long>(std::abs(n.value)) - 1;
        c.divs = n.value < 0 ? 1 : 0;
      } else {
        c.calls = 1;
      }
      break;
    case NodeKind::Call: c.calls = 1; break;
  }
  return c;
}

OpCount ExprGraph::tree_ops(int id) const {
  if (auto it = tree_memo_.find(id); it != tree_memo_.end()) return it->second;
  const Node& n = node(id);
  OpCount c = own_ops(id);
  for (int a : n.args) {
    // Inside a product, an integer power's own operations are already part of the product's.
    if (n.kind == NodeKind::Mul && node(a).kind == NodeKind::Pow && is_integer_exponent(node(a).value)) {
      const OpCount base = tree_ops(node(a).args[0]);
      for (long k = 0; k < static_cast<long>(std::abs(node(a).value)); ++k) c += base;
    } else if (n.kind == NodeKind::Pow && is_integer_exponent(n.value)) {
      const OpCount base = tree_ops(a);
      for (long k = 0; k < static_cast<long>(std::abs(n.value)); ++k) c += base;
    } else {
      c += tree_ops(a);
    }
  }
  tree_memo_.emplace(id, c);
  return c;
}

CsePlan eliminate_common_subexpressions(const ExprGraph& g, const std::vector<int>& roots) {
  std::unordered_map<int, int> uses;
  std::function<void(int, int)> count = [&](int id, int weight) {
    if (g.is_leaf(id)) return;
    const bool first = uses[id] == 0;
    uses[id] += weight;
    if (!first) return;
    const Node& n = g.node(id);
    for (int a : n.args) {
      const Node& child = g.node(a);
      // x^n (integer n) is emitted as x*x*...: x must then be computed once, in a temporary.
      if (child.kind == NodeKind::Pow && is_integer_exponent(child.value) && child.value != -1.0) {
        count(child.args[0], 2);
        continue;
      }
      count(a, 1);
    }
    if (n.kind == NodeKind::Pow && is_integer_exponent(n.value) && std::abs(n.value) >= 2.0) uses[n.args[0]] += 1;
  };
  for (int r : roots) count(r, 1);

  CsePlan plan;
  std::unordered_set<int> seen;
  std::function<void(int)> order = [&](int id) {
    if (g.is_leaf(id) || !seen.insert(id).second) return;
    for (int a : g.node(id).args) order(a);
    if (uses[id] >= 2) {
      plan.temp_index.emplace(id, static_cast<int>(plan.temporaries.size()));
      plan.temporaries.push_back(id);
    }
  };
  for (int r : roots) order(r);
  return plan;
}

std::string DoubleValues::shown(int id) const {
  const double v = value[static_cast<std::size_t>(id)];
  return std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf";
}

DoubleValues evaluate_in_double(const ExprGraph& g, const std::map<std::string, double>& symbols) {
  static const std::map<std::string, double (*)(double)> functions = {
      {"sin", [](double x) { return std::sin(x); }},   {"cos", [](double x) { return std::cos(x); }},
      {"tan", [](double x) { return std::tan(x); }},   {"asin", [](double x) { return std::asin(x); }},
      {"acos", [](double x) { return std::acos(x); }}, {"atan", [](double x) { return std::atan(x); }},
      {"exp", [](double x) { return std::exp(x); }},   {"log", [](double x) { return std::log(x); }},
      {"abs", [](double x) { return std::abs(x); }}};
  DoubleValues out;
  out.value.assign(g.size(), std::numeric_limits<double>::quiet_NaN());
  out.known.assign(g.size(), 0);
  // A node's arguments are made before it: one pass in id order.
  for (std::size_t id = 0; id < g.size(); ++id) {
    const Node& n = g.node(static_cast<int>(id));
    bool known = true, finite = true;
    std::vector<double> a;
    for (const int arg : n.args) {
      known = known && out.known[static_cast<std::size_t>(arg)];
      finite = finite && std::isfinite(out.value[static_cast<std::size_t>(arg)]);
      a.push_back(out.value[static_cast<std::size_t>(arg)]);
    }
    double v = std::numeric_limits<double>::quiet_NaN();
    std::string why = "overflow";
    switch (n.kind) {
      case NodeKind::Number: v = n.value; break;
      case NodeKind::Symbol: {
        const auto it = symbols.find(n.text);
        known = it != symbols.end();
        if (known) v = it->second;
        break;
      }
      case NodeKind::Add:
        v = 0;
        for (const double x : a) v += x;
        break;
      case NodeKind::Mul:
        v = 1;
        for (const double x : a) v *= x;
        break;
      case NodeKind::Pow:
        v = n.value == 0.5 ? std::sqrt(a[0]) : std::pow(a[0], n.value);
        if (a[0] == 0 && n.value < 0) why = "division by zero";
        else if (a[0] < 0 && !is_integer_exponent(n.value)) why = "root of a negative number";
        break;
      case NodeKind::Call:
        if (n.text == "atan2" && a.size() == 2) {
          v = std::atan2(a[0], a[1]);
        } else if (const auto f = functions.find(n.text); f != functions.end() && a.size() == 1) {
          v = f->second(a[0]);
          why = std::isnan(v) ? n.text + " outside its domain" : n.text == "log" || n.text == "tan" ? n.text + " at its pole" : "overflow";
        }
        break;
    }
    out.known[id] = known;
    out.value[id] = v;
    if (known && finite && !std::isfinite(v) && out.first_bad < 0) {
      out.first_bad = static_cast<int>(id);
      out.why = why;
    }
  }
  return out;
}

std::string node_text(const ExprGraph& g, int id, std::size_t limit) {
  std::string out;
  // bare: inside a call's own parentheses, where a sum needs none of its own.
  std::function<void(int, bool)> print = [&](int k, bool bare) {
    if (out.size() > limit) return;
    const Node& n = g.node(k);
    switch (n.kind) {
      case NodeKind::Number:
      case NodeKind::Symbol: out += n.text; break;
      case NodeKind::Add:
        out += bare ? "" : "(";
        for (std::size_t i = 0; i < n.args.size(); ++i) {
          if (i) out += " + ";
          print(n.args[i], false);
        }
        out += bare ? "" : ")";
        break;
      case NodeKind::Mul:
        for (std::size_t i = 0; i < n.args.size(); ++i) {
          if (i) out += "*";
          print(n.args[i], false);
        }
        break;
      case NodeKind::Pow: {
        const bool leaf = g.is_leaf(n.args[0]) || g.node(n.args[0]).kind == NodeKind::Add;
        out += n.value == -1 ? (leaf ? "1/" : "1/(") : n.value == 0.5 ? "sqrt(" : leaf ? "" : "(";
        print(n.args[0], n.value == 0.5);
        out += n.value == -1 ? (leaf ? "" : ")") : n.value == 0.5 ? ")" : (leaf ? "^" : ")^") + n.text;
        break;
      }
      case NodeKind::Call:
        out += n.text + "(";
        for (std::size_t i = 0; i < n.args.size(); ++i) {
          if (i) out += ", ";
          print(n.args[i], true);
        }
        out += ")";
        break;
    }
  };
  print(id, false);
  return out.size() > limit ? out.substr(0, limit) + "..." : out;
}

}  // namespace wlx::codegen
