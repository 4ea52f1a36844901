// One model's computations as functions of run-time sizes: what a binding that names no model
// (Python's wlx.Model, python/module.cpp) calls, for a built-in model and for a model file's plugin
// alike. Each model compiles its own (cli/commands/model_api.cpp); the inputs are the JSON the
// command line reads (so the grammar, the checks and the messages are the CLI's own) and vectors
// checked against the model's sizes; results are finite, or an error (never NaN torques).
#pragma once

#include <Eigen/Core>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace wlx::cli {

// A named result: a vector (one column) or a matrix.
struct NamedArray {
  std::string name;
  Eigen::MatrixXd value;
  bool is_vector = true;
};
using NamedArrays = std::vector<NamedArray>;

// The model's tables, by name (a JSON object: name, description, coordinates, units, input_count,
// frames, params (defaults, SI), param_units, scenarios, commanded, actuators, contacts), as text.
using ModelInfoText = std::string;

// The torques of a controller in the loop: f(t, s, u) -> tau, one per actuator. Whatever it throws
// reaches the caller of simulate unchanged.
using TorqueFunction = std::function<Eigen::VectorXd(double t, const Eigen::VectorXd& s, const Eigen::VectorXd& u)>;

// A run as it streams: `begin` is told the columns and the number of rows that will be kept (it
// may refuse by throwing), `row` gets each kept row.
struct SimulationSink {
  std::function<void(const std::vector<std::string>& header, long kept)> begin;
  std::function<void(long row, const std::vector<double>& values)> row;
  // Called at every sample, kept or not: a host checks its signals there (Python's Ctrl-C) and may
  // throw to end the run. Empty: nothing to check.
  std::function<void()> poll;
};
struct SimulationOutcome {
  std::string id;
  bool complete = false;
  std::string stopped;    // why a run ended early
  std::string stop_kind;  // what kind of failure ended it (wlx::error_kind_name), empty when complete
  long evaluations = 0;
  long rows = 0;
  // The run's summary over all its samples (kept or not; cli/commands/run_summary.hpp, as `wlx
  // simulate` prints it and the report tabulates it), for a sweep's metrics. Each is present only
  // where the run has the quantity and at least one sample: peak_tau and rms_tau (per actuator)
  // for a run with torques, min_clearance for a model with a clearance box; for a run with torques
  // on a model with contacts, min_normal_force and min_friction_margin (N, over the supporting
  // contacts) and min_tip_margin (the force-angle margin, rad).
  NamedArrays summary;
};

struct ModelApi {
  ModelInfoText (*info)();
  // `wlx ik`'s answer (JSON text) for a request, and all coordinates.
  std::pair<Eigen::VectorXd, std::string> (*ik)(const std::string& request_json);
  // Frame origins (frames x 3) and orientations at s.
  std::pair<Eigen::MatrixXd, std::vector<Eigen::Matrix3d>> (*fk)(const Eigen::VectorXd& s, const std::string& params_json);
  // All rates from the inputs' rates, for the dependent pair (empty: the model's); and cond(J_beta).
  std::pair<Eigen::VectorXd, double> (*dependent_rates)(const Eigen::VectorXd& s, const Eigen::VectorXd& input_rates,
                                                         const std::vector<std::string>& pair, const std::string& params_json);
  // tau, Qstar, M, b, Q_gravity, J_beta, sdot; for a model with contacts contact_force and contact_point
  // (contacts x 3), friction_margin, margins (static, zmp, tip angle).
  NamedArrays (*inverse_dynamics)(const Eigen::VectorXd& s, const Eigen::VectorXd& u, const Eigen::VectorXd& u_dot,
                                  const std::string& params_json, const std::string& weighting_json);
  // u_dot, sddot, sdot, Qstar, M.
  NamedArrays (*forward_dynamics)(const Eigen::VectorXd& s, const Eigen::VectorXd& u, const Eigen::VectorXd& tau,
                                  const std::string& params_json);
  // A scenario (JSON: an object, or a string naming an embedded id or a file), every k-th sample;
  // params_json (an object) overrides the scenario's own parameters (a sweep's variant over a run).
  SimulationOutcome (*simulate)(const std::string& scenario_json, const std::string& params_json, long every, TorqueFunction torques,
                                const SimulationSink& sink);
  // Without JSON per call, for a binding's hot loops: a workspace (the model at the parameters of
  // params_json, with its Data, made once), then states by the array, row-major (count rows of
  // the model's coordinates; outputs sized by the caller). Each state is checked as `s` above is
  // (the first bad entry named "s[row].<coordinate>"); the results are finite, or an error.
  void* (*new_workspace)(const std::string& params_json);
  void (*delete_workspace)(void* workspace);
  // positions: count x frames x 3; rotations: count x frames x 3 x 3, each matrix by columns (the
  // binding presents the transpose of that layout: the matrices as they are).
  void (*fk_many)(void* workspace, const double* s, long count, double* positions, double* rotations);
  // tau: count x actuators; Qstar: count x commanded speeds. u, u_dot: count x commanded speeds.
  // weighting_json as inverse_dynamics' (all but the contacts' distribution, an optimisation per state).
  void (*inverse_dynamics_many)(void* workspace, const std::string& weighting_json, const double* s, const double* u,
                                const double* u_dot, long count, double* tau, double* Qstar);
};

}  // namespace wlx::cli
