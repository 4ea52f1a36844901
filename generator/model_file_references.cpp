// What a model file's entries refer to: repetitions (`repeat:` and `for:`), the names of
// coordinates, parameters and frames, and expressions, parsed and checked at the defaults.
#include "model_file_internal.hpp"

#include "expr_graph.hpp"

#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

namespace wlx::codegen::model_file_detail {

// ---- repetition ----
void Parser::repeats(const Item& r) {
  if (!r.is_map()) r.fail("must map each repetition variable to its rows");
  for (const auto& kv : r.node()) {
    const std::string table = kv.first.Scalar();
    const Item rows(src_, kv.second, "repeat." + table, {});
    if (!is_identifier(table)) rows.fail(fmt::format("'{}' is not a name", excerpt(table)));
    if (!rows.is_sequence() || rows.size() == 0) rows.fail("must be a non-empty list of rows {variable: value, ...}");
    std::vector<Env> envs;
    for (const Item& row : rows.list()) {
      if (!row.is_map()) row.fail("a row must map variable names to values");
      Env env;
      for (const auto& v : row.node()) {
        const std::string var = v.first.Scalar();
        if (!is_identifier(var)) row.fail(fmt::format("'{}' is not a variable name", excerpt(var)));
        if (!v.second.IsScalar()) row.fail(fmt::format("variable '{}' must have a single value", var));
        env[var] = v.second.Scalar();
      }
      if (!envs.empty()) {
        std::set<std::string> a, b;
        for (const auto& kv2 : envs.front()) a.insert(kv2.first);
        for (const auto& kv2 : env) b.insert(kv2.first);
        if (a != b) row.fail("every row of a repetition must define the same variables as the first");
      }
      envs.push_back(std::move(env));
    }
    repeat_[table] = std::move(envs);
  }
}

void Parser::each(const Item& list, const std::function<void(const Item&)>& fn) {
  if (!list.defined()) return;
  const auto counted = [&](const Item& entry) {
    if (++expanded_entries_ > kMaxExpandedEntries)
      entry.fail(fmt::format("the file expands to more than {} list entries in all: beyond any machine", kMaxExpandedEntries));
    fn(entry);
  };
  for (const Item& e : list.list()) {
    if (!(e.is_map() && e.has("for"))) {
      counted(e);
      continue;
    }
    const Item spec = e.child("for");
    std::vector<std::string> tables;
    if (spec.is_sequence())
      for (const Item& t : spec.list()) tables.push_back(t.name());
    else
      tables.push_back(spec.name());
    for (const auto& t : tables)
      if (!repeat_.count(t)) {
        std::vector<std::string> names;
        for (const auto& kv : repeat_) names.push_back(kv.first);
        spec.fail(fmt::format("no repetition '{}' under `repeat:`{}", t, suggestion(t, names)));
      }
    // The product of the tables' rows, checked before any is written out: 10^9 rows from a
    // 1.6 KB file once took the generator past 1.2 GB.
    std::size_t product = 1;
    for (const auto& t : tables) {
      product *= repeat_[t].size();
      if (product > kMaxExpandedEntries)
        spec.fail(fmt::format("repeats its entry more than {} times (the product of the rows of {}): beyond any machine", kMaxExpandedEntries,
                              fmt::join(tables, ", ")));
    }
    std::vector<std::size_t> index(tables.size(), 0);
    while (true) {
      Env env = e.env();
      std::string suffix = "{";
      for (std::size_t k = 0; k < tables.size(); ++k) {
        const Env& row = repeat_[tables[k]][index[k]];
        for (const auto& [var, value] : row) {
          if (env.count(var)) spec.fail(fmt::format("repetition variable '{}' is defined twice here", var));
          env[var] = value;
        }
        // The row by its own value where the table has a variable of its name (side=l), else its index.
        const auto own = row.find(tables[k]);
        suffix += fmt::format("{}{}={}", k ? "," : "", tables[k], own != row.end() ? own->second : std::to_string(index[k]));
      }
      suffix += "}";
      const Item instance = e.with(env, suffix);
      if (e.has("items")) {
        const Fields only(instance, {"items"});
        each(only["items"], fn);
      } else {
        counted(instance);
      }
      std::size_t k = tables.size();
      while (k > 0 && ++index[k - 1] == repeat_[tables[k - 1]].size()) index[--k] = 0;
      if (k == 0) break;
    }
  }
}

// ---- names ----
void Parser::claim_symbol_name(const Item& it, const std::string& n) {
  if (const std::string why = reserved_reason(n); !why.empty()) it.fail(fmt::format("'{}' cannot be used as a name: {}", n, why));
  if (const auto found = symbol_kind_.find(n); found != symbol_kind_.end())
    it.fail(fmt::format("'{}' is already the name of a {}", n, found->second));
}

int Parser::coordinate_index(const Item& it, bool inputs_only, bool dependents_only) const {
  const std::string n = it.name();
  for (const auto& c : m_.coordinates)
    if (c.name == n) {
      if (inputs_only && c.index >= m_.input_count) it.fail(fmt::format("'{}' is a dependent joint; an input is needed here", n));
      if (dependents_only && c.index < m_.input_count) it.fail(fmt::format("'{}' is an input; a dependent joint is needed here", n));
      return c.index;
    }
  std::vector<std::string> names;
  for (const auto& c : m_.coordinates) names.push_back(c.name);
  it.fail(fmt::format("no coordinate '{}'{}", n, suggestion(n, names)));
}

const Parameter& Parser::parameter(const Item& it, std::optional<ParameterKind> kind) const {
  const std::string n = it.name();
  for (std::size_t k = 0; k < m_.parameters.size(); ++k)
    if (m_.parameters[k].name == n) {
      if (kind && m_.parameter_kinds[k] != *kind)
        it.fail(fmt::format("'{}' is a parameter of kind {}; one of kind {} is needed here", n,
                            kind_name(m_.parameter_kinds[k]), kind_name(*kind)));
      return m_.parameters[k];
    }
  std::vector<std::string> names;
  for (const auto& p : m_.parameters) names.push_back(p.name);
  it.fail(fmt::format("no parameter '{}'{}", n, suggestion(n, names)));
}

int Parser::frame_index(const Item& it) const {
  const std::string n = it.name();
  const int k = m_.frame_index(n);
  if (k >= 0) return k;
  std::vector<std::string> names;
  for (const auto& f : m_.frames) names.push_back(f.name);
  it.fail(fmt::format("no frame '{}'{}", n, suggestion(n, names)));
}

// ---- expressions ----
ex Parser::expression(const Item& it, bool allow_coordinates) const {
  const std::string s = it.text();
  // GiNaC's parser and every pass over the tree recurse on its depth: bounded before parsing.
  if (s.size() > kMaxExpressionBytes)
    it.fail(fmt::format("an expression of {} bytes; at most {} (a long formula belongs in parameters)", s.size(), kMaxExpressionBytes));
  {
    // Runs of signs (- - - x) nest like parentheses.
    int depth = 0, deepest = 0, signs = 0;
    for (const char c : s) {
      if (c == '(') deepest = std::max(deepest, ++depth), signs = 0;
      else if (c == ')') --depth, signs = 0;
      else if (c == '-' || c == '+') deepest = std::max(deepest, depth + ++signs);
      else if (c != ' ') signs = 0;
    }
    if (deepest > kMaxExpressionDepth)
      it.fail(fmt::format("in '{}': parentheses and signs nest more than {} deep", excerpt(s), kMaxExpressionDepth));
  }
  static const std::set<std::string> functions = {"sin", "cos", "tan", "asin", "acos", "atan", "sqrt", "exp", "log"};
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (std::isdigit(c) || (s[i] == '.' && i + 1 < s.size() && std::isdigit(static_cast<unsigned char>(s[i + 1])))) {
      while (i < s.size() && (std::isdigit(static_cast<unsigned char>(s[i])) || s[i] == '.')) ++i;
      if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
        while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
      }
      continue;
    }
    if (std::isalpha(c) || s[i] == '_') {
      std::size_t j = i;
      while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])) || s[j] == '_')) ++j;
      const std::string id = s.substr(i, j - i);
      std::size_t k = j;
      while (k < s.size() && s[k] == ' ') ++k;
      const bool call = k < s.size() && s[k] == '(';
      if (call) {
        if (!functions.count(id))
          it.fail(fmt::format("unknown function '{}' in '{}'; the functions are {}", id, excerpt(s), fmt::join(functions, ", ")));
      } else if (id != "Pi" && !params_.count(id)) {
        const bool coordinate = coordinates_.count(id) != 0;
        if (coordinate && !allow_coordinates)
          it.fail(fmt::format("'{}' is a coordinate; only parameters may appear in '{}'", id, excerpt(s)));
        if (!coordinate) {
          std::vector<std::string> names;
          for (const auto& kv : params_) names.push_back(kv.first);
          if (allow_coordinates)
            for (const auto& kv : coordinates_) names.push_back(kv.first);
          it.fail(fmt::format("unknown symbol '{}' in '{}'{}", id, excerpt(s), suggestion(id, names)));
        }
      }
      i = j;
      continue;
    }
    ++i;
  }
  // GiNaC evaluates integer powers exactly, so 9^9^9 would not finish: exponents are small
  // integer literals.
  for (std::size_t i = s.find('^'); i != std::string::npos; i = s.find('^', i + 1)) {
    std::size_t j = i + 1;
    while (j < s.size() && s[j] == ' ') ++j;
    if (j < s.size() && s[j] == '-') ++j;
    const std::size_t digits = j;
    while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) ++j;
    const std::size_t count = j - digits;
    while (j < s.size() && s[j] == ' ') ++j;
    if (count == 0 || count > 2 || (j < s.size() && (s[j] == '^' || s[j] == '.')))
      it.fail(fmt::format("in '{}': an exponent is a small integer (x^2, x^-1), not an expression", excerpt(s)));
  }
  GiNaC::symtab table = params_;
  if (allow_coordinates) table.insert(coordinates_.begin(), coordinates_.end());
  table["Pi"] = GiNaC::Pi;
  ex e;
  try {
    GiNaC::parser reader(table, true);
    e = reader(s);
  } catch (const std::exception& error) {
    it.fail(fmt::format("cannot read the expression '{}': {}", excerpt(s), error.what()));
  }
  check_at_defaults(it, s, e);
  return e;
}

