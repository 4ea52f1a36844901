// Parsing a report file (report/spec.hpp). yaml-cpp gives every node its line, so each error
// names the file, the line and the key.
#include "report/spec.hpp"

#include "bounded_input.hpp"

#include <fmt/format.h>
#include <wlx/error.hpp>
#include <wlx/support/text.hpp>
#include <yaml-cpp/yaml.h>
#include <wlx/support/yaml_key_check.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

namespace wlx::cli::report {

namespace {

// A source is a column of the claims' tables: a few fit a page.
constexpr std::size_t kMaxSources = 6;
constexpr const char* kNameCharacters = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-";

// Quantity -> the measure keys it requires (beyond `quantity`), and the ones it may take.
struct QuantityRule {
  std::string name;
  std::vector<std::string> required, optional;
};
// total_mass: the model's mass (kg). max_ik_check_error, max_ik_method_difference: over every
// sweep run (m, rad; the difference over the sweeps of limbs with a closed form).
// newton_branch_switch: the first value of `sweep`'s input where Newton from
// the start pose lands off the default branch; newton_branch_settled: the value from which it
// always does. max_wheel_residual: |v_W . n_W| over every sample
// of every run (m/s). end_value: `coordinate` at the end of `run`. end_ratio: that over the same
// of `of_run`. peak_condition(_time): the largest cond(J_beta) of `run` (and when). ground_contact_time:
// when the clearance box's lowest corner, extrapolated from `run`'s last two samples, reaches z = 0
// (a model without a clearance box has none: an error naming the claim).
// integrator_deviation: the largest deviation of `integrator` from the reference over `runs` (default:
// all compared) in `coordinates` (default: every input). static_torque: the largest |tau| of `joints`
// at the nominal pose at rest with `weighting`. peak_torque: the largest |tau| over `runs`.
// param_product: factor x the product of `params` (x the total mass). round_trip_deviation: the
// largest |s_forward - s_inverse| when the torques of the inverse-dynamics `runs` (default: all)
// drive the machine (m or rad); energy_balance: the largest |E(t) - E(0) - W(t)| of those forward
// runs over the largest |W(t)| (relative); closed_loop_error: the largest tracking error over the
// second half of the closed loop of `runs` (m or rad; none if a loop stopped early).
const std::vector<QuantityRule>& rules() {
  static const std::vector<QuantityRule> all{
      {"total_mass", {}, {}},
      {"max_ik_check_error", {}, {}},
      {"max_ik_method_difference", {}, {}},
      {"newton_branch_switch", {"sweep"}, {}},
      {"newton_branch_settled", {"sweep"}, {}},
      {"max_wheel_residual", {}, {}},
      {"end_value", {"run", "coordinate"}, {}},
      {"end_ratio", {"run", "of_run", "coordinate"}, {}},
      {"peak_condition", {"run"}, {}},
      {"peak_condition_time", {"run"}, {}},
      {"ground_contact_time", {"run"}, {}},
      {"integrator_deviation", {"integrator"}, {"runs", "coordinate", "coordinates"}},
      {"static_torque", {"joints"}, {"weighting"}},
      {"peak_torque", {"runs"}, {}},
      {"param_product", {"params"}, {"factor", "times_total_mass", "unit"}},
      {"round_trip_deviation", {}, {"runs"}},
      {"energy_balance", {}, {"runs"}},
      {"closed_loop_error", {}, {"runs"}},
  };
  return all;
}

class Parser {
 public:
  explicit Parser(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const YAML::Node& at, const std::string& path, const std::string& reason) const {
    throw Error(fmt::format("{}:{}: {}", file_, at.Mark().line + 1, path), reason);
  }
  int line(const YAML::Node& n) const { return n.Mark().line + 1; }

