// What `wlx report` computed for one model, in terms that name no model: the runs, sweeps and
// comparisons as plain numbers and names, and the model's tables the page shows. The per-model
// side (report/runner.hpp, compiled for each model) runs the simulations and fills these; the page
// and the figures (report/report.hpp, report/figures.hpp) are compiled once, into wlx itself, and
// read only these.
#pragma once

#include "report/spec.hpp"
#include "run_extremes.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace wlx::cli::report {

// Degrees per radian: the report's tables and figures show angles in degrees.
inline constexpr double kDegPerRad = 180 / std::numbers::pi;
// The unit a coordinate is shown in, from its SI unit ("rad" -> "deg", "m" stays), and the factor
// from SI to it.
inline std::string display_unit(std::string_view si_unit) { return si_unit == "rad" ? "deg" : std::string(si_unit); }
inline double display_scale(std::string_view si_unit) { return si_unit == "rad" ? kDegPerRad : 1; }

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

// One run integrated one way, against RK4 at the reference step.
struct IntegratorRow {
  std::string id;
  std::string integrator;  // "euler", "rk4", "dopri5"
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

// The model as the report names it: its generated tables, and its parameters at the report's values.
struct ModelTables {
  std::string name, description;
  std::vector<std::string> coordinates, coordinate_units;  // each coordinate's name and SI unit ("m", "rad")
  std::vector<std::string> frames;
  std::vector<int> frame_parents;  // -1 for a root frame
  std::vector<std::string> wheels, actuators, contacts;
  std::vector<int> commanded;  // the coordinates of the commanded speeds
  bool has_clearance = false;  // the model file has a clearance box
  struct Parameter {
    std::string name;
    double value = 0;
    std::string unit, meaning;
  };
  std::vector<Parameter> parameters;

  // The index of that coordinate or frame, or -1.
  int coordinate_index(std::string_view name) const;
  int frame_index(std::string_view name) const;
  std::string unit(int coordinate) const { return display_unit(coordinate_units.at(static_cast<std::size_t>(coordinate))); }
  double scale(int coordinate) const { return display_scale(coordinate_units.at(static_cast<std::size_t>(coordinate))); }
  bool is_angle(int coordinate) const { return coordinate_units.at(static_cast<std::size_t>(coordinate)) == "rad"; }
};

// One IK sweep as the page shows it.
struct SweepResult {
  std::string id, input;
  bool degrees = false;     // the input is an angle, shown in degrees
  bool closed_form = true;  // false: the limb has none, Newton's method alone
  std::vector<double> inputs;  // the swept input at each point (SI)
  std::vector<std::string> joints;                 // the limb's joints
  std::vector<std::vector<double>> joint_values;   // per joint, per point: the solution shown (rad or m)
  double max_check_closed_form = 0, max_check_newton = 0, max_newton_difference = 0, mean_newton_iterations = 0;
  int max_newton_iterations = 0;
  int branch = 0;          // the limb's branch along the sweep
  int outside_limits = 0;  // points where a joint of the limb leaves its range
  std::string first_outside;
};

// The machine drawn at one sample: its frames' origins (K0), the body frame's x axis, and the body
// outline's corners (a closed polygon, empty without an outline in the report file).
struct Pose {
  std::vector<Eigen::Vector3d> frames;
  Eigen::Vector3d heading = Eigen::Vector3d::UnitX();
  std::vector<Eigen::Vector3d> outline;
};

// One run of the report, up to where it stopped.
struct RunResult : RunExtremes {  // its extremes over the samples: run_extremes.hpp
  std::string id;           // the scenario's id, "<id>-w1"/"<id>-w2"/"<id>-w3" for inverse dynamics
  std::string scenario_id;  // the scenario file's id
  std::string description;
  std::string csv;  // file name in data/
  bool nonholonomic_verification = false;  // the scenario is marked "verify": "nonholonomic"
  // An inverse-dynamics run: its weighting's number (1: the model file's weights, 2: by
  // contribution, 3: keeping the machine on its contacts) and label; 0 and "" otherwise.
  int weighting = 0;
  std::string weighting_label;
  std::optional<Stop> stopped;  // set: the run ended before its duration
  // The largest over the wheels and over the actuators (run_summary.hpp), meaningful when samples > 0.
  double worst_rolling_residual = 0, largest_tau = 0;
  std::vector<std::vector<double>> tau;  // inverse-dynamics runs: per actuator, per sample (N m or N)
  // The wheels' contact points over the run, seen from above (x0 > x1 without a wheel or a sample).
  double contact_x0 = 1e300, contact_x1 = -1e300, contact_y0 = 1e300, contact_y1 = -1e300;
  // The machine at the first and the last sample, and the report file's body frame at every sample
  // (empty for a run without samples, and for the runs of one motion under weightings 2 and 3).
  std::vector<Pose> poses;
  std::vector<Eigen::Vector3d> body_path;
};

struct Results {
  std::vector<SweepResult> sweeps;
  std::vector<RunResult> runs;
  std::vector<IntegratorRow> integrators;
  std::vector<int> compared;  // the coordinates the integrator comparison shows
  std::vector<ForwardRow> forward;
  std::vector<EngineRow> engine;
  // Why the report has no physics engine's runs (empty: it has them, one per completed
  // inverse-dynamics run).
  std::string engine_missing;
  std::vector<StoppedRun> stopped;  // every simulation that stopped, in the order they ran
  const RunResult* find_run(const std::string& id) const;
};

// One model's side of the report (compiled per model: report/runner.hpp).
class ModelReport {
 public:
  using Progress = std::function<void(const std::string&)>;
  virtual ~ModelReport() = default;
  virtual const ModelTables& tables() const = 0;
  // How many progress steps run_all() reports.
  virtual int steps() const = 0;
  // Every sweep and run, writing the CSV files into data_dir; then results() holds them.
  virtual void run_all(const std::string& data_dir, const Progress& progress) = 0;
  virtual const Results& results() const = 0;
  // The value of a claim's measure, or nothing if it concerns a run or sweep this report did not make.
  virtual std::optional<Measured> measure(const Measure& m) = 0;
  // DIR/runs/<id>.js for the 3D viewer, for every run with a sample.
  virtual void write_viewer_runs(const std::filesystem::path& dir) const = 0;
};

}  // namespace wlx::cli::report