// An expression of parameters alone is evaluated at their defaults: acos(2) or sqrt(-a) would be
// emitted as code that yields NaN, 1/(a - b) with a = b as an Inf, so each is an error here,
// naming the field. (An expression with coordinates is a joint step, checked where it is used.)
void Parser::check_at_defaults(const Item& it, const std::string& s, const ex& e) const {
  for (const auto& kv : coordinates_)
    if (e.has(kv.second)) return;
  std::string problem;
  try {
    const ex v = e.subs(param_defaults_).evalf();
    if (!GiNaC::is_a<GiNaC::numeric>(v)) {
      problem = "does not evaluate to a number";
    } else {
      const GiNaC::numeric n = GiNaC::ex_to<GiNaC::numeric>(v);
      std::ostringstream shown;
      shown << n;
      if (!n.is_real()) problem = fmt::format("is complex ({})", excerpt(shown.str()));
      else if (!std::isfinite(n.to_double())) problem = fmt::format("is not finite ({})", n.to_double());
    }
  } catch (const std::exception& error) {  // GiNaC's pole_error: 1/0, log(0), tan(Pi/2)
    problem = fmt::format("is singular ({})", error.what());
  }
  if (!problem.empty()) it.fail(fmt::format("'{}' at the default parameters {}", excerpt(s), problem));
  // Exact arithmetic can be finite where double is not (exp(1000)/exp(999)): the emitted code
  // computes in double, so the expression is also evaluated so, as the printed code would.
  ExprGraph graph;
  int root = 0;
  try {
    root = graph.add(e.subs(GiNaC::Pi == GiNaC::Pi.evalf()));  // the graph takes numbers, not constants
  } catch (const std::exception& error) {  // what the emitted code cannot compute (a power of a parameter's power)
    it.fail(fmt::format("'{}' cannot be written as code: {}", excerpt(s), error.what()));
  }
  std::map<std::string, double> defaults;
  for (const Parameter& p : m_.parameters) defaults[p.name] = p.default_value;
  const DoubleValues values = evaluate_in_double(graph, defaults);
  if (!std::isfinite(values.value[static_cast<std::size_t>(root)]))
    it.fail(fmt::format("'{}' evaluates to {} in double at the default parameters ({}: {})", excerpt(s), values.shown(root),
                        values.why, node_text(graph, values.first_bad)));
}

Vec3 Parser::vector3(const Item& it) const {
  if (!it.is_sequence() || it.size() != 3) it.fail("must be a list of 3 expressions [x, y, z]");
  return {expression(it.element(0), false), expression(it.element(1), false), expression(it.element(2), false)};
}

}  // namespace wlx::codegen::model_file_detail
