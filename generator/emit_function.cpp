// Emission of one derived function's header: its outputs as one expression graph with their
// common subexpressions shared, the body written block by block (each output computed only when
// requested), and the declarations, documentation and operation counts around it.
#include "emit_internal.hpp"
#include "model_file.hpp"
#include "printer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <functional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

namespace wlx::codegen {

namespace {

using namespace detail;

// bodies -> BodiesOutputs, kinematic_update -> KinematicUpdateOutputs.
std::string outputs_struct_name(const std::string& function) {
  std::string name;
  bool upper = true;
  for (char c : function) {
    if (c == '_') {
      upper = true;
      continue;
    }
    name += upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
    upper = false;
  }
  return name + "Outputs";
}

std::string op_summary(const OpCount& c) {
  return fmt::format("{} (adds {}, muls {}, divs {}, calls {})", c.total(), c.adds, c.muls, c.divs, c.calls);
}

struct Element {
  std::string lvalue;
  int id;
};

// A function's outputs as nodes of one graph: a block of elements per output, then, with lane
// code, the block of its scalars (at index `lanes`); `roots` holds every element's node.
struct FunctionGraph {
  ExprGraph g;
  std::vector<std::vector<Element>> outs;
  std::vector<int> roots;
  std::size_t lanes = 0;
};

void add_outputs(const FunctionSpec& fn, FunctionGraph& fg) {
  for (const auto& o : fn.outputs) {
    std::vector<Element> els;
    for (const auto& [lv, e] : o.elements) {
      const int id = fg.g.add(e);
      if (fg.g.is_zero(id) && !o.prologue.empty()) continue;  // structural zero, written by the prologue
      els.push_back({fmt::format(fmt::runtime(lv), o.name), id});
      fg.roots.push_back(id);
    }
    fg.outs.push_back(std::move(els));
  }
  // The lane code's scalars: one more block, after the outputs', named by lane_scalars.
  fg.lanes = fg.outs.size();
  if (!fn.lane_code.empty()) {
    std::vector<Element> els;
    for (const auto& [name, e] : fn.lane_scalars) {
      const int id = fg.g.add(e);
      els.push_back({name, id});
      fg.roots.push_back(id);
    }
    fg.outs.push_back(std::move(els));
  }
}

// Every output evaluated in double at the default (or baked) parameters and the nominal state, as
// the emitted code computes it: an output that is NaN or infinite there would be emitted as code
// that yields it in the model's first call. Outputs that use other inputs (rates, lanes) are not
// known here and pass.
void refuse_non_finite(const Model& m, const FunctionSpec& fn, const EmitOptions& opt, const ExprGraph& g,
                       const std::vector<std::vector<Element>>& outs) {
  std::map<std::string, double> at;
  for (const Parameter& p : m.parameters) {
    const auto baked = opt.baked.find(p.name);
    at[p.name] = baked == opt.baked.end() ? p.default_value : baked->second;
  }
  for (std::size_t k = 0; k < m.coordinates.size() && k < m.nominal.size(); ++k) at[m.coordinates[k].name] = m.nominal[k];
  const DoubleValues values = evaluate_in_double(g, at);
  for (const auto& block : outs)
    for (const Element& el : block)
      if (values.known[static_cast<std::size_t>(el.id)] && !std::isfinite(values.value[static_cast<std::size_t>(el.id)]))
        throw ModelFileError(fmt::format("{}(): {} evaluates to {} at the {} parameters and the nominal state ({}: {})", fn.name,
                                         el.lvalue, values.shown(el.id), opt.baked.empty() ? "default" : "default and baked",
                                         values.why, node_text(g, values.first_bad)));
}

// Which outputs need which temporaries: those needed by one output only are computed inside
// that output's block, so unrequested outputs cost nothing. `symbols`: the coordinates, rates and
// parameters the outputs read.
struct Readers {
  std::vector<std::set<int>> users;  // per temporary, the blocks whose expressions reach it
  std::set<std::string> symbols;
};

Readers find_readers(const FunctionGraph& fg, const CsePlan& plan) {
  Readers r{std::vector<std::set<int>>(plan.temporaries.size()), {}};
  for (std::size_t o = 0; o < fg.outs.size(); ++o) {
    std::unordered_set<int> seen;
    std::function<void(int)> visit = [&](int id) {
      if (!seen.insert(id).second) return;
      const Node& nd = fg.g.node(id);
      if (nd.kind == NodeKind::Symbol) r.symbols.insert(nd.text);
      if (auto it = plan.temp_index.find(id); it != plan.temp_index.end()) r.users[static_cast<std::size_t>(it->second)].insert(static_cast<int>(o));
      for (int a : nd.args) visit(a);
    };
    for (const auto& el : fg.outs[o]) visit(el.id);
  }
  return r;
}

// Writes a function's body after the batched sines and cosines: each output's block with the
// temporaries it alone reads, the shared ones before the first block that reads them, and counts
// the operations, shared and each block's own.
struct BodyWriter {
  BodyWriter(const ExprGraph& graph, const CsePlan& cse, const TrigBatch& batch, const std::vector<std::set<int>>& readers)
      : g(graph), plan(cse), trig(batch), users(readers), pr(graph, cse, batch.names), body(batch.prologue) {
    shared_ops.calls += trig.calls;
  }

