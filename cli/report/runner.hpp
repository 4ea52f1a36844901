// The computations of `wlx report` for one model: its IK sweeps, its scenarios (inverse-dynamics
// scenarios with both weightings), the integrator comparison of its report file, and the
// measurements its claims name. Compiled per model (cli/per_model.hpp); names of coordinates,
// runs and sweeps come from the report file and are looked up in the generated tables.
#pragma once

#include "per_model.hpp"
#include "run_summary.hpp"
#include "report/spec.hpp"

#include <wlx/ik_verification.hpp>
#include <wlx/simulation.hpp>

#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

WLX_COMMANDS_BEGIN

// Degrees per radian: the report's tables and figures show angles in degrees.
inline constexpr double kDegPerRad = 180 / std::numbers::pi;
// A coordinate's name in the model file.
inline std::string coordinate_name(int coordinate) {
  return std::string(gen::kCoordinateNames[static_cast<std::size_t>(coordinate)]);
}

// Where and why a simulation ended before its duration: the report shows it and goes on.
struct Stop {
  double time = 0;     // s, the step that stopped it; its samples end before
  std::string reason;  // the runtime's, naming the field or the limit
  // "stopped at t = 0.1230 s: <reason>"
  std::string describe() const;
};

// Every simulation of the report that stopped, in the order they ran: a scenario's run (`part`
// empty), or one made from it ("round trip", "closed loop", an integrator compared).
struct StoppedRun {
  std::string run;   // the report run's id ("<id>-w1", ...) or the scenario's
  std::string part;  // empty: the run itself
  Stop stop;
  std::string label() const { return part.empty() ? run : run + " (" + part + ")"; }
};

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

// One run integrated one way, against RK4 at the reference step.
struct IntegratorRow {
  std::string id;
  Integrator integrator;
  std::string setting;
  long samples = 0, evaluations = 0;
  double inputs = 0;                // max |q - q_ref| over the samples, m or rad
  std::vector<double> coordinates;  // max |s_c - ref| per compared coordinate
};

// The forward dynamics of one inverse-dynamics run (the report's "Forward dynamics" section): its
// torques fed back (the round trip), and a computed-torque controller on the model tracking the
// run on a plant whose bodies are heavier than the model's, from a start off the run's (the
// closed loop). Generic: the plant, the start and the gains are the same for every model.
struct ForwardRow {
  std::string id;   // the inverse-dynamics run's
  // Set: neither the round trip nor the closed loop ran, because the inverse-dynamics run stopped
  // (they follow its whole motion); its CSV files are not written.
  std::optional<Stop> not_run;
  std::string csv;             // data/<id>-forward.csv: t, round_trip_deviation, energy_balance
  std::string closed_loop_csv;  // data/<id>-closed-loop.csv: t, tracking_error, error_<commanded coordinate> ...
  long samples = 0, evaluations = 0;  // the round trip's
  double round_trip = 0;      // max |s_forward - s_inverse| over the samples and coordinates, m or rad
  double energy_balance = 0;  // max |E(t) - E(0) - W(t)| over the samples, J (W: the actuators' work, trapezoid rule)
  double work = 0;            // max |W(t)|, J: the scale of energy_balance
  std::optional<Stop> round_trip_stopped, closed_loop_stopped;  // set: that simulation ended early
  long closed_loop_samples = 0;
  double start_error = 0, late_error = 0;  // max |q_ref - q| over the commanded coordinates (m or rad): at t = 0, and over the second half
};
// The same controller on MuJoCo's machine (the report's "In a physics engine"): the model exported
// as `wlx export mjcf` writes it, its wheels rolling by friction on soft contacts, free to slip and
// lift, driven along an inverse-dynamics run at MuJoCo's step (1 kHz) from the run's start and
// speeds. The controller reads MuJoCo's state in the model's coordinates.
struct EngineRow {
  std::string id;   // the inverse-dynamics run's
  std::string csv;  // data/<id>-mujoco.csv: t, tracking errors, per contact slip and both normal forces
  // Set: the machine left its reference, or MuJoCo's state the model's reach or finite numbers.
  // Not one of the report's stopped simulations: MuJoCo's machine is not the model.
  std::optional<Stop> stopped;
  long samples = 0;  // rows of the CSV: one per MuJoCo step reached, t = 0 included
  // max |q_ref - q| over the commanded lengths (m) and angles (rad): over the run, and its second half
  double length_error = 0, angle_error = 0, late_length_error = 0, late_angle_error = 0;
  // After the contacts settle (kEngineSettle): each contact's slip (m/s), mean and largest, and
  // |normal force, MuJoCo's - the model's for the same torques| / the machine's weight.
  double mean_slip = 0, max_slip = 0, mean_force_difference = 0, max_force_difference = 0;
};
inline constexpr double kEngineSettle = 0.05;  // s: the machine starts on its contacts, not yet pressed in
// Where the machine is taken to have left its reference: the run stops there.
inline constexpr double kEngineLostLength = 0.5, kEngineLostAngle = std::numbers::pi / 6;  // m, rad (30 deg)

// The closed loop's plant and controller (ForwardRow).
inline constexpr double kPlantMassFactor = 1.10;     // every body's mass and inertia, plant / model
inline constexpr double kStartOffsetLength = 0.02;   // m, added to every commanded length coordinate at t = 0
inline constexpr double kStartOffsetAngle = 0.0174532925199432957;  // 1 deg, to every commanded angle
inline constexpr double kTrackingKp = 400, kTrackingKd = 40;  // 1/s^2, 1/s: critically damped at 20 rad/s
inline constexpr double kRoundTripTolerance = 1e-12;  // dopri5's, for the round trip

// A measured value in the unit the report shows it in.
struct Measured {
  Measured(double value_in, std::string unit_in, std::string stopped_in = {})
      : value(value_in), unit(std::move(unit_in)), stopped(std::move(stopped_in)) {}
  double value = 0;
  std::string unit;
  // Not empty: the value could not be measured because a run it depends on stopped (this says
  // which, where and why); the value is then NaN, which no criterion passes.
  std::string stopped;
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
  const std::vector<IntegratorRow>& integrators() const { return integrators_; }
  const std::vector<ForwardRow>& forward() const { return forward_; }
  const std::vector<EngineRow>& engine() const { return engine_; }
  // Why the report has no physics engine's runs (empty: it has them, one per completed
  // inverse-dynamics run).
  const std::string& engine_missing() const { return engine_missing_; }
  const std::vector<int>& compared_coordinates() const { return compared_; }
  // Every simulation that stopped, in the order they ran.
  const std::vector<StoppedRun>& stopped() const { return stopped_; }
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
  std::vector<int> compared_;
  std::vector<IkSweepResult> sweeps_;
  std::vector<ReportRun> runs_;
  std::vector<IntegratorRow> integrators_;
  std::vector<ForwardRow> forward_;
  std::vector<EngineRow> engine_;
  std::string engine_missing_;
  std::vector<StoppedRun> stopped_;
};

// The unit a coordinate is shown in ("deg" for angles, "m") and the factor from SI to it.
std::string display_unit(int coordinate);
double display_scale(int coordinate);

WLX_COMMANDS_END
