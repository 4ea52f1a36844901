// The printer of the dynamics passes' code: names, lane types, indentation (lane_printer.hpp).
#include "lane_printer.hpp"

#include "expr_graph.hpp"

#include <fmt/format.h>
#include <wlx/support/text.hpp>

#include <algorithm>
#include <cctype>
#include <set>
#include <stdexcept>

namespace wlx::codegen::lane_code {

namespace {

// The prefix of every name below that could meet a model's (the lane scalars and the sums the
// model file cannot name): the model's coordinates and parameters must not start with it.
constexpr std::string_view kReservedPrefix = "kane_";

// Each quantity's name, from its indices.
struct Spelling {
  Quantity what;
  const char* pattern;
};
constexpr Spelling kSpellings[] = {
    {Quantity::rate_basis_entry, "T({}, {})"},
    {Quantity::rate, "sdot({})"},
    {Quantity::acceleration, "sddot({})"},
    {Quantity::joint_axis, "kane_S_{}_{}"},
    {Quantity::com_offset, "kane_p_{}_{}"},
    {Quantity::com_rotation, "kane_R_{}_{}_{}"},
    {Quantity::mass, "kane_mass_{}"},
    {Quantity::inertia, "kane_inertia_{}_{}"},
    {Quantity::gravity, "kane_g"},
    {Quantity::minus_gravity, "kane_minus_g"},
    {Quantity::spatial_velocity, "kane_V{}_{}"},
    {Quantity::motion_cross, "kane_X{}_{}"},
    {Quantity::spatial_acceleration, "kane_A{}_{}"},
    {Quantity::com_velocity, "kane_v{}_{}"},
    {Quantity::com_acceleration, "kane_a{}_{}"},
    {Quantity::force, "kane_F{}_{}"},
    {Quantity::body_rate, "kane_wb{}_{}"},
    {Quantity::body_angular_acceleration, "kane_ab{}_{}"},
    {Quantity::angular_momentum, "kane_Iw{}_{}"},
    {Quantity::body_moment, "kane_N{}_{}"},
    {Quantity::moment, "kane_M{}_{}"},
    {Quantity::wrench, "kane_W{}_{}"},
    {Quantity::joint_force, "kane_tau{}"},
    {Quantity::coordinate_force, "kane_tau_s{}"},
    {Quantity::commanded_force, "kane_Q{}"},
    {Quantity::first_moment, "kane_h{}_{}"},
    {Quantity::inertia_difference, "kane_dI{}_{}"},
    {Quantity::rotated_inertia, "kane_RI{}_{}_{}"},
    {Quantity::inertia_shift, "kane_sigma{}"},
    {Quantity::origin_inertia, "kane_J{}_{}_{}"},
    {Quantity::composite_mass, "kane_mc{}"},
    {Quantity::composite_first_moment, "kane_hc{}_{}"},
    {Quantity::composite_inertia, "kane_Jc{}_{}_{}"},
    {Quantity::joint_momentum, "kane_IS{}_{}"},
    {Quantity::joint_mass, "kane_Mjk{}_{}"},
    {Quantity::projected_mass, "kane_TM{}_{}"},
    {Quantity::reduced_mass, "kane_Mu{}_{}"},
    {Quantity::gravity_force, "kane_G{}"},
    {Quantity::commanded_gravity, "kane_Gu{}"},
    {Quantity::local_rotation, "kane_Rl{}_{}_{}"},
    {Quantity::local_offset, "kane_rl{}_{}"},
    {Quantity::offset_velocity, "kane_wr{}_{}"},
    {Quantity::carried_acceleration, "kane_C{}_{}"},
    {Quantity::incoming_motion, "kane_In{}_{}"},
    {Quantity::transmitted_force, "kane_Ft{}_{}"},
    {Quantity::turned_first_moment, "kane_hr{}_{}"},
    {Quantity::carried_first_moment, "kane_hp{}_{}"},
    {Quantity::turned_inertia, "kane_RJ{}_{}_{}"},
    {Quantity::carried_shift, "kane_sp{}"},
    {Quantity::carried_inertia, "kane_Jp{}_{}_{}"},
    {Quantity::carried_momentum, "kane_Fc{}_{}_{}"},
    {Quantity::up_direction, "kane_up{}_{}"},
    {Quantity::gravity_wrench, "kane_Wg{}_{}"},
    {Quantity::constant, "kane_c{}"},
};

class LanePrinter {
 public:
  explicit LanePrinter(const LaneProgram& program) : program_(program) {}

  std::string name(const ValueId& id) const {
    // The composite pass' values named after another one (LaneProgram::named_after): its name, marked.
    if (id.what == Quantity::lanes_of || id.what == Quantity::row_sum || id.what == Quantity::negated ||
        id.what == Quantity::scalar_part || id.what == Quantity::everywhere) {
      const ValueId from = program_.named_after.at(id);
      std::string base;
      for (const char c : name(from))  // T(18, 0) as kane_T_18_0
        if (std::isalnum(static_cast<unsigned char>(c)) || c == '_') base += c;
        else if (!base.empty() && base.back() != '_') base += '_';
      while (!base.empty() && base.back() == '_') base.pop_back();
      if (!base.starts_with(kReservedPrefix)) base = std::string(kReservedPrefix) + base;
      switch (id.what) {
        case Quantity::lanes_of: return base + "_lanes";
        case Quantity::row_sum: return base + "_by_lane";
        case Quantity::scalar_part: return base + "_scalars";
        case Quantity::everywhere: return base + "_everywhere";
        default: return base + "_negated";
      }
    }
    const auto* spelling = std::find_if(std::begin(kSpellings), std::end(kSpellings), [&](const Spelling& s) { return s.what == id.what; });
    const char* pattern = spelling == std::end(kSpellings) ? nullptr : spelling->pattern;
    if (pattern == nullptr) throw std::logic_error(fmt::format("lane code: no name for quantity {}", static_cast<int>(id.what)));
    std::string out = fmt::format(fmt::runtime(pattern), id.index[0], id.index[1], id.index[2]);
    return out;
  }