  const ExprGraph& g;
  const CsePlan& plan;
  const TrigBatch& trig;
  const std::vector<std::set<int>>& users;
  Printer pr;
  std::string body;
  OpCount shared_ops;
  std::vector<OpCount> output_ops;
  std::string indent = "    ";  // of the lane code's line being written

  bool batched(std::size_t k) const { return trig.names.count(plan.temporaries[k]) != 0; }
  // Whether temporary k is block o's alone (then defined inside that block).
  bool local_to(std::size_t k, std::size_t o) const {
    return users[k].size() == 1 && *users[k].begin() == static_cast<int>(o) && !batched(k);
  }

  void write_blocks(const FunctionSpec& fn, const FunctionGraph& fg) {
    output_ops.assign(fg.outs.size(), OpCount{});
    // Beside lane code, the outputs of their own (reduced_dynamics' convective terms) share
    // temporaries the lane code never reads: those go into one scope with those outputs' blocks,
    // run when one of them is requested, so that a call for the lane code's outputs alone (M, say)
    // skips them.
    std::vector<std::size_t> own;
    for (std::size_t o = 0; o < fn.outputs.size(); ++o)
      if (!fn.outputs[o].from_lanes) own.push_back(o);
    std::vector<bool> in_scope(plan.temporaries.size(), false);
    if (!fn.lane_code.empty() && own.size() >= 2)
      for (std::size_t k = 0; k < plan.temporaries.size(); ++k)
        in_scope[k] = users[k].size() >= 2 && !batched(k) &&
                      std::all_of(users[k].begin(), users[k].end(), [&](int o) { return o != static_cast<int>(fg.lanes); });
    const bool scoped = std::find(in_scope.begin(), in_scope.end(), true) != in_scope.end();
    if (scoped) {
      std::vector<std::string> requested;
      for (std::size_t o : own) {
        define_shared_before(o, [&](std::size_t k) { return !in_scope[k]; });
        requested.push_back(fn.outputs[o].name + " != nullptr");
      }
      body += fmt::format("  if ({}) {{\n", fmt::join(requested, " || "));
      const std::size_t start = body.size();
      for (std::size_t o : own) {
        define_shared_before(o, [&](std::size_t k) { return in_scope[k]; });
        write_output_block(fn.outputs[o], fg.outs[o], o);
      }
      std::string inner = body.substr(start), indented;
      body.resize(start);
      std::istringstream lines(inner);
      for (std::string line; std::getline(lines, line);) indented += "  " + line + "\n";
      body += indented + "  }\n";
    }
    for (std::size_t o = 0; o < fg.outs.size(); ++o) {
      if (scoped && std::find(own.begin(), own.end(), o) != own.end()) continue;
      define_shared_before(o, [](std::size_t) { return true; });
      if (o == fg.lanes)
        write_lane_block(fn, fg.outs[o], o);
      else if (!fn.outputs[o].from_lanes)
        write_output_block(fn.outputs[o], fg.outs[o], o);
    }
  }

