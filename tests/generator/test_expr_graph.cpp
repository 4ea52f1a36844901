// The expression graph and its CSE, on small GiNaC expressions.
#include "../../generator/expr_graph.hpp"

#include <doctest/doctest.h>

using namespace wlx::codegen;
using GiNaC::ex;

TEST_CASE("expr_graph: structurally equal expressions are one node, signs are canonical") {
  GiNaC::realsymbol a("a"), b("b"), c("c");
  ExprGraph g;
  const int x = g.add(c * (a - b));
  const int y = g.add(c * (a - b));
  CHECK(x == y);
  // c*(a-b) and -c*(b-a) are the same product: one canonical node whichever sign GiNaC kept.
  CHECK(g.add(-c * (b - a)) == x);
  const int z = g.add(GiNaC::sin(a) + GiNaC::cos(a));
  CHECK(g.node(z).kind == NodeKind::Add);
  CHECK(g.node(z).args.size() == 2);
}

TEST_CASE("expr_graph: a subexpression used twice becomes one temporary") {
  GiNaC::realsymbol a("a"), b("b");
  ExprGraph g;
  const ex shared = GiNaC::sin(a) * b + a;
  const std::vector<int> roots = {g.add(shared * a), g.add(shared * b)};
  const CsePlan plan = eliminate_common_subexpressions(g, roots);
  CHECK(plan.temporaries.size() == 1);
  CHECK(plan.temporaries[0] == g.add(shared));
  // Before CSE the shared sum (1 mul, 1 add, 1 call) is counted twice; each root adds a mul.
  OpCount before;
  for (int r : roots) before += g.tree_ops(r);
  CHECK(before.total() == 2 * 3 + 2);
}

TEST_CASE("expr_graph: integer powers of a sum compute the base once") {
  GiNaC::realsymbol a("a"), b("b");
  ExprGraph g;
  const int root = g.add(GiNaC::pow(a + b, 3));
  const CsePlan plan = eliminate_common_subexpressions(g, {root});
  REQUIRE(plan.temporaries.size() == 1);
  CHECK(plan.temporaries[0] == g.add(a + b));
}