  void keys(const YAML::Node& map, const std::string& path, const std::vector<std::string>& valid) const {
    if (!map.IsMap()) fail(map, path, "must be a mapping (key: value)");
    for (const auto& kv : map) {
      if (!kv.first.IsScalar()) fail(kv.first, path, "a key is a list or a map: keys are names");
      const std::string key = kv.first.as<std::string>();
      if (std::find(valid.begin(), valid.end(), key) != valid.end()) continue;
      const std::string near = nearest(key, valid);
      fail(kv.first, path, fmt::format("unknown key '{}'{}", excerpt(key), near.empty() ? "" : fmt::format(" (did you mean '{}'?)", near)));
    }
  }
  YAML::Node required(const YAML::Node& map, const std::string& key, const std::string& path) const {
    const YAML::Node n = map[key];
    if (!n) fail(map, path, fmt::format("missing key '{}'", key));
    return n;
  }
  std::string text(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(n, path, "must be a text");
    const std::string s = n.as<std::string>();
    if (s.empty()) fail(n, path, "must not be empty");
    // Every text of a report file reaches a gnuplot script or the HTML page: one line of
    // printable UTF-8 (and quoted for each where it is written, report/figures.cpp, html.cpp).
    if (const std::string why = text::check_one_line(s); !why.empty()) fail(n, path, why);
    return s;
  }
  double number(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(n, path, "must be a number");
    double v = 0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(n, path, fmt::format("must be a number, got '{}'", n.as<std::string>()));
    }
    if (!std::isfinite(v)) fail(n, path, "must be finite");
    return v;
  }
  // A weighting a report's run is named by: model-weights (1, its run id's -w1) or contribution (2, -w2).
  int weighting(const YAML::Node& n, const std::string& path) const {
    if (n.IsScalar() && n.as<std::string>() == "model-weights") return 1;
    if (n.IsScalar() && n.as<std::string>() == "contribution") return 2;
    const double w = n.IsScalar() && (n.as<std::string>() == "1" || n.as<std::string>() == "2") ? number(n, path) : 0;
    if (w != 1 && w != 2) fail(n, path, "must be model-weights (or 1: the model file's weights) or contribution (or 2)");
    return static_cast<int>(w);
  }
  bool flag(const YAML::Node& n, const std::string& path) const {
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(n, path, "must be true or false");
    }
  }
  std::vector<std::string> names(const YAML::Node& n, const std::string& path) const {
    if (!n.IsSequence() || n.size() == 0) fail(n, path, "must be a non-empty list of names");
    std::vector<std::string> out;
    for (std::size_t k = 0; k < n.size(); ++k) out.push_back(text(n[k], fmt::format("{}[{}]", path, k)));
    return out;
  }
  std::string optional_text(const YAML::Node& map, const std::string& key, const std::string& path) const {
    return map[key] ? text(map[key], path + "." + key) : std::string();
  }

  Criterion criterion(const YAML::Node& n, const std::string& path) const {
    keys(n, path, {"at_most", "at_least", "between", "near", "tolerance", "negative", "positive"});
    Criterion c;
    int kinds = 0;
    if (n["at_most"]) c = {Criterion::Kind::at_most, number(n["at_most"], path + ".at_most")}, ++kinds;
    if (n["at_least"]) c = {Criterion::Kind::at_least, number(n["at_least"], path + ".at_least")}, ++kinds;
    if (n["between"]) {
      const YAML::Node b = n["between"];
      if (!b.IsSequence() || b.size() != 2) fail(b, path + ".between", "must be a list [low, high]");
      c = {Criterion::Kind::between, number(b[0], path + ".between[0]"), number(b[1], path + ".between[1]")};
      if (c.a > c.b) fail(b, path + ".between", "low must not exceed high");
      ++kinds;
    }
    if (n["near"]) {
      if (!n["tolerance"]) fail(n, path, "'near' needs a 'tolerance'");
      c = {Criterion::Kind::near, number(n["near"], path + ".near"), number(n["tolerance"], path + ".tolerance")};
      if (c.b <= 0) fail(n["tolerance"], path + ".tolerance", "must be positive");
      ++kinds;
    } else if (n["tolerance"]) {
      fail(n["tolerance"], path + ".tolerance", "only goes with 'near'");
    }
    for (const char* sign : {"negative", "positive"}) {
      if (!n[sign]) continue;
      if (!flag(n[sign], path + "." + sign)) fail(n[sign], path + "." + sign, "must be true (leave it out otherwise)");
      c = {std::string(sign) == "negative" ? Criterion::Kind::negative : Criterion::Kind::positive};
      ++kinds;
    }
    if (kinds != 1) fail(n, path, "must give exactly one of at_most, at_least, between, near, negative, positive");
    return c;
  }