  // A temporary several outputs read is defined right before the block of the first of them, not
  // all up front: the same operations, fewer values held at once. users[k] holds every output
  // whose expression reaches k, through other temporaries too, so a temporary's first reader is
  // never after the first reader of one built on it, and ascending k within a block keeps the
  // order of dependence. (All up front, clang kept every one live across the blocks and spilled
  // about 6 kB of stack in the wheeled quadruped's kinematic_update: 1.7x GCC's time.) Only the
  // temporaries `which` takes.
  template <class Which>
  void define_shared_before(std::size_t o, const Which& which) {
    for (std::size_t k = 0; k < plan.temporaries.size(); ++k)
      if (users[k].size() >= 2 && !batched(k) && static_cast<std::size_t>(*users[k].begin()) == o && which(k))
        body += fmt::format("  const Scalar t{} = {};\n", k, pr.define(plan.temporaries[k], shared_ops));
  }

  void write_output_block(const OutputSpec& spec, const std::vector<Element>& els, std::size_t o) {
    body += fmt::format("  if ({} != nullptr) {{\n", spec.name);
    if (!spec.prologue.empty())
      body += "    if (zero_fill) " + fmt::format(fmt::runtime(spec.prologue), spec.name) + "\n";
    for (std::size_t k = 0; k < plan.temporaries.size(); ++k)
      if (local_to(k, o)) body += fmt::format("    const Scalar t{} = {};\n", k, pr.define(plan.temporaries[k], output_ops[o]));
    for (const auto& el : els) {
      body += fmt::format("    {} = {};\n", el.lvalue, pr.value(el.id, output_ops[o]));
    }
    body += "  }\n";
  }

  void write_lane_block(const FunctionSpec& fn, const std::vector<Element>& scalars, std::size_t o) {
    std::vector<std::string> requested;
    for (const auto& spec : fn.outputs)
      if (spec.from_lanes) requested.push_back(spec.name + " != nullptr");
    body += fmt::format("  if ({}) {{\n", fmt::join(requested, " || "));
    // Each scalar right before the first line of lane code that reads it, after the block's own
    // temporaries it needs: computed where used, not all up front, so that fewer values wait in
    // registers or on the stack while the lanes run (the code gets shorter).
    LaneScalars state;
    state.emitted.assign(plan.temporaries.size(), false);
    for (const auto& el : scalars) state.pending.emplace(el.lvalue, el.id);
    std::istringstream lines(fn.lane_code);
    for (std::string line; std::getline(lines, line);) {
      const std::size_t text = line.find_first_not_of(' ');
      if (text != std::string::npos && line[text] == '}') close_lane_scope(state);
      indent = std::string(4 + 2 * state.scopes.size(), ' ');
      for (const auto& word : identifiers(line)) define_lane_scalar(word, state, o);
      body += line + "\n";
      const std::string code = line.substr(0, line.find("  //"));  // a block's opening line may end in a comment
      if (!code.empty() && code.back() == '{') state.scopes.emplace_back();
    }
    if (!state.pending.empty()) throw std::logic_error("lane scalar " + state.pending.begin()->first + " is never read");
    body += "  }\n";
  }

  // The lane code's scalars and the temporaries they need, as they are placed: those not yet
  // defined, and those defined inside each of the lane code's blocks open at the line at hand (an
  // output's code run only when it is requested), which a reader after the block defines again.
  struct Scope {
    std::vector<std::pair<std::string, int>> scalars;
    std::vector<std::size_t> temporaries;
  };
  struct LaneScalars {
    std::map<std::string, int> pending, closed;  // lane scalar -> node: never defined; defined in a closed block
    std::vector<bool> emitted;
    std::vector<Scope> scopes;
  };
  static void close_lane_scope(LaneScalars& state) {
    if (state.scopes.empty()) return;
    for (const auto& [name, id] : state.scopes.back().scalars) state.closed.emplace(name, id);
    for (std::size_t k : state.scopes.back().temporaries) state.emitted[k] = false;
    state.scopes.pop_back();
  }

