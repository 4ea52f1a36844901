// The printer of the dynamics passes' code: names, lane types, indentation (lane_printer.hpp).
#include "lane_printer.hpp"

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

// Each quantity's name, from its indices, in the lane code and in the scalar code (the two spell
// some alike values apart: the names the generated headers have always had).
struct Spelling {
  Quantity what;
  const char* lanes;
  const char* scalars;
};
constexpr Spelling kSpellings[] = {
    {Quantity::rate_basis_entry, "T({}, {})", "T({}, {})"},
    {Quantity::rate, "sdot({})", "sdot({})"},
    {Quantity::acceleration, "sddot({})", "sddot({})"},
    {Quantity::joint_axis, "kane_twist_{}_{}", "kane_S_{}_{}"},
    {Quantity::com_offset, "kane_p_{}_{}", "kane_p_{}_{}"},
    {Quantity::minus_com_offset, "kane_minus_p_{}_{}", nullptr},
    {Quantity::com_rotation, "kane_R_{}_{}_{}", "kane_R_{}_{}_{}"},
    {Quantity::mass, "kane_mass_{}_0", "kane_mass_{}"},
    {Quantity::inertia, "kane_inertia_{}_{}", "kane_inertia_{}_{}"},
    {Quantity::bias_acceleration, "kane_acc_{}_{}", "kane_acc_{}_{}"},
    {Quantity::bias_torque, "kane_torque_{}_{}", "kane_torque_{}_{}"},
    {Quantity::gravity, nullptr, "kane_g"},
    {Quantity::minus_gravity, "kane_minus_g", "kane_minus_g"},
    {Quantity::spatial_velocity, "twist{}_{}", "kane_V{}_{}"},
    {Quantity::motion_cross, nullptr, "kane_X{}_{}"},
    {Quantity::spatial_acceleration, nullptr, "kane_A{}_{}"},
    {Quantity::com_velocity, "pv{}_{}", "kane_v{}_{}"},
    {Quantity::com_acceleration, nullptr, "kane_a{}_{}"},
    {Quantity::force, "dv{}_{}", "kane_F{}_{}"},
    {Quantity::body_rate, "pb{}_{}", "kane_wb{}_{}"},
    {Quantity::body_angular_acceleration, nullptr, "kane_ab{}_{}"},
    {Quantity::angular_momentum, "db{}_{}", "kane_Iw{}_{}"},
    {Quantity::body_moment, nullptr, "kane_N{}_{}"},
    {Quantity::moment, "moment{}_{}", "kane_M{}_{}"},
    {Quantity::wrench, "wrench{}_{}", "kane_W{}_{}"},
    {Quantity::joint_force, "tau{}", "kane_tau{}"},
    {Quantity::coordinate_force, nullptr, "kane_tau_s{}"},
    {Quantity::commanded_force, nullptr, "kane_Q{}"},
    {Quantity::first_moment, nullptr, "kane_h{}_{}"},
    {Quantity::inertia_difference, nullptr, "kane_dI{}_{}"},
    {Quantity::rotated_inertia, nullptr, "kane_RI{}_{}_{}"},
    {Quantity::inertia_shift, nullptr, "kane_sigma{}"},
    {Quantity::origin_inertia, nullptr, "kane_J{}_{}_{}"},
    {Quantity::composite_mass, nullptr, "kane_mc{}"},
    {Quantity::composite_first_moment, nullptr, "kane_hc{}_{}"},
    {Quantity::composite_inertia, nullptr, "kane_Jc{}_{}_{}"},
    {Quantity::joint_momentum, nullptr, "kane_IS{}_{}"},
    {Quantity::joint_mass, nullptr, "kane_Mjk{}_{}"},
    {Quantity::projected_mass, nullptr, "kane_TM{}_{}"},
    {Quantity::reduced_mass, nullptr, "kane_Mu{}_{}"},
    {Quantity::gravity_force, nullptr, "kane_G{}"},
    {Quantity::commanded_gravity, nullptr, "kane_Gu{}"},
    {Quantity::local_rotation, nullptr, "kane_Rl{}_{}_{}"},
    {Quantity::local_offset, nullptr, "kane_rl{}_{}"},
    {Quantity::offset_velocity, nullptr, "kane_wr{}_{}"},
    {Quantity::carried_acceleration, nullptr, "kane_C{}_{}"},
    {Quantity::incoming_motion, nullptr, "kane_In{}_{}"},
    {Quantity::transmitted_force, nullptr, "kane_Ft{}_{}"},
    {Quantity::constant, nullptr, "kane_c{}"},
    {Quantity::rate_row, "kane_T_{}", nullptr},
    {Quantity::mass_matrix_row, "kane_M_{}", nullptr},
    {Quantity::velocity_forces, "kane_b", nullptr},
    {Quantity::gravity_forces, "kane_Q", nullptr},
    {Quantity::bias_column, "kane_B_{}", nullptr},
};

class LanePrinter {
 public:
  explicit LanePrinter(const LaneProgram& program) : program_(program) {}