  Measure measure(const YAML::Node& n, const std::string& path) const {
    keys(n, path, {"quantity", "run", "of_run", "coordinate", "sweep", "integrator", "unit", "runs", "coordinates", "joints",
                   "params", "factor", "times_total_mass", "weighting"});
    Measure m;
    m.line = line(n);
    m.quantity = text(required(n, "quantity", path), path + ".quantity");
    const auto rule = std::find_if(rules().begin(), rules().end(), [&](const QuantityRule& r) { return r.name == m.quantity; });
    if (rule == rules().end()) {
      const std::string near = nearest(m.quantity, quantities());
      fail(n["quantity"], path + ".quantity",
           fmt::format("unknown quantity '{}'{}", m.quantity, near.empty() ? "" : fmt::format(" (did you mean '{}'?)", near)));
    }
    for (const auto& key : rule->required) required(n, key, path);
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      if (key == "quantity") continue;
      if (std::find(rule->required.begin(), rule->required.end(), key) == rule->required.end() &&
          std::find(rule->optional.begin(), rule->optional.end(), key) == rule->optional.end())
        fail(kv.first, path + "." + key, fmt::format("does not apply to quantity '{}'", m.quantity));
    }
    m.run = optional_text(n, "run", path);
    m.of_run = optional_text(n, "of_run", path);
    m.coordinate = optional_text(n, "coordinate", path);
    m.sweep = optional_text(n, "sweep", path);
    m.integrator = optional_text(n, "integrator", path);
    m.unit = optional_text(n, "unit", path);
    if (n["runs"]) m.runs = names(n["runs"], path + ".runs");
    if (n["coordinates"]) m.coordinates = names(n["coordinates"], path + ".coordinates");
    if (!m.coordinate.empty()) m.coordinates.insert(m.coordinates.begin(), m.coordinate);
    if (n["joints"]) m.joints = names(n["joints"], path + ".joints");
    if (n["params"]) m.params = names(n["params"], path + ".params");
    if (n["factor"]) m.factor = number(n["factor"], path + ".factor");
    if (n["times_total_mass"]) m.times_total_mass = flag(n["times_total_mass"], path + ".times_total_mass");
    if (n["weighting"]) m.weighting = weighting(n["weighting"], path + ".weighting");
    return m;
  }

  Test test(const YAML::Node& n, const std::string& path, ClaimKind kind) const {
    keys(n, path, {"measure", "criterion"});
    Test t{measure(required(n, "measure", path), path + ".measure"), std::nullopt};
    if (kind == ClaimKind::check) t.criterion = criterion(required(n, "criterion", path), path + ".criterion");
    else if (n["criterion"])
      fail(n["criterion"], path + ".criterion", "only a check has a criterion (inputs and observations are not checks)");
    return t;
  }

  using Sources = std::vector<std::pair<std::string, std::string>>;

  Claim claim(const YAML::Node& n, const std::string& path, const Sources& sources) const {
    keys(n, path, {"id", "kind", "claim", "source", "claimed", "measure", "criterion", "tests", "why"});
    Claim c;
    c.line = line(n);
    c.id = text(required(n, "id", path), path + ".id");
    const std::string kind = text(required(n, "kind", path), path + ".kind");
    if (kind == "check") c.kind = ClaimKind::check;
    else if (kind == "input") c.kind = ClaimKind::input;
    else if (kind == "observation") c.kind = ClaimKind::observation;
    else fail(n["kind"], path + ".kind", fmt::format("must be check, input or observation, got '{}'", kind));
    c.claim = text(required(n, "claim", path), path + ".claim");
    std::vector<std::string> names;
    for (const auto& [name, what] : sources) names.push_back(name);
    const YAML::Node source = required(n, "source", path);
    if (sources.empty()) fail(source, path + ".source", "cites a source, but the file names none: list them under `sources`");
    keys(source, path + ".source", names);
    for (const std::string& name : names)
      if (source[name]) c.source += (c.source.empty() ? "" : "; ") + name + " " + text(source[name], path + ".source." + name);
    if (c.source.empty())
      fail(source, path + ".source", fmt::format("must cite one of the sources ({}) with its section, figure or table", fmt::join(names, ", ")));
    const YAML::Node claimed = required(n, "claimed", path);
    keys(claimed, path + ".claimed", names);
    for (const std::string& name : names) c.claimed.push_back(claimed[name] ? text(claimed[name], path + ".claimed." + name) : "");
    if (std::all_of(c.claimed.begin(), c.claimed.end(), [](const std::string& v) { return v.empty(); }))
      fail(claimed, path + ".claimed", fmt::format("must give the value as a source states it ({})", fmt::join(names, ", ")));
    c.why = text(required(n, "why", path), path + ".why");
    if (n["tests"]) {
      if (n["measure"] || n["criterion"]) fail(n, path, "give either 'tests' or 'measure' (and 'criterion'), not both");
      const YAML::Node tests = n["tests"];
      if (!tests.IsSequence() || tests.size() == 0) fail(tests, path + ".tests", "must be a non-empty list");
      for (std::size_t k = 0; k < tests.size(); ++k) c.tests.push_back(test(tests[k], fmt::format("{}.tests[{}]", path, k), c.kind));
    } else {
      YAML::Node single;
      single["measure"] = required(n, "measure", path);
      if (n["criterion"]) single["criterion"] = n["criterion"];
      if (c.kind == ClaimKind::check && !n["criterion"]) fail(n, path, "a check needs a 'criterion'");
      if (c.kind != ClaimKind::check && n["criterion"])
        fail(n["criterion"], path + ".criterion", "only a check has a criterion (inputs and observations are not checks)");
      c.tests.push_back({measure(n["measure"], path + ".measure"),
                         n["criterion"] ? std::optional(criterion(n["criterion"], path + ".criterion")) : std::nullopt});
    }
    return c;
  }

  ReportSpec parse(const std::string& text_in) const {
    YAML::Node root;
    try {
      // Keys given twice, keys that are lists or maps, and deep nesting, each with its place,
      // before yaml-cpp builds nodes (which would keep one of two keys without a word).
      std::istringstream stream(text_in);
      YAML::Parser parser(stream);
      YamlKeyCheck check([&](const YAML::Mark& mark, const std::string& path, const std::string& reason) {
        throw Error(fmt::format("{}:{}: {}", file_, mark.line + 1, path.empty() ? "(top level)" : path), reason);
      });
      parser.HandleNextDocument(check);
      root = YAML::Load(text_in);
    } catch (const YAML::Exception& e) {
      throw Error(fmt::format("{}:{}", file_, e.mark.line + 1), e.msg.empty() ? std::string("not valid YAML") : e.msg);
    }
    ReportSpec s;
    s.file = file_;
    if (!root || root.IsNull()) return s;
    keys(root, "(top level)", {"title", "sources", "quick", "integrator_comparison", "sections", "reference_lines", "run_figures", "torque_figures",
                               "pose", "claims"});
    s.title = optional_text(root, "title", "");
    if (const YAML::Node q = root["quick"]) {
      keys(q, "quick", {"sweeps", "scenarios"});
      if (q["sweeps"]) s.quick_sweeps = names(q["sweeps"], "quick.sweeps");
      if (q["scenarios"]) s.quick_scenarios = names(q["scenarios"], "quick.scenarios");
    }
    if (const YAML::Node ic = root["integrator_comparison"]) {
      keys(ic, "integrator_comparison", {"scenarios", "reference_step", "coordinates", "note"});
      s.integrator_note = optional_text(ic, "note", "integrator_comparison");
      s.integrator_scenarios = names(required(ic, "scenarios", "integrator_comparison"), "integrator_comparison.scenarios");
      if (ic["coordinates"]) s.integrator_coordinates = names(ic["coordinates"], "integrator_comparison.coordinates");
      if (ic["reference_step"]) {
        s.reference_step = number(ic["reference_step"], "integrator_comparison.reference_step");
        if (s.reference_step <= 0 || s.reference_step > 1e-2)
          fail(ic["reference_step"], "integrator_comparison.reference_step", "must be in (0, 0.01] s");
      }
    }
    if (const YAML::Node src = root["sources"]) {
      if (!src.IsMap() || src.size() == 0) fail(src, "sources", "must be a map {name: what the source is}");
      if (src.size() > kMaxSources) fail(src, "sources", fmt::format("names {} sources; at most {} (a column each)", src.size(), kMaxSources));
      for (const auto& kv : src) {
        const std::string name = kv.first.as<std::string>();
        if (name.empty() || name.size() > 40 || name.find_first_not_of(kNameCharacters) != std::string::npos)
          fail(kv.first, "sources", fmt::format("'{}' is not a source's name: letters, digits, '_' and '-', at most 40", excerpt(name)));
        s.sources.emplace_back(name, text(kv.second, "sources." + name));
      }
    }
    if (const YAML::Node sec = root["sections"]) {
      keys(sec, "sections", {"ik", "nonholonomic", "kinematic", "dynamics", "forward"});
      for (const auto& kv : sec) s.section_titles[kv.first.as<std::string>()] = text(kv.second, "sections." + kv.first.as<std::string>());
    }
    if (const YAML::Node lines = root["reference_lines"]) {
      keys(lines, "reference_lines", {"ik_check_error", "wheel_residual"});
      for (const auto& kv : lines) {
        const std::string path = "reference_lines." + kv.first.as<std::string>();
        keys(kv.second, path, {"value", "label"});
        const double v = number(required(kv.second, "value", path), path + ".value");
        if (v <= 0) fail(kv.second["value"], path + ".value", "must be positive (the figures have log axes)");
        s.reference_lines[kv.first.as<std::string>()] = {v, text(required(kv.second, "label", path), path + ".label")};
      }
    }
    if (const YAML::Node figs = root["run_figures"]) {
      if (!figs.IsSequence()) fail(figs, "run_figures", "must be a list");
      for (std::size_t k = 0; k < figs.size(); ++k) {
        const std::string path = fmt::format("run_figures[{}]", k);
        keys(figs[k], path, {"id", "runs", "x", "y", "reference"});
        RunFigure f;
        f.line = line(figs[k]);
        f.id = text(required(figs[k], "id", path), path + ".id");
        f.runs = names(required(figs[k], "runs", path), path + ".runs");
        f.x = text(required(figs[k], "x", path), path + ".x");
        f.y = names(required(figs[k], "y", path), path + ".y");
        f.reference = optional_text(figs[k], "reference", path);
        s.run_figures.push_back(f);
      }
    }
    if (const YAML::Node tf = root["torque_figures"]) {
      keys(tf, "torque_figures", {"panels", "references"});
      const YAML::Node panels = required(tf, "panels", "torque_figures");
      if (!panels.IsSequence() || panels.size() == 0) fail(panels, "torque_figures.panels", "must be a non-empty list of lists");
      for (std::size_t k = 0; k < panels.size(); ++k) s.torque_panels.push_back(names(panels[k], fmt::format("torque_figures.panels[{}]", k)));
      if (const YAML::Node refs = tf["references"]) {
        if (!refs.IsSequence()) fail(refs, "torque_figures.references", "must be a list");
        for (std::size_t k = 0; k < refs.size(); ++k) {
          const std::string path = fmt::format("torque_figures.references[{}]", k);
          keys(refs[k], path, {"scenario", "weighting", "figures"});
          TorqueReference r;
          r.line = line(refs[k]);
          r.scenario = text(required(refs[k], "scenario", path), path + ".scenario");
          r.weighting = weighting(required(refs[k], "weighting", path), path + ".weighting");
          r.figures = names(required(refs[k], "figures", path), path + ".figures");
          if (r.figures.size() != s.torque_panels.size())
            fail(refs[k]["figures"], path + ".figures", fmt::format("must name one figure per panel ({})", s.torque_panels.size()));
          s.torque_references.push_back(r);
        }
      }
    }
    if (const YAML::Node pose = root["pose"]) {
      keys(pose, "pose", {"body_frame", "outline"});
      s.pose_line = line(pose);
      s.pose_frame = text(required(pose, "body_frame", "pose"), "pose.body_frame");
      if (pose["outline"]) {
        s.pose_outline = names(pose["outline"], "pose.outline");
        if (s.pose_outline.size() != 2) fail(pose["outline"], "pose.outline", "must name two parameters: the length along x and the width along y");
      }
    }
    if (const YAML::Node claims = root["claims"]) {
      if (!claims.IsSequence()) fail(claims, "claims", "must be a list");
      std::set<std::string> ids;
      for (std::size_t k = 0; k < claims.size(); ++k) {
        Claim c = claim(claims[k], fmt::format("claims[{}]", k), s.sources);
        if (!ids.insert(c.id).second) fail(claims[k]["id"], fmt::format("claims[{}].id", k), fmt::format("'{}' is given twice", c.id));
        s.claims.push_back(std::move(c));
      }
    }
    return s;
  }

 private:
  std::string file_;
};