  // The lane scalar `name` if it is not defined where this line is, after the temporaries of
  // block o it needs.
  void define_lane_scalar(const std::string& name, LaneScalars& state, std::size_t o) {
    auto it = state.pending.find(name);
    std::map<std::string, int>* from = &state.pending;
    if (it == state.pending.end()) {
      it = state.closed.find(name);
      from = &state.closed;
      if (it == state.closed.end()) return;
    }
    const int id = it->second;
    from->erase(it);
    if (auto t = plan.temp_index.find(id); t != plan.temp_index.end()) {
      const auto k = static_cast<std::size_t>(t->second);
      if (local_to(k, o) && !state.emitted[k]) define_temporary(k, state, o);
    } else {
      define_needs(id, state, o);
    }
    body += fmt::format("{}const Scalar {} = {};\n", indent, name, pr.value(id, output_ops[o]));
    if (!state.scopes.empty()) state.scopes.back().scalars.emplace_back(name, id);
  }

  // Temporary k of block o, after those of block o it reads.
  void define_temporary(std::size_t k, LaneScalars& state, std::size_t o) {
    state.emitted[k] = true;
    define_needs(plan.temporaries[k], state, o);
    body += fmt::format("{}const Scalar t{} = {};\n", indent, k, pr.define(plan.temporaries[k], output_ops[o]));
    if (!state.scopes.empty()) state.scopes.back().temporaries.push_back(k);
  }