  std::string name(const ValueId& id) const {
    // The composite pass' values named after another one (composite_units.cpp folds that one's
    // quantity into the first index): its name, marked.
    if (id.what == Quantity::lanes_of || id.what == Quantity::row_sum || id.what == Quantity::negated) {
      const ValueId from = value_id(static_cast<Quantity>(id.index[0] / 1000), id.index[0] % 1000, id.index[1], id.index[2]);
      std::string base;
      for (const char c : name(from))  // T(18, 0) as kane_T_18_0
        if (std::isalnum(static_cast<unsigned char>(c)) || c == '_') base += c;
        else if (!base.empty() && base.back() != '_') base += '_';
      while (!base.empty() && base.back() == '_') base.pop_back();
      if (!base.starts_with(kReservedPrefix)) base = std::string(kReservedPrefix) + base;
      return base + (id.what == Quantity::lanes_of ? "_lanes" : id.what == Quantity::row_sum ? "_by_lane" : "_negated");
    }
    const auto* spelling = std::find_if(std::begin(kSpellings), std::end(kSpellings), [&](const Spelling& s) { return s.what == id.what; });
    const char* pattern = spelling == std::end(kSpellings) ? nullptr
                          : program_.kind == LaneProgram::Kind::lanes ? spelling->lanes
                                                                      : spelling->scalars;
    if (pattern == nullptr) throw std::logic_error(fmt::format("lane code: no name for quantity {}", static_cast<int>(id.what)));
    std::string out = fmt::format(fmt::runtime(pattern), id.index[0], id.index[1], id.index[2]);
    if (id.wide_copy) out += "_all";
    if (id.part > 0) out += fmt::format("_part{}", id.part);
    return out;
  }

  std::string code(const std::vector<bool>& keep) {
    const auto& statements = program_.statements;
    for (std::size_t i = 0; i < statements.size(); ++i) {
      if (!keep[i]) continue;
      if (std::holds_alternative<ZeroRow>(statements[i].step)) {
        i = zero_rows(i, keep) - 1;
        continue;
      }
      std::visit([&](const auto& step) { print(step); }, statements[i].step);
    }
    return std::move(out_);
  }

 private:
  static const char* type(Layout layout) { return layout == Layout::scalar ? "Scalar" : layout == Layout::wide ? "LW" : "L"; }
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
  void print(const Accumulate& s) { out_ += fmt::format("{}{} += {};\n", indent(), name(s.target), sum(s.terms)); }
  void print(const PlusLane& s) {
    const std::string target = name(s.target);
    out_ += fmt::format("{0}{1} {2} = {3};\n{0}{2}.add_to_lane({4}, {5});\n", indent(), type(s.layout), target,
                        s.base.is_zero() ? zero(s.layout) : name(s.base), s.lane, name(s.value));
  }
  void print(const Widen& s) {
    const std::string target = name(s.target), source = name(s.source);
    out_ += fmt::format("{}LW {} = {};\n", indent(), target, zero(Layout::wide));
    for (const auto& [lane, from] : s.lanes) out_ += fmt::format("{}{}.set_lane({}, {}.lane({}));\n", indent(), target, lane, source, from);
  }
  void print(const LoadRow& s) {
    const std::string target = name(s.target);
    if (s.whole) {
      out_ += fmt::format("{}const L {} = detail::lanes_of_row<Scalar, {}>(T, {});\n", indent(), target, program_.speeds, s.row);
      return;
    }
    out_ += fmt::format("{}L {} = {};\n", indent(), target, zero(Layout::narrow));
    for (const auto& [lane, entry] : s.lanes) out_ += fmt::format("{}{}.set_lane({}, {});\n", indent(), target, lane, name(entry));
  }
  void print(const ZeroRow& s) { out_ += fmt::format("{}{} {} = {};\n", indent(), type(s.layout), name(s.target), zero(s.layout)); }
  // A run of accumulators' declarations, from statement `first` on, in the order of the
  // accumulators' names (an accumulator's parts in the order they come): the order the generated
  // headers have always had, whatever order the derivation made them in. Returns the statement
  // after the run.
  std::size_t zero_rows(std::size_t first, const std::vector<bool>& keep) {
    std::vector<std::pair<std::string, const ZeroRow*>> rows;
    std::size_t end = first;
    for (; end < program_.statements.size() && std::holds_alternative<ZeroRow>(program_.statements[end].step); ++end) {
      if (!keep[end]) continue;
      const ZeroRow& row = std::get<ZeroRow>(program_.statements[end].step);
      const ValueId accumulator{row.target.what, row.target.index};
      rows.emplace_back(name(accumulator), &row);
    }
    std::stable_sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& row : rows) print(*row.second);
    return end;
  }
  void print(const LaneTypes&) {
    out_ += fmt::format("{}using L = detail::Lanes<Scalar, {}>;\n", indent(), program_.width);
    if (program_.shares_lanes()) out_ += fmt::format("{}using LW = detail::Lanes<Scalar, {}>;\n", indent(), program_.speeds);
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
  if (program.kind == LaneProgram::Kind::lanes)
    out.layout = program.shares_lanes() ? fmt::format("{} lanes, {} where the limbs' sums meet", program.width, program.speeds)
                                        : fmt::format("{} lanes", program.speeds);
  return out;
}

}  // namespace wlx::codegen::lane_code
