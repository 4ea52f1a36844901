// The report file parser (cli/report/spec.cpp): a valid file's contents, every kind of error with
// the file, line and key it names, and the criteria a check applies.
#include <doctest/doctest.h>

#include "report/spec.hpp"

#include <wlx/error.hpp>

#include <cmath>
#include <string>

using wlx::cli::report::ClaimKind;
using wlx::cli::report::Criterion;
using wlx::cli::report::parse_report_spec;

namespace {

// The message of the error parsing `text` throws, or "" if it parses.
std::string error_of(const std::string& text) {
  try {
    parse_report_spec(text, "claims.yaml");
  } catch (const wlx::Error& e) {
    return e.what();
  }
  return "";
}

// Sources of any names: a report file names its own documents.
const char* const kSources = "sources: {paper: the paper, spec: the specification}\n";
const char* const kClaim = R"(  - id: mass
    kind: check
    claim: the total mass
    source: {paper: Table 6-1}
    claimed: {paper: 6153.98 kg}
    measure: {quantity: total_mass}
    criterion: {near: 6153.98, tolerance: 0.005}
    why: quoted to 0.01 kg
)";
const std::string kCheck = std::string(kSources) + "claims:\n" + kClaim;

// kCheck with `from` replaced by `to` (the test fails if `from` is not in it).
std::string variant(const std::string& from, const std::string& to) {
  std::string text = kCheck;
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("report file: a valid file gives its claims, tests and layout") {
  const std::string text = std::string(R"(title: a machine
quick: {sweeps: [S1], scenarios: [R1]}
integrator_comparison: {scenarios: [R1], reference_step: 1.0e-4, coordinates: [a], note: text}
reference_lines: {ik_check_error: {value: 1.0e-5, label: "thesis"}}
run_figures:
  - {id: F, runs: [R1, R2], x: a, y: [b, c], reference: paper fig. 1}
torque_figures:
  panels: [[j1, j2], [j3]]
  references: [{scenario: R1, weighting: contribution, figures: [paper fig. 2, paper fig. 3]}]
pose: {body_frame: C, outline: [p1, p2]}
)") + kCheck + R"(  - id: signs
    kind: observation
    claim: both
    source: {spec: section 5}
    claimed: {spec: signs}
    tests:
      - measure: {quantity: end_value, run: R1, coordinate: a}
      - measure: {quantity: end_ratio, run: R1, of_run: R2, coordinate: b}
    why: because
)";
  const auto spec = parse_report_spec(text, "claims.yaml");
  CHECK(spec.title == "a machine");
  REQUIRE(spec.sources.size() == 2);  // in the file's order: the claims' columns
  CHECK(spec.sources[0] == std::pair<std::string, std::string>{"paper", "the paper"});
  CHECK(spec.sources[1] == std::pair<std::string, std::string>{"spec", "the specification"});
  CHECK(spec.run_figures.at(0).reference == "paper fig. 1");
  CHECK(spec.torque_references.at(0).figures.at(1) == "paper fig. 3");
  REQUIRE(spec.quick_sweeps.has_value());
  CHECK(spec.quick_sweeps->at(0) == "S1");
  CHECK(spec.integrator_coordinates.at(0) == "a");
  CHECK(spec.reference_lines.at("ik_check_error").value == 1e-5);
  CHECK(spec.run_figures.at(0).y.size() == 2);
  CHECK(spec.torque_panels.size() == 2);
  CHECK(spec.torque_references.at(0).weighting == 2);
  CHECK(spec.pose_outline.at(1) == "p2");
  REQUIRE(spec.claims.size() == 2);
  CHECK(spec.claims[0].kind == ClaimKind::check);
  CHECK(spec.claims[0].line == 13);  // after the 10 lines of layout, "sources:" and "claims:"
  CHECK(spec.claims[0].source == "paper Table 6-1");
  CHECK(spec.claims[0].claimed == std::vector<std::string>{"6153.98 kg", ""});
  CHECK(spec.claims[1].claimed == std::vector<std::string>{"", "signs"});
  REQUIRE(spec.claims[0].tests.at(0).criterion.has_value());
  CHECK(spec.claims[0].tests[0].criterion->kind == Criterion::Kind::near);
  CHECK(spec.claims[1].kind == ClaimKind::observation);
  CHECK(spec.claims[1].tests.size() == 2);
  CHECK(!spec.claims[1].tests[0].criterion.has_value());
  CHECK(spec.claims[1].tests[1].measure.of_run == "R2");
}

TEST_CASE("report file: an empty file is a model without claims") {
  const auto spec = parse_report_spec("", "claims.yaml");
  CHECK(spec.claims.empty());
  CHECK(spec.run_figures.empty());
}

TEST_CASE("report file: each error names the file, the line, the key and the reason") {
  // Malformed YAML: the parser's own reason at its line.
  CHECK(error_of("claims:\n  - id: [unclosed\n").find("claims.yaml:") == 0);
  // Unknown keys, with the nearest valid one.
  CHECK(error_of("titel: x\n") == "claims.yaml:1: (top level): unknown key 'titel' (did you mean 'title'?)");
  CHECK(error_of(variant("    why:", "    wyh:")).find("claims.yaml:10: claims[0]: unknown key 'wyh' (did you mean 'why'?)") == 0);
  // Missing keys.
  CHECK(error_of(variant("    why: quoted to 0.01 kg\n", "")) == "claims.yaml:3: claims[0]: missing key 'why'");
  CHECK(error_of(variant("    kind: check\n", "")) == "claims.yaml:3: claims[0]: missing key 'kind'");
  // Wrong values.
  CHECK(error_of(variant("kind: check", "kind: test")) ==
        "claims.yaml:4: claims[0].kind: must be check, input or observation, got 'test'");
  // Sources: the file's own names, cited and claimed by them.
  CHECK(error_of(variant("source: {paper: Table 6-1}", "source: {papr: Table 6-1}")) ==
        "claims.yaml:6: claims[0].source: unknown key 'papr' (did you mean 'paper'?)");
  CHECK(error_of(variant("source: {paper: Table 6-1}", "source: {}")) ==
        "claims.yaml:6: claims[0].source: must cite one of the sources (paper, spec) with its section, figure or table");
  CHECK(error_of(variant("    claimed: {paper: 6153.98 kg}\n", "")) == "claims.yaml:3: claims[0]: missing key 'claimed'");
  CHECK(error_of(variant("claimed: {paper: 6153.98 kg}", "claimed: {}")) ==
        "claims.yaml:7: claims[0].claimed: must give the value as a source states it (paper, spec)");
  CHECK(error_of(variant("claimed: {paper: 6153.98 kg}", "claimed: {spek: 6153.98 kg}")) ==
        "claims.yaml:7: claims[0].claimed: unknown key 'spek' (did you mean 'spec'?)");
  CHECK(error_of(std::string("claims:\n") + kClaim) ==
        "claims.yaml:5: claims[0].source: cites a source, but the file names none: list them under `sources`");
  CHECK(error_of("sources: {a b: x}\n") == "claims.yaml:1: sources: 'a b' is not a source's name: letters, digits, '_' and '-', at most 40");
  CHECK(error_of("sources: {a: 1, b: 2, c: 3, d: 4, e: 5, f: 6, g: 7}\n") == "claims.yaml:1: sources: names 7 sources; at most 6 (a column each)");
  CHECK(error_of("sources: [a]\n") == "claims.yaml:1: sources: must be a map {name: what the source is}");
  // Checks and their criteria.
  CHECK(error_of(variant("    criterion: {near: 6153.98, tolerance: 0.005}\n", "")) == "claims.yaml:3: claims[0]: a check needs a 'criterion'");
  CHECK(error_of(variant("kind: check", "kind: input")) ==
        "claims.yaml:9: claims[0].criterion: only a check has a criterion (inputs and observations are not checks)");
  CHECK(error_of(variant("{near: 6153.98, tolerance: 0.005}", "{near: 6153.98}")) ==
        "claims.yaml:9: claims[0].criterion: 'near' needs a 'tolerance'");
  CHECK(error_of(variant("tolerance: 0.005", "tolerance: 0")) == "claims.yaml:9: claims[0].criterion.tolerance: must be positive");
  CHECK(error_of(variant("tolerance: 0.005", "tolerance: small")) ==
        "claims.yaml:9: claims[0].criterion.tolerance: must be a number, got 'small'");
  CHECK(error_of(variant("{near: 6153.98, tolerance: 0.005}", "{at_most: 1, at_least: 0}")) ==
        "claims.yaml:9: claims[0].criterion: must give exactly one of at_most, at_least, between, near, negative, positive");
  CHECK(error_of(variant("{near: 6153.98, tolerance: 0.005}", "{between: [2, 1]}")) ==
        "claims.yaml:9: claims[0].criterion.between: low must not exceed high");
  CHECK(error_of(variant("{near: 6153.98, tolerance: 0.005}", "{negative: false}")) ==
        "claims.yaml:9: claims[0].criterion.negative: must be true (leave it out otherwise)");
  // Measures.
  CHECK(error_of(variant("quantity: total_mass", "quantity: total_mas")) ==
        "claims.yaml:8: claims[0].measure.quantity: unknown quantity 'total_mas' (did you mean 'total_mass'?)");
  CHECK(error_of(variant("quantity: total_mass", "quantity: end_value, run: R1")) ==
        "claims.yaml:8: claims[0].measure: missing key 'coordinate'");
  CHECK(error_of(variant("quantity: total_mass", "quantity: total_mass, run: R1")) ==
        "claims.yaml:8: claims[0].measure.run: does not apply to quantity 'total_mass'");
  CHECK(error_of(variant("quantity: total_mass", "quantity: static_torque, joints: [a], weighting: 3")) ==
        "claims.yaml:8: claims[0].measure.weighting: must be model-weights (or 1: the model file's weights) or contribution (or 2)");
  CHECK(error_of(variant("quantity: total_mass", "quantity: static_torque, joints: [a], weighting: contacts")) ==
        "claims.yaml:8: claims[0].measure.weighting: must be model-weights (or 1: the model file's weights) or contribution (or 2)");
  CHECK(error_of(variant("quantity: total_mass", "quantity: peak_torque, runs: []")) ==
        "claims.yaml:8: claims[0].measure.runs: must be a non-empty list of names");
  // Two claims with one id.
  const std::string twice = kCheck + kClaim;
  CHECK(error_of(twice) == "claims.yaml:11: claims[1].id: 'mass' is given twice");
  // The layout.
  CHECK(error_of("torque_figures:\n  panels: [[a], [b]]\n  references: [{scenario: R, weighting: 1, figures: [f]}]\n") ==
        "claims.yaml:3: torque_figures.references[0].figures: must name one figure per panel (2)");
  CHECK(error_of("pose: {body_frame: C, outline: [a]}\n") ==
        "claims.yaml:1: pose.outline: must name two parameters: the length along x and the width along y");
  CHECK(error_of("reference_lines: {wheel_residual: {value: -1, label: x}}\n") ==
        "claims.yaml:1: reference_lines.wheel_residual.value: must be positive (the figures have log axes)");
  CHECK(error_of("integrator_comparison: {scenarios: [R], reference_step: 1}\n") ==
        "claims.yaml:1: integrator_comparison.reference_step: must be in (0, 0.01] s");
  CHECK(error_of("run_figures: [{id: F, runs: [R], x: a}]\n") == "claims.yaml:1: run_figures[0]: missing key 'y'");
  // Keys given twice (yaml-cpp kept one without a word), keys that are lists or maps (they crashed
  // the reader: the fuzzer's tests/fuzz/regressions/report_file/crash-ea478c2d...), deep nesting.
  CHECK(error_of("title: a\ntitle: b\n") == "claims.yaml:2: title: given twice (first at line 1)");
  CHECK(error_of(variant("    kind: check\n", "    kind: check\n    kind: input\n")) == "claims.yaml:5: claims[0].kind: given twice (first at line 4)");
  CHECK(error_of("sources: {[a, b]: x}\n") == "claims.yaml:1: sources: a key is a list: keys are names");
  CHECK(error_of("claims: [{id: a, {quantity: x}: 1}]\n") == "claims.yaml:1: claims[0]: a key is a map: keys are names");
  CHECK(error_of(std::string(70, '[') + std::string(70, ']') + "\n").find("nest more than 64 levels deep") != std::string::npos);
  CHECK(error_of("title: \"[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[\"\n") == "");  // brackets in text are text
}

TEST_CASE("report file: a check fails when the measured value is outside its criterion") {
  const Criterion near{Criterion::Kind::near, 0.583, 0.0005};
  CHECK(near.passes(0.5833));
  CHECK(!near.passes(0.5836));
  CHECK(!near.passes(0.5824));
  const Criterion at_most{Criterion::Kind::at_most, 1e-10};
  CHECK(at_most.passes(1e-10));
  CHECK(!at_most.passes(1.1e-10));
  const Criterion at_least{Criterion::Kind::at_least, 2};
  CHECK(!at_least.passes(1.9));
  const Criterion between{Criterion::Kind::between, 2e-4, 1.5e-3};
  CHECK(between.passes(6e-4));
  CHECK(!between.passes(1.6e-3));
  CHECK(!Criterion{Criterion::Kind::negative}.passes(0));
  CHECK(!Criterion{Criterion::Kind::positive}.passes(-1e-300));
  // A value that could not be measured (NaN) never passes, whatever the rule.
  for (const Criterion& c : {near, at_most, at_least, between, Criterion{Criterion::Kind::negative}, Criterion{Criterion::Kind::positive}})
    CHECK(!c.passes(std::nan("")));
  // The criterion as the report states it.
  CHECK(near.describe("s") == "0.583 \u00b1 0.0005 s");
  CHECK((Criterion{Criterion::Kind::near, 6e-4, 0.5e-4}.describe("deg")) == "(6.0 \u00b1 0.5)e-04 deg");
  CHECK((Criterion{Criterion::Kind::near, 2.7e7, 0.05e7}.describe("")) == "(2.70 \u00b1 0.05)e+07");
  CHECK(at_most.describe("m") == "\u2264 1e-10 m");
  CHECK(Criterion{Criterion::Kind::negative}.describe("deg") == "< 0");
}