  // The temporaries of block o that node `id` reads, not defined yet, each after its own.
  void define_needs(int id, LaneScalars& state, std::size_t o) {
    for (int a : g.node(id).args) {
      if (auto it = plan.temp_index.find(a); it != plan.temp_index.end()) {
        const auto k = static_cast<std::size_t>(it->second);
        if (local_to(k, o) && !state.emitted[k]) define_temporary(k, state, o);
      } else {
        define_needs(a, state, o);
      }
    }
  }
};

// The numbers the umbrella header and this one's banner state.
void count_operations(const FunctionSpec& fn, const FunctionGraph& fg, const CsePlan& plan, const BodyWriter& w,
                      FunctionStats& stats) {
  OpCount total = w.shared_ops, before;
  for (const auto& c : w.output_ops) total += c;
  for (int r : fg.roots) before += fg.g.tree_ops(r);
  stats.name = fn.name;
  stats.intermediates = static_cast<int>(plan.temporaries.size());
  for (std::size_t k = 0; k < plan.temporaries.size(); ++k) stats.intermediates -= w.batched(k) ? 1 : 0;
  stats.before_cse = before;
  stats.after_cse = total;
}

std::string function_opening(const Model& m, const FunctionSpec& fn, const EmitOptions& opt, bool uses_trig) {
  std::string t = banner(m, opt, fmt::format("{}: {}", fn.name, fn.doc));
  t += "#pragma once\n\n#include <array>\n#include <cmath>\n\n#include \"params.hpp\"\n";
  t += uses_trig ? "#include \"trig.hpp\"\n" : "";
  t += "#include \"types.hpp\"\n\n" + namespace_open(opt) + "\n";
  t += fmt::format("// {}\n//\n", comment(fn.doc));
  return t;
}

// Each output with its own operations, the lane code's scalars, and the operation counts.
std::string operations_documentation(const FunctionSpec& fn, const FunctionGraph& fg, const BodyWriter& w,
                                     const FunctionStats& stats) {
  const std::string outputs_type = outputs_struct_name(fn.name);
  std::string t = fmt::format(
      "// Outputs, members of {}Of<Scalar> ({} for double), each computed only when its\n"
      "// pointer is set (C++20: {}(..., {{.{} = &x}})):\n",
      outputs_type, outputs_type, fn.name, fn.outputs.front().name);
  for (std::size_t o = 0; o < fn.outputs.size(); ++o) {
    if (fn.outputs[o].from_lanes)
      t += fmt::format("//   {:<18} {} (own operations: {})\n", fn.outputs[o].name, fn.outputs[o].doc, w.output_ops[o].total());
    else
      t += fmt::format("//   {:<18} {} (own operations: {}, nonzero entries: {})\n", fn.outputs[o].name, fn.outputs[o].doc,
                       w.output_ops[o].total(), fg.outs[o].size());
  }
  if (!fn.lane_code.empty())
    t += fmt::format("// The scalars that code is built from ({} of them, the bodies' and joints' geometry among them):\n"
                     "// {} operations, computed only when one of them is requested.\n",
                     fn.lane_scalars.size(), w.output_ops[fg.lanes].total());
  t += fmt::format("// Intermediate terms: {}; shared by several outputs: {} operations (sin and cos of all angles\n"
                   "// included: they are computed up front, whichever outputs are requested{}).\n",
                   stats.intermediates, w.shared_ops.total(),
                   fn.lane_code.empty() ? "" : ";\n// those only the outputs outside the lane code share, only when one of them is");
  t += fmt::format("// Operations with every output requested: {}.\n", op_summary(stats.after_cse));
  t += fmt::format("// The same outputs as expression trees, before CSE: {}.\n", op_summary(stats.before_cse));
  return t;
}

// One parameter list, printed twice: the template (Scalar deduced from s alone, so the other
// arguments, nullptr among them, are not deduced from) and the double overload, whose plain types
// take Eigen expressions for s, which a template cannot deduce from.
struct FunctionParameter {
  std::string templated, plain, name;
  std::string default_value() const { return name == "zero_fill" ? " = true" : ""; }
};

bool has_structural_zeros(const FunctionSpec& fn) {
  return std::any_of(fn.outputs.begin(), fn.outputs.end(), [](const auto& o) { return !o.prologue.empty(); });
}

std::vector<FunctionParameter> parameters_of(const FunctionSpec& fn) {
  const std::string outputs_type = outputs_struct_name(fn.name);
  std::vector<FunctionParameter> parameters{{"const CoordinatesOf<Scalar>&", "const Coordinates&", "s"}};
  if (fn.needs_rates) parameters.push_back({"const detail::NonDeduced<CoordinatesOf<Scalar>>&", "const Coordinates&", "sdot"});
  for (const auto& in : fn.inputs)
    parameters.push_back({fmt::format("const detail::NonDeduced<{}Of<Scalar>>&", in.type), fmt::format("const {}&", in.type), in.name});
  parameters.push_back({"const Params&", "const Params&", "p"});
  // The outputs by name in one struct, not as positional pointers of look-alike types.
  parameters.push_back({fmt::format("const detail::NonDeduced<{}Of<Scalar>>&", outputs_type),
                        fmt::format("const {}&", outputs_type), "out"});
  if (has_structural_zeros(fn)) parameters.push_back({"bool", "bool", "zero_fill"});
  return parameters;
}

std::string parameters_documentation(const FunctionSpec& fn) {
  std::string t =
      "// Scalar: double, float, or a number type with +, -, *, / and sin, cos (, sqrt, ...) found by\n"
      "// argument-dependent lookup; deduced from s. The parameters stay double.\n";
  for (const auto& in : fn.inputs) t += fmt::format("// Input {} ({}): {}\n", in.name, in.type, in.doc);
  if (has_structural_zeros(fn)) {
    // Zeroing a 14 x 32 or 7 x 3 x 32 output costs more than computing its nonzeros (store
    // bandwidth), so a workspace that keeps its zeros can skip it.
    t += "// zero_fill: write the structural zeros of the matrix outputs too. Pass false when they are\n"
         "// zero already (a workspace zeroed once at setup): this function never writes them.\n";
  }
  return t;
}

// The struct of output pointers, ...Of<Scalar>, and its double name.
std::string outputs_struct(const FunctionSpec& fn) {
  const std::string outputs_type = outputs_struct_name(fn.name);
  std::string t = fmt::format(
      "// Where {}() writes: set the outputs you want; a null pointer skips that output and the\n"
      "// work only it needs.\ntemplate <typename Scalar>\nstruct {}Of {{\n",
      fn.name, outputs_type);
  std::vector<std::string> members;
  std::size_t width = 0;
  for (const auto& o : fn.outputs) {
    members.push_back(fmt::format("{}* {} = nullptr;", o.type == "double" ? "Scalar" : o.type + "Of<Scalar>", o.name));
    width = std::max(width, members.back().size());
  }
  for (std::size_t o = 0; o < members.size(); ++o)
    t += fmt::format("  {:<{}}  // {}\n", members[o], width, fn.outputs[o].doc);
  t += fmt::format("}};\nusing {0} = {0}Of<double>;\n\n", outputs_type);
  return t;
}

// The function template, on the scalar type; `body`: its statements after the arguments' unpacking.
std::string function_template(const FunctionSpec& fn, const std::vector<FunctionParameter>& parameters,
                              const std::string& body) {
  std::vector<std::string> templated;
  for (const auto& par : parameters) templated.push_back(par.templated + " " + par.name + par.default_value());
  std::string t = fmt::format("template <typename Scalar>\ninline void {}({}) noexcept {{\n", fn.name, fmt::join(templated, ", "));
  t += "  static_cast<void>(s);\n  static_cast<void>(p);\n";
  for (const auto& o : fn.outputs) t += fmt::format("  const auto {0} = out.{0};\n", o.name);
  if (fn.needs_rates) t += "  static_cast<void>(sdot);\n";
  for (const auto& in : fn.inputs) t += fmt::format("  static_cast<void>({});\n", in.name);
  return t + body + "}\n\n";
}

std::string double_version(const EmitOptions& opt, const FunctionSpec& fn, const std::vector<FunctionParameter>& parameters) {
  std::vector<std::pair<std::string, std::string>> plain;  // declaration, default value
  for (const auto& par : parameters) plain.emplace_back(par.plain + " " + par.name, par.default_value());
  return double_overload(opt, fn.name, "void", plain, "for any Eigen expression of the coordinates");
}

}  // namespace

EmittedFile emit_function(const Model& m, const FunctionSpec& fn, const EmitOptions& opt, FunctionStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  FunctionGraph fg;
  add_outputs(fn, fg);
  refuse_non_finite(m, fn, opt, fg.g, fg.outs);
  const CsePlan plan = eliminate_common_subexpressions(fg.g, fg.roots);
  const TrigBatch trig = batch_trig(m, fg.g, fg.roots);
  const Readers readers = find_readers(fg, plan);

  BodyWriter w(fg.g, plan, trig, readers.users);
  w.write_blocks(fn, fg);
  // The lane code's operations, scalar-equivalent, are their outputs' own.
  for (std::size_t o = 0; o < fn.outputs.size(); ++o) w.output_ops[o] += fn.outputs[o].lane_ops;
  count_operations(fn, fg, plan, w, stats);

  const std::string aliases = coordinate_aliases(m, readers.symbols) + parameter_aliases(m, readers.symbols, opt);
  const std::vector<FunctionParameter> parameters = parameters_of(fn);
  std::string t = function_opening(m, fn, opt, !trig.names.empty());
  t += operations_documentation(fn, fg, w, stats);
  t += parameters_documentation(fn);
  t += outputs_struct(fn);
  t += function_template(fn, parameters, using_declarations(w.pr.calls()) + aliases + w.body);
  t += double_version(opt, fn, parameters);
  t += fmt::format("namespace operations {{\n// Operations {}() evaluates with every output requested (adds, muls, divs, calls).\n"
                   "inline constexpr long {} = {};\n}}  // namespace operations\n\n",
                   fn.name, fn.name, stats.after_cse.total());
  t += namespace_close(opt);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {"wlx/gen/" + fn.header, t};
}

}  // namespace wlx::codegen
