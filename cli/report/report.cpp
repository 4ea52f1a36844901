// `wlx report`'s page for any model (report/report.hpp): the claims checked against the model's
// measurements, the tables of its runs, the figures and the 3D viewer, from what the model's side
// computed (report/results.hpp). Compiled once, into wlx itself.
#include "report/report.hpp"

#include "interrupt.hpp"
#include "output_checks.hpp"
#include "report/figures.hpp"
#include "report/html.hpp"
#include "viewer_export.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <wlx/error.hpp>
#include <wlx/support/atomic_file.hpp>
#include <wlx/support/diagnostics.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>

namespace wlx::cli::report {

std::string Stop::describe() const { return fmt::format("stopped at t = {:.4f} s: {}", time, reason); }

int ModelTables::coordinate_index(std::string_view name) const {
  const auto it = std::find(coordinates.begin(), coordinates.end(), name);
  return it == coordinates.end() ? -1 : static_cast<int>(it - coordinates.begin());
}

int ModelTables::frame_index(std::string_view name) const {
  const auto it = std::find(frames.begin(), frames.end(), name);
  return it == frames.end() ? -1 : static_cast<int>(it - frames.begin());
}

const RunResult* Results::find_run(const std::string& id) const {
  for (const auto& r : runs)
    if (r.id == id) return &r;
  return nullptr;
}

namespace {

namespace fs = std::filesystem;

// Small and large values to 3 significant digits, others to 6; more where a "near" criterion's
// tolerance needs them to be seen.
std::string format_value(const Measured& m, const std::optional<Criterion>& c) {
  const std::string unit = m.unit.empty() ? "" : " " + m.unit;
  if (!std::isfinite(m.value)) return "none" + unit;
  const double a = std::abs(m.value);
  const bool scientific = a != 0 && (a < 1e-3 || a >= 1e6);
  int digits = scientific ? 3 : 6;
  if (c && c->kind == Criterion::Kind::near && c->a != 0)
    digits = std::clamp(static_cast<int>(std::ceil(std::log10(std::abs(c->a) / c->b))) + 2, digits, 15);
  if (scientific) return fmt::format("{:.{}e}{}", m.value, digits - 1, unit);
  return fmt::format("{:.{}g}{}", m.value, digits, unit);
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return text;
}

class Report {
 public:
  Report(ModelReport& model, const ReportSpec& spec, const ModelOptions& model_options, const ReportOptions& options)
      : model_options_(model_options), options_(options), root_(options.out_dir), spec_(spec), model_(model),
        tables_(model.tables()), results_(model.results()) {}

  int run();

 private:
  void progress(const std::string& what) {
    ++step_;
    throw_if_interrupted();
    fmt::print("[{:>2}/{}] {}\n", step_, total_steps_, what);
    std::fflush(stdout);
  }
  void evaluate_claims(Document& d);
  Document document(const ReportFigures& figures);
  std::vector<Section> sections(const ReportFigures& figures) const;
  std::string section_title(const std::string& key, const std::string& fallback) const;
  Section ik_section(const ReportFigures& figures) const;
  template <typename Keep>
  Table runs_table(Keep keep) const;
  Table integrators_table() const;
  Section contacts_section() const;
  Section forward_section(const ReportFigures& figures) const;
  Section engine_section(const ReportFigures& figures) const;

  void write_viewer();
  // The run's page in the 3D viewer, relative to index.html; empty without the viewer.
  std::string viewer_link(const std::string& run_id) const;

