// `wlx report` for this model: its report file (report/spec.hpp: the claims as data, embedded
// from scenarios/<model>/report.yaml or given with --claims), its runs and measurements
// (report/runner.hpp), and the view of them that the page and the figures read
// (report/results.hpp). The page, the figures and the HTML are compiled once, into wlx itself
// (report/report.hpp); what is here names the model's generated tables.
#include "per_model.hpp"
#include "model_commands.hpp"
#include "bounded_input.hpp"
#include "limits.hpp"
#include "report/report.hpp"
#include "report/runner.hpp"
#include "report/spec.hpp"
#include "scenario_folder.hpp"

#include <fmt/format.h>
#include <wlx/contacts.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/support/bounded_file.hpp>

#include <algorithm>
#include <filesystem>

WLX_COMMANDS_BEGIN

extern const char* const kEmbeddedReportFile;  // scenarios/<model>/report.yaml, embedded by CMake

namespace {

namespace fs = std::filesystem;

report::ReportSpec load_spec(const std::string& claims_file) {
  // --scenarios DIR: its report.yaml, else a report of its runs (no claims); not the embedded
  // file, whose runs are not these.
  if (const ScenarioFolder* folder = scenario_folder(); claims_file.empty() && folder != nullptr)
    return report::parse_report_spec(folder->report_text, folder->report_text.empty() ? folder->dir + "/report.yaml" : folder->report_path);
  if (claims_file.empty())
    return report::parse_report_spec(kEmbeddedReportFile, fmt::format("scenarios/{}/report.yaml", gen::kModelName));
  // Bounded, regular files only (wlx/support/bounded_file.hpp): /dev/zero or a FIFO is an error, not a hang.
  const BoundedRead file = read_bounded_file(claims_file, kMaxReportFileBytes);
  if (!file.ok()) throw Error("--claims", fmt::format("{} {}", excerpt(claims_file), file.error));
  return report::parse_report_spec(file.text, claims_file);
}

template <class Names>
std::vector<std::string> strings(const Names& names) {
  return {names.begin(), names.end()};
}

report::ModelTables model_tables(const Params& params) {
  report::ModelTables t;
  t.name = std::string(gen::kModelName);
  t.description = std::string(gen::kModelDescription);
  t.coordinates = strings(gen::kCoordinateNames);
  t.coordinate_units = strings(gen::kCoordinateUnits);
  t.frames = strings(gen::kFrameNames);
  t.frame_parents.assign(gen::kFrameParent.begin(), gen::kFrameParent.end());
  t.wheels = strings(gen::kWheelNames);
  t.actuators = strings(kActuatorNames);
  for (int c = 0; c < kContactCount; ++c) t.contacts.push_back(contact_name(c));
  t.commanded.assign(kCommandedSpeeds.begin(), kCommandedSpeeds.end());
  t.has_clearance = gen::kHasClearance;
  for (const auto& info : gen::kParamInfo)
    t.parameters.push_back({std::string(info.name), params.*(info.member), std::string(info.unit), std::string(info.meaning)});
  return t;
}

report::SweepResult sweep_result(const IkSweepResult& s) {
  report::SweepResult r{s.sweep.id, s.sweep.input, s.sweep.degrees, s.closed_form, {}, {}, {},
                        s.max_check_closed_form, s.max_check_newton, s.max_newton_difference, s.mean_newton_iterations,
                        s.max_newton_iterations, s.branch, s.outside_limits, s.first_outside};
  for (const auto& p : s.points) r.inputs.push_back(p.value);
  const LimbBlock block = limb_block(s.sweep.limb);
  for (int j = 0; j < block.size; ++j) {
    const int c = block.joints[static_cast<std::size_t>(j)];
    r.joints.push_back(coordinate_name(c));
    r.joint_values.emplace_back();
    for (const auto& p : s.points) r.joint_values.back().push_back(s.solution(p)(c));
  }
  return r;
}

// The report's number of a weighting: 1 the model file's weights, 2 by contribution, 3 the contacts'.
int weighting_number(const Weighting& w) {
  return w.kind == Weighting::Kind::contribution ? 2 : w.kind == Weighting::Kind::contacts ? 3 : 1;
}

// One run's view: its summary, torques and contact extent, and (but for the runs of one motion
// under weightings 2 and 3, whose poses are weighting 1's) the machine at its first and last
// samples and the report file's body frame along it.
class RunViews {
 public:
  RunViews(const Model& model, const report::ReportSpec& spec) : model_(model), spec_(spec) {
    body_frame_ = spec.pose_frame.empty() ? 0 : frame_index(spec.pose_frame);
  }

