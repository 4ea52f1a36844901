// A hash-consed expression DAG built from GiNaC expressions, with common-subexpression
// elimination and operation counting.
//
// Why not walk GiNaC's trees directly: GiNaC orders the operands of sums and products by hash
// values seeded with type_info addresses, which change from run to run. This graph orders
// commutative operands by a structural hash of names and values only, so the emitted code is
// byte-for-byte the same on every run and machine.
#pragma once

#include <ginac/ginac.h>

#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

namespace wlx::codegen {

enum class NodeKind { Symbol, Number, Add, Mul, Pow, Call };

struct Node {
  NodeKind kind = NodeKind::Number;
  std::string text;     // symbol name, function name, or the number's exact GiNaC form
  double value = 0;     // Number: the value; Pow: the exponent
  std::vector<int> args;
  std::uint64_t hash = 0;
};

struct OpCount {
  long adds = 0;  // additions, subtractions, negations
  long muls = 0;
  long divs = 0;
  long calls = 0;  // sin, cos, sqrt, atan2, ...
  long total() const { return adds + muls + divs + calls; }
  OpCount& operator+=(const OpCount& o) {
    adds += o.adds; muls += o.muls; divs += o.divs; calls += o.calls;
    return *this;
  }
};

class ExprGraph {
 public:
  // Returns the node id of a GiNaC expression (memoised).
  int add(const GiNaC::ex& e);
  const Node& node(int id) const { return nodes_[static_cast<std::size_t>(id)]; }
  bool is_leaf(int id) const {
    return node(id).kind == NodeKind::Symbol || node(id).kind == NodeKind::Number;
  }
  bool is_zero(int id) const { return node(id).kind == NodeKind::Number && node(id).value == 0.0; }
  std::size_t size() const { return nodes_.size(); }
  // Operations needed to evaluate just this node from its (already evaluated) arguments.
  OpCount own_ops(int id) const;
  // Operations of the whole expression as a tree, every repeated subexpression counted again.
  OpCount tree_ops(int id) const;

 private:
  int intern(Node n);
  int make(NodeKind kind, std::string text, double value, std::vector<int> args);
  // Canonical constructors: products flattened with one numeric coefficient, sums signed so that
  // their first term (in this graph's own order) is positive. GiNaC's choice of which of a - b
  // and -(b - a) to keep depends on its hash order, so this is needed for deterministic output.
  int number(double v);
  int product(std::vector<int> factors);
  int sum(const std::vector<int>& terms);
  int power(int base, double exponent);
  std::pair<double, int> split_coefficient(int id);  // id = c * magnitude
  bool less(int a, int b) const;

  std::vector<Node> nodes_;
  std::unordered_map<std::uint64_t, std::vector<int>> by_hash_;
  std::map<GiNaC::ex, int, GiNaC::ex_is_less> memo_;
  mutable std::unordered_map<int, OpCount> tree_memo_;
};

// The result of common-subexpression elimination over a set of roots: the nodes to keep in
// temporaries, in an order in which each one's arguments come before it.
struct CsePlan {
  std::vector<int> temporaries;
  std::unordered_map<int, int> temp_index;  // node id -> position in temporaries
};

// Every node's value in double, operation by operation as the printed code computes it, for the
// symbols given; a node using any other symbol is unknown. GiNaC's exact arithmetic can be finite
// where double is not (exp(1000)/exp(999) is e exactly, inf/inf in double).
struct DoubleValues {
  std::vector<double> value;
  std::vector<char> known;
  int first_bad = -1;  // the first node that is NaN or infinite although its arguments are finite
  std::string why;     // what happened there: "division by zero", "overflow", ...

  // "nan", "inf" or "-inf" for a node that is not finite.
  std::string shown(int id) const;
};
DoubleValues evaluate_in_double(const ExprGraph& g, const std::map<std::string, double>& symbols);

// A node as text for messages, cut after about `limit` characters (a derived expression can be
// far larger printed as a tree than as the graph).
std::string node_text(const ExprGraph& g, int id, std::size_t limit = 80);

// Every non-leaf node reached twice or more becomes a temporary (so does the base of an integer
// power, which would otherwise be evaluated once per factor).
CsePlan eliminate_common_subexpressions(const ExprGraph& g, const std::vector<int>& roots);

}  // namespace wlx::codegen