std::string number_text(double v) { return fmt::format("{:g}", v); }

}  // namespace

const std::vector<std::string>& quantities() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const auto& r : rules()) out.push_back(r.name);
    return out;
  }();
  return names;
}

bool Criterion::passes(double v) const {
  if (!std::isfinite(v)) return false;
  switch (kind) {
    case Kind::at_most: return v <= a;
    case Kind::at_least: return v >= a;
    case Kind::between: return v >= a && v <= b;
    case Kind::near: return std::abs(v - a) <= b;
    case Kind::negative: return v < 0;
    case Kind::positive: return v > 0;
  }
  return false;
}

std::string Criterion::describe(const std::string& unit) const {
  const std::string u = unit.empty() ? "" : " " + unit;
  switch (kind) {
    case Kind::at_most: return fmt::format("\u2264 {}{}", number_text(a), u);
    case Kind::at_least: return fmt::format("\u2265 {}{}", number_text(a), u);
    case Kind::between: return fmt::format("in [{}, {}]{}", number_text(a), number_text(b), u);
    case Kind::near: {
      // Very small or large values with a common exponent, "(6.0 ± 0.5)e-04", so the two compare at a glance.
      if (a == 0 || (std::abs(a) >= 1e-3 && std::abs(a) < 1e6)) return fmt::format("{} \u00b1 {}{}", number_text(a), number_text(b), u);
      const int exponent = static_cast<int>(std::floor(std::log10(std::abs(a))));
      const double scale = std::pow(10.0, exponent);
      const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(b / scale))));
      return fmt::format("({:.{}f} \u00b1 {:.{}f})e{:+03d}{}", a / scale, decimals, b / scale, decimals, exponent, u);
    }
    case Kind::negative: return "< 0";
    case Kind::positive: return "> 0";
  }
  return "?";
}

ReportSpec parse_report_spec(const std::string& text, const std::string& file) { return Parser(file).parse(text); }

std::string where(const ReportSpec& spec, int line, const std::string& path) {
  return fmt::format("{}:{}: {}", spec.file, line, path);
}

}  // namespace wlx::cli::report