  report::RunResult operator()(const ReportRun& run) {
    const RunSummary& st = run.summary;
    const auto& samples = run.trajectory.samples;
    report::RunResult r;
    r.id = run.id, r.scenario_id = run.scenario_id, r.description = run.scenario.description, r.csv = run.csv;
    r.nonholonomic_verification = run.nonholonomic_verification;
    if (run.scenario.weighting) r.weighting = weighting_number(*run.scenario.weighting), r.weighting_label = run.scenario.weighting->label();
    r.stopped = run.stopped;
    static_cast<cli::RunExtremes&>(r) = st;
    r.worst_rolling_residual = st.worst_rolling_residual(), r.largest_tau = st.largest_tau();
    if (run.scenario.weighting) {
      r.tau.assign(static_cast<std::size_t>(kActuatedCount), {});
      for (const Sample& smp : samples)
        for (int k = 0; k < kActuatedCount; ++k) r.tau[static_cast<std::size_t>(k)].push_back(smp.tau(k));
    }
    for (const Sample& smp : samples)
      for (int w = 0; w < kWheelCount; ++w) {
        r.contact_x0 = std::min(r.contact_x0, smp.contacts(2 * w)), r.contact_x1 = std::max(r.contact_x1, smp.contacts(2 * w));
        r.contact_y0 = std::min(r.contact_y0, smp.contacts(2 * w + 1)), r.contact_y1 = std::max(r.contact_y1, smp.contacts(2 * w + 1));
      }
    if (r.weighting <= 1 && !samples.empty()) {
      r.poses = {pose_at(samples.front().s), pose_at(samples.back().s)};
      for (const Sample& smp : samples) {
        forward_kinematics(model_, data_, smp.s);
        r.body_path.emplace_back(data_.frame_positions.col(body_frame_));
      }
    }
    return r;
  }

 private:
  report::Pose pose_at(const Coordinates& s) {
    forward_kinematics(model_, data_, s);
    report::Pose p;
    for (int f = 0; f < gen::kFrameCount; ++f) p.frames.emplace_back(data_.frame_positions.col(f));
    const Eigen::Matrix3d& R = data_.frame_rotations[static_cast<std::size_t>(body_frame_)];
    p.heading = R.col(0);
    if (spec_.pose_outline.size() == 2) {
      Params params = model_.params();
      const double length = *find_param(params, spec_.pose_outline[0]), width = *find_param(params, spec_.pose_outline[1]);
      for (auto [x, y] : {std::pair{1, 1}, std::pair{1, -1}, std::pair{-1, -1}, std::pair{-1, 1}, std::pair{1, 1}})
        p.outline.push_back(p.frames[static_cast<std::size_t>(body_frame_)] + R * Eigen::Vector3d(x * length / 2, y * width / 2, 0));
    }
    return p;
  }

  const Model& model_;
  Data data_;
  const report::ReportSpec& spec_;
  int body_frame_ = 0;
};

// This model's side of the report, for the page compiled once (report::write_report).
class ModelSide final : public report::ModelReport {
 public:
  ModelSide(const Params& params, const report::ReportSpec& spec, bool quick)
      : spec_(spec), tables_(model_tables(params)), runner_(params, spec, quick, [this](const std::string& what) {
          if (progress_) progress_(what);
        }) {
    runner_.validate();
  }

  const report::ModelTables& tables() const override { return tables_; }
  int steps() const override { return runner_.steps(); }
  void run_all(const std::string& data_dir, const Progress& progress) override {
    progress_ = progress;
    runner_.run_all(data_dir);
    report::Results& results = runner_.results();  // the runner's rows; the sweeps and runs added here
    for (const auto& s : runner_.sweeps()) results.sweeps.push_back(sweep_result(s));
    RunViews view(runner_.model(), spec_);
    for (const auto& r : runner_.runs()) results.runs.push_back(view(r));
  }
  const report::Results& results() const override { return runner_.results(); }
  std::optional<Measured> measure(const report::Measure& m) override { return runner_.measure(m); }
  void write_viewer_runs(const fs::path& dir) const override {
    for (const auto& r : runner_.runs()) {
      if (r.trajectory.samples.empty()) continue;  // stopped at its first step: nothing to animate (its "3D" cell says "-")
      const std::string weighting = r.scenario.weighting ? " (" + r.scenario.weighting->label() + ")" : "";
      write_viewer_run(dir, r.scenario, r.trajectory, r.id, r.scenario.description + weighting);
    }
  }

 private:
  const report::ReportSpec& spec_;
  report::ModelTables tables_;
  Progress progress_;
  ReportRunner runner_;
};

}  // namespace

int run_report(const ModelOptions& model_options, const ReportOptions& options) {
  const Params params = load_params(model_options);
  // The report file and its names first: a bad one exits 2 before any output.
  const report::ReportSpec spec = load_spec(options.claims_file);
  ModelSide side(params, spec, options.quick);
  return report::write_report(side, spec, model_options, options);
}

WLX_COMMANDS_END
