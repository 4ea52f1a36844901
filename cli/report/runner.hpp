// The computations of `wlx report` for one model: its IK sweeps, its scenarios (inverse-dynamics
// scenarios with both weightings), the integrator comparison of its report file, and the
// measurements its claims name. Compiled per model (cli/per_model.hpp); names of coordinates,
// runs and sweeps come from the report file and are looked up in the generated tables. The page
// and the figures, compiled once, read what it computed through report::ModelReport
// (report/results.hpp; commands/report_command.cpp makes that view).
#pragma once

#include "per_model.hpp"
#include "run_summary.hpp"
#include "report/results.hpp"
#include "report/spec.hpp"

#include <wlx/ik_verification.hpp>
#include <wlx/simulation.hpp>

#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

WLX_COMMANDS_BEGIN

// The model-independent parts of the report's results (report/results.hpp), here by their names.
using report::EngineRow;
using report::ForwardRow;
using report::IntegratorRow;
using report::kDegPerRad;
using report::Measured;
using report::Stop;
using report::StoppedRun;
// A coordinate's name in the model file.
inline std::string coordinate_name(int coordinate) {
  return std::string(gen::kCoordinateNames[static_cast<std::size_t>(coordinate)]);
}

struct ReportRun {
  std::string id;           // the scenario's id, "<id>-w1"/"<id>-w2" for inverse dynamics
  std::string scenario_id;  // the scenario file's id
  Scenario scenario;
  Trajectory trajectory;  // what it computed, up to where it stopped
  std::string csv;  // file name in data/
  bool nonholonomic_verification = false;  // the scenario is marked "verify": "nonholonomic"
  std::optional<Stop> stopped;  // set: the run ended before its duration
  // Its maxima and minima (run_summary.hpp), once: the tables', the claims' and the figures'.
  RunSummary summary;
};

class ReportRunner {
 public:
  using Progress = std::function<void(const std::string&)>;
  ReportRunner(const Params& params, const report::ReportSpec& spec, bool quick, Progress progress);

  // Throws wlx::Error naming the report file's line for a name that is not the model's.
  void validate() const;
  // How many progress steps run_all() reports.
  int steps() const;
  // Everything, writing the CSV files into data_dir.
  void run_all(const std::string& data_dir);

  // The value of a claim's measure, or nothing if it concerns a run or sweep this report did not make.
  std::optional<Measured> measure(const report::Measure& m);

  const std::vector<IkSweepResult>& sweeps() const { return sweeps_; }
  const std::vector<ReportRun>& runs() const { return runs_; }
  // What it made in the page's terms (report/results.hpp): the integrators compared, the forward
  // and physics-engine rows, why there is no engine, every simulation that stopped; the sweeps and
  // runs are left for the view to add (commands/report_command.cpp), which poses the machine.
  report::Results& results() { return results_; }
  const report::Results& results() const { return results_; }
  const Model& model() const { return model_; }
  Data& data() { return data_; }
  const ReportRun* find_run(const std::string& id) const;

 private:
  std::vector<const IkSweep*> selected_sweeps() const;
  std::vector<std::string> selected_scenarios() const;
  void compare_integrators(const std::string& data_dir);
  ForwardRow forward_dynamics_of(const ReportRun& run, const std::string& data_dir);
  EngineRow physics_engine_of(const ReportRun& run, const std::string& data_dir);
  // Records a stopped simulation; returns its Stop.
  Stop record_stop(const std::string& run, const std::string& part, const Trajectory& trajectory);
  // The first stop of one of these runs' simulations named in `parts` ("": the run itself; no
  // parts: any of them), or null.
  const StoppedRun* first_stop(const std::vector<std::string>& runs, const std::vector<std::string>& parts = {""}) const;

  const report::ReportSpec& spec_;
  bool quick_;
  Progress progress_;
  Model model_;
  Data data_;
  std::vector<IkSweepResult> sweeps_;
  std::vector<ReportRun> runs_;
  report::Results results_;
};

// The unit a coordinate is shown in ("deg" for angles, "m") and the factor from SI to it.
std::string display_unit(int coordinate);
double display_scale(int coordinate);

WLX_COMMANDS_END