  std::string code(const std::vector<bool>& keep) {
    const auto& statements = program_.statements;
    for (std::size_t i = 0; i < statements.size(); ++i) {
      if (!keep[i]) continue;
      std::visit([&](const auto& step) { print(step); }, statements[i].step);
    }
    return std::move(out_);
  }

 private:
  static const char* type(Layout layout) { return layout == Layout::scalar ? "Scalar" : "L"; }
  std::string zero(Layout layout) const { return fmt::format("detail::zero_lanes<Scalar, {}>()", program_.lanes(layout)); }
  const char* indent() const { return output_ != nullptr && output_->indent_body ? "      " : "    "; }

  std::string sum(const std::vector<Term>& terms) const {
    if (terms.empty()) return "Scalar(0)";
    std::string out;
    for (std::size_t k = 0; k < terms.size(); ++k) {
      const Term& t = terms[k];
      if (k > 0) out += t.negate ? " - " : " + ";
      else if (t.negate) out += "-";
      if (t.factor.what != Quantity::one) out += name(t.factor) + " * ";
      out += name(t.value);
      if (t.lane >= 0) out += fmt::format(".lane({})", t.lane);
    }
    return out;
  }

  // Quoted (wlx/support/text.hpp): the text may hold a body's meaning from the model file.
  void print(const Comment& s) { out_ += fmt::format("{}// {}\n", indent(), text::cpp_comment(s.text)); }
  void print(const Define& s) { out_ += fmt::format("{}const {} {} = {};\n", indent(), type(s.layout), name(s.target), sum(s.terms)); }
  void print(const LoadRow& s) {
    const std::string target = name(s.target);
    out_ += fmt::format("{}L {} = {};\n", indent(), target, zero(Layout::row));
    for (const auto& [lane, entry] : s.lanes) out_ += fmt::format("{}{}.set_lane({}, {});\n", indent(), target, lane, name(entry));
  }
  void print(const LaneTypes&) {
    out_ += fmt::format("{}using L = detail::Lanes<Scalar, {}>;\n", indent(), program_.width);
  }
  void print(const OpenOutput& s) {
    out_ += fmt::format("    if ({} != nullptr) {{{}\n", s.output, s.note.empty() ? "" : "  // " + s.note);
    output_ = &s;
    if (s.prologue == OpenOutput::Prologue::zero) out_ += fmt::format("{}{}->setZero();\n", indent(), s.output);
    if (s.prologue == OpenOutput::Prologue::zero_if_asked) out_ += fmt::format("{}if (zero_fill) {}->setZero();\n", indent(), s.output);
  }
  void print(const CloseOutput&) {
    output_ = nullptr;
    out_ += "    }\n";
  }
  void print(const Store& s) {
    const auto entry = [&](int a, int b) { return b < 0 ? fmt::format("(*{})({})", s.output, a) : fmt::format("(*{})({}, {})", s.output, a, b); };
    const std::string lvalue = s.mirrored ? entry(s.row, s.column) + " = " + entry(s.column, s.row) : entry(s.row, s.column);
    out_ += fmt::format("{}{} = {};\n", indent(), lvalue, sum(s.terms));
  }

  const LaneProgram& program_;
  const OpenOutput* output_ = nullptr;  // the output block the statements are in, if any
  std::string out_;
};

}  // namespace

void reserve_printer_names(const Model& m) {
  const auto reserved = [](const char* what, const std::string& name) {
    if (name.starts_with(kReservedPrefix))
      throw std::runtime_error(fmt::format("{} name {}: names starting with {} are reserved", what, name, kReservedPrefix));
  };
  for (const auto& c : m.coordinates) reserved("coordinate", c.name);
  for (const auto& par : m.parameters) reserved("parameter", par.name);
}

long scalar_operations(const PrintedCode& printed) {
  ExprGraph graph;
  std::vector<int> stack;
  for (const auto& [name, value] : printed.scalars) stack.push_back(graph.add(value));
  std::set<int> seen;
  long ops = 0;
  while (!stack.empty()) {
    const int id = stack.back();
    stack.pop_back();
    if (graph.is_leaf(id) || !seen.insert(id).second) continue;
    ops += graph.own_ops(id).total();
    for (int a : graph.node(id).args) stack.push_back(a);
  }
  return ops;
}

PrintedCode print(const LaneProgram& program, std::size_t outputs) {
  const std::vector<bool> keep = kept_statements(program);
  LanePrinter printer(program);
  PrintedCode out;
  out.ops.resize(outputs);
  std::set<ValueId> read;
  for (std::size_t i = 0; i < program.statements.size(); ++i) {
    if (!keep[i]) continue;
    const Statement& s = program.statements[i];
    out.ops.at(static_cast<std::size_t>(s.output)) += operations(program, s.step);
    for (const ValueId& v : reads(s.step)) read.insert(v);
  }
  // A scalar no kept statement reads (a body's rotation that only unread values needed) is not
  // computed at all.
  for (const auto& [id, value] : program.scalars)
    if (read.count(id)) out.scalars.emplace_back(printer.name(id), value);
  out.code = printer.code(keep);
  return out;
}

}  // namespace wlx::codegen::lane_code