  const ModelOptions& model_options_;
  ReportOptions options_;
  std::string viewer_missing_;  // why the report has no 3D viewer (empty: it has one)
  fs::path root_;
  const ReportSpec& spec_;
  ModelReport& model_;
  const ModelTables& tables_;
  const Results& results_;  // filled by model_.run_all()
  int step_ = 0, total_steps_ = 0;
};

void Report::evaluate_claims(Document& d) {
  for (const auto& c : spec_.claims) {
    ClaimRow row{c.id, c.claim, c.source, c.why, c.claimed, {}, {}, ClaimRow::Result::none};
    bool pass = true, measured = true;
    for (const auto& t : c.tests) {
      const std::optional<Measured> m = model_.measure(t.measure);
      if (!m) {
        measured = false;
        break;
      }
      if (!m->stopped.empty()) {  // a run it depends on stopped: no value, and a check fails
        row.measured.push_back("not measured: " + m->stopped);
        if (t.criterion) row.criteria.push_back(t.criterion->describe(m->unit));
        pass = false;
        continue;
      }
      row.measured.push_back(format_value(*m, t.criterion));
      if (t.criterion) {
        row.criteria.push_back(t.criterion->describe(m->unit));
        pass = pass && t.criterion->passes(m->value);
      }
    }
    if (!measured) {
      ++d.skipped_claims;
      continue;
    }
    switch (c.kind) {
      case ClaimKind::check:
        row.result = pass ? ClaimRow::Result::pass : ClaimRow::Result::fail;
        d.checks.push_back(row);
        break;
      case ClaimKind::input: d.inputs.push_back(row); break;
      case ClaimKind::observation: d.observations.push_back(row); break;
    }
  }
}

std::string Report::section_title(const std::string& key, const std::string& fallback) const {
  const auto it = spec_.section_titles.find(key);
  return it == spec_.section_titles.end() ? fallback : it->second;
}

Section Report::ik_section(const ReportFigures& figures) const {
  Table t{{"sweep", "input", "points", "max check, closed form (m)", "max check, Newton (m)", "max |closed form - Newton| (rad)",
                   "Newton iterations (mean / max)", "joints' limits (branch)", "CSV"},
                  {}};
  // A limb without a closed form: Newton's method alone, nothing to check or compare (ik_verification.hpp).
  const auto closed_form_cell = [](const SweepResult& s, double v) {
    return s.closed_form ? fmt::format("{:.2e}", v) : std::string("no closed form");
  };
  for (const auto& s : results_.sweeps)
    t.rows.push_back({{s.id},
                      {s.input},
                      {std::to_string(s.inputs.size())},
                      {closed_form_cell(s, s.max_check_closed_form)},
                      {fmt::format("{:.2e}", s.max_check_newton)},
                      {closed_form_cell(s, s.max_newton_difference)},
                      {fmt::format("{:.2f} / {}", s.mean_newton_iterations, s.max_newton_iterations)},
                      {s.outside_limits == 0 ? fmt::format("within ({})", s.branch)
                                             : fmt::format("{} points outside ({}), first {}", s.outside_limits, s.branch, s.first_outside)},
                      {s.id + ".csv", "data/" + s.id + ".csv"}});
  return {"ik", section_title("ik", "Inverse kinematics sweeps"), "", {t}, figures.ik, {}};
}

// The runs `keep` selects, a row each. A model without a clearance box has no clearance column.
template <typename Keep>
Table Report::runs_table(Keep keep) const {
  Table t{{"run", "description", "samples", "result", "max |v_W . n_W| (m/s)", "max cond(J_beta)"}, {}};
  if (tables_.has_clearance) t.header.emplace_back("min clearance (m)");
  t.header.insert(t.header.end(), {"CSV", "3D"});
  for (const auto& r : results_.runs) {
    if (!keep(r)) continue;
    const bool any = r.samples > 0;  // a run stopped at its first step has no maxima
    std::vector<Cell> row{{r.id}, {r.description}, {std::to_string(r.samples)}, {r.stopped ? r.stopped->describe() : "complete"},
                          {any ? fmt::format("{:.2e}", r.worst_rolling_residual) : "-"},
                          {any ? fmt::format("{:.3g}", r.worst_cond) : "-"}};
    if (tables_.has_clearance) row.push_back({any ? fmt::format("{:.4f}", r.min_clearance) : "-"});
    row.push_back({r.csv, "data/" + r.csv});
    row.push_back(viewer_missing_.empty() && any ? Cell{"animate", viewer_link(r.id)} : Cell{"-"});
    t.rows.push_back(row);
  }
  return t;
}

Table Report::integrators_table() const {
  std::vector<std::string> header{"run", "integrator", "setting", "samples", "evaluations", "max |q - q_ref| (m or rad)"};
  for (int c : results_.compared)
    header.push_back(fmt::format("max |{} - ref| ({})", tables_.coordinates[static_cast<std::size_t>(c)], tables_.unit(c)));
  header.push_back("CSV");
  Table t{header, {}};
  for (const auto& r : results_.integrators) {
    std::vector<Cell> row{{r.id}, {r.integrator},
                                  {r.setting}, {std::to_string(r.samples)}, {std::to_string(r.evaluations)}, {fmt::format("{:.2e}", r.inputs)}};
    for (std::size_t k = 0; k < r.coordinates.size(); ++k)
      row.push_back({fmt::format("{:.2e}", r.coordinates[k] * tables_.scale(results_.compared[k]))});
    row.push_back({"integrators.csv", "data/integrators.csv"});
    t.rows.push_back(row);
  }
  return t;
}

bool is_dynamics_run(const RunResult& r) { return !r.nonholonomic_verification && r.weighting > 0; }

// Will it tip, will it slip: each dynamics run's smallest margins under each weighting, side by side.
Section Report::contacts_section() const {
  Table t{{"run", "weighting", "smallest normal force (N)", "smallest friction margin (N)", "first slip",
                   "first lift-off", "smallest tip-over margin (deg)", "max momentum residual"},
                  {}};
  const auto contact_name = [&](int c) { return tables_.contacts.at(static_cast<std::size_t>(c)); };
  const auto lowest = [&](const Lowest& l) {
    return fmt::format("{:.6g} ({} at {:.3f} s)", l.value, l.contact >= 0 ? contact_name(l.contact) : "-", l.t);
  };
  const auto first = [&](int contact, double t) {
    return contact >= 0 ? fmt::format("{} at {:.3f} s", contact_name(contact), t) : std::string("none");
  };
  for (const auto& r : results_.runs) {
    if (!is_dynamics_run(r) || r.samples == 0) continue;
    const RunResult& st = r;
    t.rows.push_back({{r.id},
                      {r.weighting_label},
                      {lowest(st.normal)},
                      {lowest(st.friction)},
                      {first(st.first_slip, st.slip_t)},
                      {first(st.first_pull, st.pull_t)},
                      {st.tip.contact >= 0 && st.tip.other >= 0
                           ? fmt::format("{:.4g} (edge {}-{})", st.tip.value * kDegPerRad, contact_name(st.tip.contact),
                                         contact_name(st.tip.other))
                           : std::string("-")},
                      {fmt::format("{:.1e}", st.worst_momentum)}});
  }
  return {"contacts", section_title("contacts", "Contacts: will it tip, will it slip"),
          "The force the ground exerts at each contact, from the equations of motion for the torques applied (the "
          "multipliers of the closure and rolling rows), for each inverse-dynamics run under the model file's weighting "
          "(1), weighting by contribution (2) and the weighting that keeps the machine on its contacts (3: the largest "
          "smallest margin of normal forces and friction at each step, within the torque limits). A negative normal "
          "force would pull on the ground "
          "(the contact lifts off), a negative friction margin slides; the tip-over margin is the force-angle measure "
          "about the support polygon's edges. The momentum residual checks the forces against the bodies' "
          "accelerations. The per-sample forces and margins are in each run's CSV.",
          {t}, {}, {}};
}

Section Report::forward_section(const ReportFigures& figures) const {
  Table trips{{"run", "result", "samples", "evaluations", "max |s_forward - s_inverse| (m or rad)", "max |E - E0 - W| (J)",
                       "relative to max |W|", "CSV"},
                      {}};
  Table loops{{"run", "result", "tracking error at t = 0 (m or rad)", "max tracking error, second half (m or rad)", "CSV"}, {}};
  for (const auto& r : results_.forward) {
    if (r.not_run) {  // its inverse-dynamics run stopped: neither simulation has a motion to follow
      const std::string why = fmt::format("not run: {} {}", r.id, r.not_run->describe());
      trips.rows.push_back({{r.id}, {why}, {"-"}, {"-"}, {"-"}, {"-"}, {"-"}, {"-"}});
      loops.rows.push_back({{r.id}, {why}, {"-"}, {"-"}, {"-"}});
      continue;
    }
    const bool trip = r.samples > 0, loop = r.closed_loop_samples > 0;  // no sample: no maxima
    trips.rows.push_back({{r.id}, {r.round_trip_stopped ? r.round_trip_stopped->describe() : "complete"}, {std::to_string(r.samples)},
                          {std::to_string(r.evaluations)}, {trip ? fmt::format("{:.2e}", r.round_trip) : "-"},
                          {trip ? fmt::format("{:.2e}", r.energy_balance) : "-"},
                          {trip ? fmt::format("{:.1e}", r.energy_balance / std::max(r.work, 1.0)) : "-"}, {r.csv, "data/" + r.csv}});
    loops.rows.push_back({{r.id}, {r.closed_loop_stopped ? r.closed_loop_stopped->describe() : "complete"},
                          {loop ? fmt::format("{:.2e}", r.start_error) : "-"},
                          {r.closed_loop_stopped ? std::string("-") : fmt::format("{:.2e}", r.late_error)},
                          {r.closed_loop_csv, "data/" + r.closed_loop_csv}});
  }
  Section s{"forward", section_title("forward", "Forward dynamics"),
                    "The machine moved by its actuators: from the torques and the state, forward_dynamics solves the reduced "
                    "equations of motion M(s) u' = J_beta^T tau - b(s, u) - Q_gravity(s) for the accelerations of the commanded "
                    "speeds u; the closure is re-solved by the closed-form IK at every evaluation and the rolling rows hold at "
                    "velocity level, so neither can drift. Round trip: each inverse-dynamics run's torques, cubic between its "
                    "samples, drive the machine from the run's start (dopri5 at " +
                        fmt::format("{:.0e}", kRoundTripTolerance) +
                        "); the deviation from the run and the energy balance (kinetic + potential energy against the "
                        "actuators' work, trapezoid rule on the samples) are shown.",
                    {trips}, figures.forward, {}};
  s.subsections.push_back(
      {"closed-loop", "A controller in the loop",
       fmt::format("Computed torque on the model (its inverse dynamics, the run's weighting) with PD feedback on the commanded "
                   "coordinates (Kp {:g} 1/s^2, Kd {:g} 1/s) tracks each run on a plant that is not the model: every body's mass "
                   "and inertia x{:g}, and a start {:g} mm or {:g} deg off in every commanded coordinate. The controller reads the "
                   "plant's coordinates and speeds and is evaluated continuously (at every stage of RK4 at the run's step); the "
                   "reference is the run's motion, cubic Hermite between its samples. What is left after the start has decayed is "
                   "the plant's extra weight, which the model does not know.",
                   kTrackingKp, kTrackingKd, kPlantMassFactor, kStartOffsetLength * 1e3, kStartOffsetAngle * kDegPerRad),
       {loops}, figures.closed_loop, {}});
  return s;
}

std::vector<Section> Report::sections(const ReportFigures& figures) const {
  std::vector<Section> out;
  if (!results_.sweeps.empty()) out.push_back(ik_section(figures));
  const auto is_nh = [](const RunResult& r) { return r.nonholonomic_verification; };
  const auto is_kinematic = [](const RunResult& r) { return !r.nonholonomic_verification && r.weighting == 0; };
  const auto any = [&](auto keep) { return std::any_of(results_.runs.begin(), results_.runs.end(), keep); };
  if (any(is_nh))
    out.push_back({"nonholonomic", section_title("nonholonomic", "Wheel constraint runs"), "", {runs_table(is_nh)}, figures.nonholonomic, {}});
  if (any(is_kinematic)) {
    Section s{"kinematic", section_title("kinematic", "Kinematic runs"), "", {runs_table(is_kinematic)}, figures.kinematic, {}};
    if (!results_.integrators.empty())
      s.subsections.push_back({"integrators", "Integrators compared",
                               fmt::format("Each run integrated three ways and compared at its samples with RK4 at {:g} s: "
                                           "explicit Euler and RK4 (wlx's default) at the run's step, and dopri5 (adaptive "
                                           "Dormand-Prince 5(4)), which writes 10 samples per run and chooses its steps in between. "
                                           "An evaluation is one closed-form IK of every limb plus a dependent-rate solve. {}",
                                           spec_.reference_step, spec_.integrator_note),
                               {integrators_table()}, {}, {}});
    out.push_back(s);
  }
  if (any(is_dynamics_run)) {
    out.push_back({"dynamics", section_title("dynamics", "Inverse dynamics"), "", {runs_table(is_dynamics_run)}, figures.dynamics, {}});
    if (!tables_.contacts.empty()) out.push_back(contacts_section());
  }
  if (!results_.forward.empty()) out.push_back(forward_section(figures));
  if (any(is_dynamics_run)) out.push_back(engine_section(figures));
  if (!figures.poses.empty()) out.push_back({"poses", "Poses at the start and the end of each run", "", {}, figures.poses, {}});
  return out;
}

Section Report::engine_section(const ReportFigures& figures) const {
  Section s{"engine", "In a physics engine", "", {}, figures.engine, {}};
  if (!results_.engine_missing.empty()) {
    s.intro = "Not run: " + results_.engine_missing + ".";
    return s;
  }
  s.intro = fmt::format(
      "The machine exported as `wlx export mjcf` writes it, in MuJoCo: its wheels roll by friction on soft contacts and may "
      "slip or lift, where the model holds them exactly. The controller of \"A controller in the loop\" (computed torque on the "
      "model, the model file's weighting, Kp {:g} 1/s^2, Kd {:g} 1/s) reads MuJoCo's state in the model's coordinates and drives "
      "its motors at every MuJoCo step (1 ms), along each inverse-dynamics run from the run's start and speeds (each wheel "
      "spinning as it rolls). Slip is the speed of a contact's material point on the ground; the normal forces are compared "
      "with the model's for the same torques (contact_forces). Slip and forces are taken after the first {:g} s, while the "
      "contacts press in. A run stops where the machine is {:g} m or {:g} deg off its reference, or where the model's IK cannot "
      "place MuJoCo's state: a finding about the controller on MuJoCo's machine, which is not the model, so it does not fail "
      "the report.",
      kTrackingKp, kTrackingKd, kEngineSettle, kEngineLostLength, kEngineLostAngle * kDegPerRad);
  Table t{{"run", "result", "samples (1 ms)", "max tracking error (mm / deg)", "second half (mm / deg)", "slip, mean / max (mm/s)",
                   "|normal force difference| / weight, mean / max", "CSV"},
                  {}};
  for (const EngineRow& r : results_.engine)
    t.rows.push_back({{r.id},
                      {r.stopped ? r.stopped->describe() : "complete"},
                      {std::to_string(r.samples)},
                      {fmt::format("{:.3g} / {:.3g}", 1e3 * r.length_error, kDegPerRad * r.angle_error)},
                      {fmt::format("{:.3g} / {:.3g}", 1e3 * r.late_length_error, kDegPerRad * r.late_angle_error)},
                      {fmt::format("{:.3g} / {:.3g}", 1e3 * r.mean_slip, 1e3 * r.max_slip)},
                      {fmt::format("{:.2e} / {:.2e}", r.mean_force_difference, r.max_force_difference)},
                      {r.csv, "data/" + r.csv}});
  s.tables.push_back(t);
  return s;
}

Document Report::document(const ReportFigures& figures) {
  Document d;
  d.title = spec_.title.empty() ? tables_.name + ": " + tables_.description : spec_.title;
  d.claims_source = spec_.claims.empty() ? "" : spec_.file;
  d.sources = spec_.sources;
  d.about = {{"wlx version", options_.version},
             {"model", fmt::format("{} ({})", tables_.name, tables_.description)},
             {"parameters", model_options_.params_file.empty() ? "the model file's defaults" : "overridden by " + model_options_.params_file},
             {"date", utc_now()},
             {"command line", options_.command_line},
             {"runs", options_.quick ? "--quick: a reduced set" : "all"},
             {"3D viewer", viewer_missing_.empty() ? "viewer/viewer.html: every run animated (the \"3D\" column), the "
                                                     "machine dragged with the closed-form IK"
                                                   : "not included: " + viewer_missing_}};
  d.parameters.header = {"parameter", "value", "unit", "meaning"};
  for (const auto& p : tables_.parameters)
    d.parameters.rows.push_back({{p.name}, {fmt::format("{:.10g}", p.value)}, {p.unit}, {p.meaning}});
  evaluate_claims(d);
  d.stopped_runs.header = {"run", "stopped at t (s)", "reason"};
  for (const StoppedRun& r : results_.stopped)
    d.stopped_runs.rows.push_back({{r.label()}, {fmt::format("{:.4f}", r.stop.time)}, {r.stop.reason}});
  d.sections = sections(figures);
  return d;
}

void Report::write_viewer() {
  if (!model_options_.params_file.empty()) {
    viewer_missing_ = "the viewer draws the model's default parameters, and --params changes them";
    return;
  }
  const fs::path dir = root_ / "viewer";
  std::error_code ec;  // an earlier report's runs would stay listed in the page's index
  fs::remove_all(dir / "runs", ec);
  if (ec) throw OutputError((dir / "runs").string(), fmt::format("cannot remove the earlier report's ({})", ec.message()));
  try {
    copy_viewer_files(dir);
  } catch (const Error& e) {  // built without emscripten: the report stands without its viewer
    viewer_missing_ = e.what();
    return;
  }
  model_.write_viewer_runs(dir);
}

std::string Report::viewer_link(const std::string& run_id) const {
  std::string encoded;  // the ids' characters are A-Z a-z 0-9 . _ + -: only '+' needs encoding
  for (char c : run_id) encoded += c == '+' ? std::string("%2B") : std::string(1, c);
  return "viewer/viewer.html?run=" + encoded;
}

int Report::run() {
  const auto start = std::chrono::steady_clock::now();
  // An index.html from an earlier run would claim that this one is complete until it is.
  std::error_code ec;
  fs::remove(root_ / "index.html", ec);
  if (ec) throw OutputError((root_ / "index.html").string(), fmt::format("cannot remove the earlier report's ({})", ec.message()));
  prepare_out_dir("--out", (root_ / "data").string());
  prepare_out_dir("--out", (root_ / "fig").string());
  total_steps_ = model_.steps() + 3;
  model_.run_all((root_ / "data").string(), [this](const std::string& what) { progress(what); });
  progress("the 3D viewer: the page and every run's data");
  write_viewer();
  progress("measuring the claims and drawing the figures");
  const ReportFigures figures = make_figures(results_, tables_, spec_, (root_ / "data").string());
  Document doc = document(figures);
  std::vector<FigureSpec> all;  // the figures drawn; an omitted one is a sentence in the page
  for (const auto* group : {&figures.ik, &figures.nonholonomic, &figures.kinematic, &figures.dynamics, &figures.forward,
                            &figures.closed_loop, &figures.engine, &figures.poses})
    for (const auto& f : *group)
      if (!f.omitted()) all.push_back(f);
  progress(fmt::format("rendering {} figures with gnuplot (PNG and SVG)", all.size()));
  render(root_.string(), all);
  // Last of all the files: its presence says the report is complete.
  write_file_atomically((root_ / "index.html").string(), render_html(doc));
  std::size_t failed = 0;
  for (const auto& c : doc.checks) failed += c.result != ClaimRow::Result::pass;
  const auto& stopped = results_.stopped;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  fmt::print("\n{} of {} checks pass ({} inputs, {} observations shown apart); stopped simulations: {}; {} figures; {:.1f} s\nopen {}\n",
             doc.checks.size() - failed, doc.checks.size(), doc.inputs.size(), doc.observations.size(), stopped.size(), all.size(),
             seconds, fs::absolute(root_ / "index.html").string());
  for (const StoppedRun& r : stopped)
    wlx::diagnose("wlx: run stopped: {} at t = {:.4f} s: {}\n", r.label(), r.stop.time, r.stop.reason);
  for (const EngineRow& r : results_.engine)
    if (r.stopped) wlx::diagnose("wlx: in the physics engine, {} ended at t = {:.4f} s: {}\n", r.id, r.stopped->time, r.stopped->reason);
  for (const auto& c : doc.checks)
    if (c.result != ClaimRow::Result::pass) wlx::diagnose("wlx: check failed: {}: {}\n", c.id, c.claim);
  // A stopped run fails the report as a failed check does: the report stands, the result does not.
  return failed == 0 && stopped.empty() ? 0 : 1;
}

}  // namespace

int write_report(ModelReport& model, const ReportSpec& spec, const ModelOptions& model_options, const ReportOptions& options) {
  Report report(model, spec, model_options, options);
  prepare_out_dir("--out", options.out_dir);
  try {
    return report.run();
  } catch (const Interrupted& e) {
    std::fflush(stdout);
    wlx::diagnose("wlx: {}: the report in {} is partial: no index.html was written; the files in data/ and fig/ "
                  "that exist are complete\n", e.what(), options.out_dir);
    return e.exit_code();
  }
}

}  // namespace wlx::cli::report
