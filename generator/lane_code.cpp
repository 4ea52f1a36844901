// What follows from the lane code's structure (lane_code.hpp): which values are read, which
// statements stay, and what each costs.
#include "lane_code.hpp"

#include <algorithm>
#include <map>
#include <type_traits>

namespace wlx::codegen::lane_code {

namespace {

void add_term_reads(const std::vector<Term>& terms, std::vector<ValueId>& out) {
  for (const Term& t : terms) {
    out.push_back(t.factor);
    out.push_back(t.value);
  }
}

}  // namespace

std::vector<ValueId> reads(const Step& step) {
  std::vector<ValueId> out;
  std::visit(Overloaded{[&](const Define& s) { add_term_reads(s.terms, out); },
                        [&](const Store& s) { add_term_reads(s.terms, out); },
                        [&](const LoadRow& s) {
                          for (const auto& lane : s.lanes) out.push_back(lane.second);
                        },
                        [](const auto&) {}},
             step);
  std::erase_if(out, [](const ValueId& v) { return v.is_zero() || v.what == Quantity::one; });
  return out;
}

ValueId defined_unless_unread(const Step& step) {
  return std::visit(Overloaded{[](const Define& s) { return s.target; }, [](const LoadRow& s) { return s.target; },
                               [](const auto&) { return ValueId{}; }},
                    step);
}

std::vector<bool> kept_statements(const LaneProgram& program) {
  const auto& statements = program.statements;
  // How many kept statements read each value; dropping one that none reads can leave its own
  // inputs unread, so this runs until nothing changes.
  std::map<ValueId, int> readers;
  std::vector<std::vector<ValueId>> read(statements.size());
  for (std::size_t i = 0; i < statements.size(); ++i) {
    read[i] = reads(statements[i].step);
    for (const ValueId& v : read[i]) ++readers[v];
  }
  std::vector<bool> keep(statements.size(), true);
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t i = 0; i < statements.size(); ++i) {
      const ValueId defined = defined_unless_unread(statements[i].step);
      if (!keep[i] || defined.is_zero() || readers[defined] > 0) continue;
      keep[i] = false;
      changed = true;
      for (const ValueId& v : read[i]) --readers[v];
    }
  }
  return keep;
}

OpCount operations(const LaneProgram& program, const Step& step) {
  // A sum of n terms on rows of k lanes: n - 1 additions and a multiplication per factor, each k
  // times; a leading minus is one more.
  const auto sum = [&](const std::vector<Term>& terms, Layout layout) {
    const long lanes = program.lanes(layout);
    OpCount ops;
    if (terms.empty()) return ops;
    ops.adds = (static_cast<long>(terms.size()) - 1 + (terms.front().negate ? 1 : 0)) * lanes;
    for (const Term& t : terms)
      if (t.factor.what != Quantity::one) ops.muls += lanes;
    return ops;
  };
  return std::visit(Overloaded{[&](const Define& s) { return sum(s.terms, s.layout); },
                               [&](const Store& s) { return sum(s.terms, Layout::scalar); }, [](const auto&) { return OpCount{}; }},
                    step);
}

}  // namespace wlx::codegen::lane_code
