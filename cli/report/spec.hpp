// A model's report file (scenarios/<model>/report.yaml): the claims its sources (a paper, a
// specification: any documents the file names) make, with their citations, how wlx measures each,
// and how the report groups runs into figures. Parsed here into names
// (strings); the per-model code resolves the names against the generated tables and the model's
// scenarios (report/resolve.hpp). Model-independent, so a model without a report file, or any
// model, uses the same parser. The format: scenarios/README.md, "Report files".
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace wlx::cli::report {

// The rule a measured value must meet, in the unit the report shows it in.
struct Criterion {
  enum class Kind { at_most, at_least, between, near, negative, positive };
  Kind kind = Kind::at_most;
  double a = 0, b = 0;  // at_most/at_least: a; between: [a, b]; near: a +- b
  bool passes(double value) const;
  // "≤ 1e-10", "≥ 1", "in [a, b]", "2.63 ± 0.005", "< 0", "> 0" (with the unit where it has one).
  std::string describe(const std::string& unit) const;
};

// What wlx measures for a claim. `quantity` is one of kQuantities; the other fields are the
// names it needs (which ones: kQuantities' documentation in spec.cpp).
struct Measure {
  std::string quantity;
  std::string run, of_run, coordinate, sweep, integrator, unit;
  std::vector<std::string> runs, coordinates, joints, params;
  double factor = 1;
  bool times_total_mass = false;
  int weighting = 1;
  int line = 0;  // in the report file, for messages
};

struct Test {
  Measure measure;
  std::optional<Criterion> criterion;  // checks only
};

enum class ClaimKind { check, input, observation };

struct Claim {
  std::string id;
  ClaimKind kind = ClaimKind::check;
  std::string claim;
  std::string source;  // the citations, "<source> <where>" joined by "; ": "paper section 3.4; spec section 5"
  std::vector<std::string> claimed;  // the value as each source states it (ReportSpec::sources' order; "" where it does not)
  std::string why;           // why the criterion, or where the value comes from
  std::vector<Test> tests;
  int line = 0;
};

struct RunFigure {
  std::string id, x;
  std::string reference;  // the sources' figure of the same, cited in the caption (may be empty)
  std::vector<std::string> runs, y;
  int line = 0;
};

struct TorqueReference {
  std::string scenario;
  int weighting = 1;
  std::vector<std::string> figures;  // one per panel
  int line = 0;
};

// A horizontal line in a figure: a value the sources quote (an error level they report, ...).
struct ReferenceLine {
  double value = 0;
  std::string label;
};

struct ReportSpec {
  std::string file;   // for messages: "scenarios/<model>/report.yaml" or the user's path
  std::string title;  // what the report is of, in words
  std::optional<std::vector<std::string>> quick_sweeps, quick_scenarios;  // unset: all
  std::vector<std::string> integrator_scenarios, integrator_coordinates;
  double reference_step = 1e-4;
  std::string integrator_note;  // what the sources say about the integrators (text), may be empty
  // Keyed by the figure they go into: ik_check_error (IK sweeps), wheel_residual (wheel constraint runs).
  std::map<std::string, ReferenceLine> reference_lines;
  std::map<std::string, std::string> section_titles;  // ik, nonholonomic, kinematic, dynamics
  // The documents the claims cite, in the file's order: a short name (a claim's `source` and
  // `claimed` keys, a column of the claims' tables) and what it is, for the reader.
  std::vector<std::pair<std::string, std::string>> sources;
  std::vector<RunFigure> run_figures;
  std::vector<std::vector<std::string>> torque_panels;
  std::vector<TorqueReference> torque_references;  // the sources' figures of the same torques
  std::string pose_frame;
  std::vector<std::string> pose_outline;  // two parameters: length along x, width along y
  int pose_line = 0;
  std::vector<Claim> claims;
};

// The quantities a measure may name.
const std::vector<std::string>& quantities();

// Parses a report file's text. Throws wlx::Error whose field is "<file>:<line>: <key path>" and
// whose reason says what is wrong (unknown key with "did you mean", missing key, wrong type, a
// value out of range).
ReportSpec parse_report_spec(const std::string& text, const std::string& file);

// "<file>:<line>: <path>": the field of an error about something the file names (used by the
// per-model resolution too).
std::string where(const ReportSpec& spec, int line, const std::string& path);

}  // namespace wlx::cli::report
