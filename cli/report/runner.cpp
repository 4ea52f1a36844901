// The report's runs and measurements (report/runner.hpp).
#include "report/runner.hpp"

#include "bounded_input.hpp"
#include "interrupt.hpp"
#include "limits.hpp"
#include "description.hpp"
#include "outputs.hpp"
#include "physics_engine.hpp"
#include "scenario_io.hpp"

#include <fmt/format.h>
#include <wlx/support/csv.hpp>
#include <wlx/contacts.hpp>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

WLX_COMMANDS_BEGIN

namespace {

using report::kEngineLostAngle;
using report::kEngineLostLength;
using report::kEngineSettle;
using report::kPlantMassFactor;
using report::kRoundTripTolerance;
using report::kStartOffsetAngle;
using report::kStartOffsetLength;
using report::kTrackingKd;
using report::kTrackingKp;

bool is_dynamics(const std::string& scenario_id) {
  return model_scenario_json(scenario_id).contains("weighting");
}

// The runs of a dynamics scenario in the report, one per weighting compared: the model file's (1),
// by contribution (2) and, for a model with contacts, the one that keeps the machine on them (3,
// compared with 1 and 2 in the contacts table). Their ids are what report files name.
std::vector<std::pair<std::string, Weighting>> weighting_variants(const std::string& scenario_id) {
  std::vector<std::pair<std::string, Weighting>> v{{scenario_id + "-w1", Weighting::model_weights()},
                                                   {scenario_id + "-w2", Weighting::contribution()}};
  if (kContactCount > 0) v.emplace_back(scenario_id + "-w3", Weighting::contacts());
  return v;
}

// Asked after every sample: a signal stops a long simulation at once, not when it ends.
void stop_on_signal(long, long) { throw_if_interrupted(); }

// A controller's reference along a run at any t: cubic Hermite between the run's samples (its
// coordinates and rates), so evaluations between samples see the motion, not a staircase; an
// inverse-dynamics run's commanded speeds are constant, so u_ref' = 0.
void commanded_reference(const ReportRun& run, double t, CommandVector& q, CommandVector& u) {
  const std::vector<Sample>& reference = run.trajectory.samples;
  const double dt = run.scenario.dt;
  const std::size_t k = std::min(static_cast<std::size_t>(std::max(t / dt, 0.0)), reference.size() - 2);
  const Sample &a = reference[k], &b = reference[k + 1];
  const double h = b.t - a.t, x = std::clamp((t - a.t) / h, 0.0, 1.0);
  const double h00 = (1 + 2 * x) * (1 - x) * (1 - x), h10 = x * (1 - x) * (1 - x), h01 = x * x * (3 - 2 * x), h11 = x * x * (x - 1);
  for (int j = 0; j < kCommandedCount; ++j) {
    const int c = kCommandedSpeeds[static_cast<std::size_t>(j)];
    q(j) = h00 * a.s(c) + h10 * h * a.sdot(c) + h01 * b.s(c) + h11 * h * b.sdot(c);
    u(j) = a.sdot(c) + x * (b.sdot(c) - a.sdot(c));
  }
}

}  // namespace

std::string display_unit(int c) { return report::display_unit(gen::kCoordinateUnits[static_cast<std::size_t>(c)]); }
double display_scale(int c) { return report::display_scale(gen::kCoordinateUnits[static_cast<std::size_t>(c)]); }

ReportRunner::ReportRunner(const Params& params, const report::ReportSpec& spec, bool quick, Progress progress)
    : spec_(spec), quick_(quick), progress_(std::move(progress)), model_(params) {
  for (const auto& name : spec_.integrator_coordinates) results_.compared.push_back(coordinate_index(name));
}

// ---- names --------------------------------------------------------------------------------------

void ReportRunner::validate() const {
  const auto fail = [&](int line, const std::string& path, const std::string& what, const std::string& name,
                        const std::vector<std::string>& valid) {
    const std::string near = nearest(name, valid);
    throw Error(report::where(spec_, line, path), fmt::format("'{}' is not {} of model {}{}", name, what, gen::kModelName,
                                                              near.empty() ? "" : fmt::format(" (did you mean '{}'?)", near)));
  };
  std::vector<std::string> coordinates(gen::kCoordinateNames.begin(), gen::kCoordinateNames.end());
  std::vector<std::string> scenarios = scenario_ids();
  std::vector<std::string> runs;
  for (const auto& id : scenarios) {
    if (is_dynamics(id)) {
      for (const auto& variant : weighting_variants(id)) runs.push_back(variant.first);
    } else {
      runs.push_back(id);
    }
  }
  std::vector<std::string> sweeps, params, joints;
  for (const auto& s : model_ik_sweeps()) sweeps.push_back(s.id);
  for (const auto& p : gen::kParamInfo) params.emplace_back(p.name);
  for (const std::string_view a : kActuatorNames) joints.emplace_back(a);
  const auto check = [&](const std::vector<std::string>& names, const std::vector<std::string>& valid, int line,
                         const std::string& path, const std::string& what) {
    for (const auto& n : names)
      if (std::find(valid.begin(), valid.end(), n) == valid.end()) fail(line, path, what, n, valid);
  };
  if (spec_.quick_sweeps) check(*spec_.quick_sweeps, sweeps, 1, "quick.sweeps", "an IK sweep");
  if (spec_.quick_scenarios) check(*spec_.quick_scenarios, scenarios, 1, "quick.scenarios", "a scenario");
  check(spec_.integrator_scenarios, scenarios, 1, "integrator_comparison.scenarios", "a scenario");
  check(spec_.integrator_coordinates, coordinates, 1, "integrator_comparison.coordinates", "a coordinate");
  for (const auto& f : spec_.run_figures) {
    check(f.runs, runs, f.line, "run_figures." + f.id + ".runs", "a run");
    check({f.x}, coordinates, f.line, "run_figures." + f.id + ".x", "a coordinate");
    check(f.y, coordinates, f.line, "run_figures." + f.id + ".y", "a coordinate");
  }
  for (const auto& p : spec_.torque_panels) check(p, joints, 1, "torque_figures.panels", "an actuated joint");
  for (const auto& r : spec_.torque_references) check({r.scenario}, scenarios, r.line, "torque_figures.references.scenario", "a scenario");
  if (!spec_.pose_frame.empty() && frame_index(spec_.pose_frame) < 0) {
    std::vector<std::string> frames(gen::kFrameNames.begin(), gen::kFrameNames.end());
    fail(spec_.pose_line, "pose.body_frame", "a frame", spec_.pose_frame, frames);
  }
  check(spec_.pose_outline, params, spec_.pose_line, "pose.outline", "a parameter");
  const std::vector<std::string> integrators{"rk4", "euler", "dopri5"};
  for (const auto& c : spec_.claims) {
    for (const auto& t : c.tests) {
      const report::Measure& m = t.measure;
      const std::string path = "claims." + c.id + ".measure";
      if (!m.run.empty()) check({m.run}, runs, m.line, path + ".run", "a run");
      if (!m.of_run.empty()) check({m.of_run}, runs, m.line, path + ".of_run", "a run");
      check(m.runs, runs, m.line, path + ".runs", "a run");
      check(m.coordinates, coordinates, m.line, path + ".coordinates", "a coordinate");
      check(m.joints, joints, m.line, path + ".joints", "an actuated joint");
      check(m.params, params, m.line, path + ".params", "a parameter");
      if (!m.sweep.empty()) check({m.sweep}, sweeps, m.line, path + ".sweep", "an IK sweep");
      if (!m.integrator.empty()) check({m.integrator}, integrators, m.line, path + ".integrator", "an integrator");
      // Measured from the clearance box (structure.hpp's kHasClearance): a model without one has no such time.
      if (m.quantity == "ground_contact_time" && !gen::kHasClearance)
        throw Error(report::where(spec_, m.line, path + ".quantity"),
                    fmt::format("ground_contact_time needs a clearance box, and model {} has none (its model file has no "
                                "'clearance')", gen::kModelName));
      if (m.quantity == "integrator_deviation") {
        for (const auto& r : m.runs)
          if (std::find(spec_.integrator_scenarios.begin(), spec_.integrator_scenarios.end(), r) == spec_.integrator_scenarios.end())
            throw Error(report::where(spec_, m.line, path + ".runs"), fmt::format("'{}' is not in integrator_comparison.scenarios", r));
        for (const auto& name : m.coordinates) {
          if (std::find(spec_.integrator_coordinates.begin(), spec_.integrator_coordinates.end(), name) == spec_.integrator_coordinates.end())
            throw Error(report::where(spec_, m.line, path + ".coordinates"),
                        fmt::format("'{}' is not in integrator_comparison.coordinates", name));
          // One value in one unit: a criterion cannot hold metres and degrees at once.
          if (display_unit(coordinate_index(name)) != display_unit(coordinate_index(m.coordinates.front())))
            throw Error(report::where(spec_, m.line, path + ".coordinates"),
                        fmt::format("'{}' and '{}' have different units: give them in separate tests", m.coordinates.front(), name));
        }
      }
    }
  }
}

// ---- runs ---------------------------------------------------------------------------------------

std::vector<const IkSweep*> ReportRunner::selected_sweeps() const {
  std::vector<const IkSweep*> out;
  for (const IkSweep& s : model_ik_sweeps())
    if (!quick_ || !spec_.quick_sweeps || std::count(spec_.quick_sweeps->begin(), spec_.quick_sweeps->end(), s.id)) out.push_back(&s);
  return out;
}

std::vector<std::string> ReportRunner::selected_scenarios() const {
  std::vector<std::string> out;
  for (const auto& id : scenario_ids())
    if (!quick_ || !spec_.quick_scenarios || std::count(spec_.quick_scenarios->begin(), spec_.quick_scenarios->end(), id)) out.push_back(id);
  return out;
}

int ReportRunner::steps() const {
  int n = static_cast<int>(selected_sweeps().size());
  // Each weighting's run, the forward dynamics of model-weights' and contribution's, and model-weights' in a physics engine.
  for (const auto& id : selected_scenarios()) n += is_dynamics(id) ? static_cast<int>(weighting_variants(id).size()) + 3 : 1;
  if (!quick_ && !spec_.integrator_scenarios.empty()) ++n;
  return n;
}

void ReportRunner::run_all(const std::string& data_dir) {
  const auto data_file = [&](const std::string& name) { return data_dir + "/" + name; };
  for (const IkSweep* sweep : selected_sweeps()) {
    progress_(fmt::format("inverse kinematics sweep {} ({} from {:g} to {:g})", sweep->id, sweep->input,
                          sweep->degrees ? sweep->from * kDegPerRad : sweep->from, sweep->degrees ? sweep->to * kDegPerRad : sweep->to));
    sweeps_.push_back(run_ik_sweep(model_, data_, *sweep));
    write_ik_sweep_csv(data_file(sweep->id + ".csv"), sweeps_.back());
  }
  for (const auto& scenario_id : selected_scenarios()) {
    const nlohmann::json json = model_scenario_json(scenario_id);
    const bool verify = json.value("verify", "") == "nonholonomic";
    std::vector<std::pair<std::string, std::optional<Weighting>>> variants;
    if (json.contains("weighting")) {
      for (auto& [id, weighting] : weighting_variants(scenario_id)) variants.emplace_back(id, weighting);
    } else {
      variants.emplace_back(scenario_id, std::nullopt);
    }
    for (const auto& [id, weighting] : variants) {
      Scenario sc = parse_scenario(json, model_.params(), model_scenario_directory());
      if (weighting) sc.weighting = weighting;
      // The report compares the weightings' contacts over the whole run: a lift-off is a row of
      // its contacts table, not the end of the report.
      if (weighting) sc.stop_on_contact_loss = false;
      progress_(fmt::format("simulating {}{}: {}", id, weighting ? " (" + weighting->label() + ")" : "", sc.description));
      ReportRun r{id, scenario_id, sc, simulate(sc, stop_on_signal), id + ".csv", verify, std::nullopt, {}};
      r.summary = summarize(r.trajectory, sc.weighting || sc.driven_by_torques());
      // A run that stops is one row of the report, with what it computed up to there: the
      // others still run, and the report says where and why.
      if (!r.trajectory.complete) r.stopped = record_stop(id, "", r.trajectory);
      write_trajectory(data_file(r.csv), r.trajectory, sc);
      runs_.push_back(std::move(r));
    }
  }
  const std::size_t inverse_runs = runs_.size();
  for (std::size_t k = 0; k < inverse_runs; ++k) {
    // Forward dynamics for model-weights and contribution (the contacts' torques retrace the same motion).
    if (!runs_[k].scenario.weighting || runs_[k].scenario.weighting->kind == Weighting::Kind::contacts) continue;
    if (runs_[k].stopped) {
      // Both follow the run's whole motion (its torques from 0 to its duration, its path as the
      // reference): a stopped run has neither.
      progress_(fmt::format("forward dynamics of {}: not run ({} stopped)", runs_[k].id, runs_[k].id));
      ForwardRow row;
      row.id = runs_[k].id;
      row.not_run = runs_[k].stopped;
      results_.forward.push_back(row);
      continue;
    }
    progress_(fmt::format("forward dynamics of {}: its torques fed back, and a controller tracking it on a heavier plant", runs_[k].id));
    results_.forward.push_back(forward_dynamics_of(runs_[k], data_dir));
  }
  // The physics engine: each scenario's run under the model file's weights (the controller's own split).
  results_.engine_missing = physics_engine_missing();
  if (results_.engine_missing.empty() && description_text().empty()) results_.engine_missing = "the model's description is not loaded";
  if (results_.engine_missing.empty() && kContactCount == 0) results_.engine_missing = "the model has no contacts with the ground";
  for (std::size_t k = 0; k < inverse_runs; ++k) {
    const ReportRun& run = runs_[k];
    if (!run.scenario.weighting || run.scenario.weighting->kind != Weighting::Kind::model_weights) continue;
    if (!results_.engine_missing.empty() || run.stopped) {
      progress_(fmt::format("{} in a physics engine: not run ({})", run.id, run.stopped ? run.id + " stopped" : results_.engine_missing));
      continue;
    }
    progress_(fmt::format("{} in a physics engine: the controller drives MuJoCo's machine", run.id));
    try {
      results_.engine.push_back(physics_engine_of(run, data_dir));
    } catch (const Error& e) {  // MuJoCo's machine could not be made (what the export cannot express): a row that says so
      EngineRow row;
      row.id = run.id;
      row.stopped = Stop{0, std::string("no machine in MuJoCo: ") + e.what()};
      results_.engine.push_back(row);
    }
  }
  if (!quick_ && !spec_.integrator_scenarios.empty()) {
    progress_(fmt::format("comparing integrators: Euler, RK4, dopri5 against RK4 at {:g} s on {} runs", spec_.reference_step,
                          spec_.integrator_scenarios.size()));
    compare_integrators(data_dir);
  }
}

void ReportRunner::compare_integrators(const std::string& data_dir) {
  const double step = spec_.reference_step;
  for (const auto& id : spec_.integrator_scenarios) {
    // A run that stopped at its own step stops in the comparison too: its row says so already.
    if (first_stop({id})) continue;
    Scenario sc = parse_scenario(model_scenario_json(id), model_.params(), model_scenario_directory());
    Scenario ref_sc = sc;
    ref_sc.dt = step;
    const Trajectory ref = simulate(ref_sc, stop_on_signal);
    if (!ref.complete) {
      record_stop(id, fmt::format("reference, RK4 at {:g} s", step), ref);
      continue;
    }
    const auto compare = [&](const std::string& setting, const Scenario& run) {
      const Trajectory tr = simulate(run, stop_on_signal);
      if (!tr.complete) {
        record_stop(id, fmt::format("{}, {}", integrator_name(run.integrator), setting), tr);
        return;
      }
      IntegratorRow row{id, std::string(integrator_name(run.integrator)), setting, static_cast<long>(tr.samples.size()), tr.evaluations, 0,
                        std::vector<double>(results_.compared.size(), 0.0)};
      for (const auto& smp : tr.samples) {
        const auto& r = ref.samples[static_cast<std::size_t>(std::lround(smp.t / step))];
        const Coordinates d = (smp.s - r.s).cwiseAbs();
        row.inputs = std::max(row.inputs, d.head<kInputCount>().maxCoeff());
        for (std::size_t k = 0; k < results_.compared.size(); ++k) row.coordinates[k] = std::max(row.coordinates[k], d(results_.compared[k]));
      }
      results_.integrators.push_back(row);
    };
    Scenario euler = sc, rk4 = sc, dopri = sc;
    euler.integrator = Integrator::euler;
    rk4.integrator = Integrator::rk4;
    compare(fmt::format("dt {} s", sc.dt), euler);
    compare(fmt::format("dt {} s", sc.dt), rk4);
    // dopri5 writes 10 samples per run and chooses its own steps in between.
    dopri.integrator = Integrator::dopri5;
    dopri.dt = sc.duration / 10;
    compare(fmt::format("tolerance {:.0e}", dopri.tolerance), dopri);
  }
  std::vector<std::string> header{"run", "integrator", "samples", "evaluations", "max_input_deviation"};
  for (int c : results_.compared) header.push_back("max_" + coordinate_name(c) + "_deviation");
  CsvWriter csv(data_dir + "/integrators.csv", header);
  for (const auto& r : results_.integrators) {
    std::vector<double> values{static_cast<double>(r.samples), static_cast<double>(r.evaluations), r.inputs};
    values.insert(values.end(), r.coordinates.begin(), r.coordinates.end());
    csv.row({r.id, r.integrator}, values);
  }
  csv.commit();
}

ForwardRow ReportRunner::forward_dynamics_of(const ReportRun& run, const std::string& data_dir) {
  const std::vector<Sample>& reference = run.trajectory.samples;
  ForwardRow row;
  row.id = run.id;
  row.csv = run.id + "-forward.csv";
  row.closed_loop_csv = run.id + "-closed-loop.csv";

  // The round trip: the run's torques, cubic between its samples, drive the same machine from the
  // same start; dopri5 at a tight tolerance, samples at the run's.
  std::vector<double> times;
  std::vector<TorqueVector> torques;
  for (const Sample& smp : reference) times.push_back(smp.t), torques.push_back(smp.tau);
  Scenario trip = run.scenario;
  trip.weighting.reset();
  trip.integrator = Integrator::dopri5;
  trip.tolerance = kRoundTripTolerance;
  trip.torques = TorqueTable(times, torques, TorqueTable::Interpolation::cubic);
  const Trajectory forward = simulate(trip, stop_on_signal);
  if (!forward.complete) row.round_trip_stopped = record_stop(run.id, "round trip", forward);
  row.samples = static_cast<long>(forward.samples.size());
  row.evaluations = forward.evaluations;

  // The closed loop, along the run's motion (commanded_reference).
  Scenario plant = run.scenario;
  plant.weighting.reset();
  for (const auto& body : gen::kBodyMass) {
    plant.params.*body.mass *= kPlantMassFactor;
    for (auto inertia : body.inertia) plant.params.*inertia *= kPlantMassFactor;
  }
  for (int j = 0; j < kCommandedCount; ++j) {
    const int c = kCommandedSpeeds[static_cast<std::size_t>(j)];
    plant.initial(c) += is_angle(c) ? kStartOffsetAngle : kStartOffsetLength;
  }
  const Weighting weighting = *run.scenario.weighting;
  DynamicsTerms terms;
  plant.torques = [&](double t, const Coordinates& s, const CommandVector& u) -> TorqueVector {
    CommandVector q_ref, u_ref;
    commanded_reference(run, t, q_ref, u_ref);
    CommandVector q;
    for (int j = 0; j < kCommandedCount; ++j) q(j) = s(kCommandedSpeeds[static_cast<std::size_t>(j)]);
    const CommandVector u_dot = kTrackingKd * (u_ref - u) + kTrackingKp * (q_ref - q);
    inverse_dynamics(model_, data_, s, u, u_dot, terms);  // the model's: it does not know the plant
    return distribute_torques(terms.J_beta, terms.Qstar, weighting);
  };
  const Trajectory loop = simulate(plant, stop_on_signal);
  if (!loop.complete) row.closed_loop_stopped = record_stop(run.id, "closed loop", loop);
  row.closed_loop_samples = static_cast<long>(loop.samples.size());

  CsvWriter csv(data_dir + "/" + row.csv, {"t", "round_trip_deviation", "energy_balance"});
  EnergyBalance energy;
  for (std::size_t k = 0; k < forward.samples.size(); ++k) {
    const Sample& f = forward.samples[k];
    energy.add(f);
    const double deviation = (f.s - reference[k].s).cwiseAbs().maxCoeff();
    const double balance = std::abs(energy.residual());
    row.round_trip = std::max(row.round_trip, deviation);
    row.energy_balance = std::max(row.energy_balance, balance);
    row.work = std::max(row.work, std::abs(energy.work));
    csv.row({f.t, deviation, balance});
  }
  csv.commit();

  std::vector<std::string> header{"t", "tracking_error"};
  for (int c : kCommandedSpeeds) header.push_back("error_" + coordinate_name(c));
  CsvWriter tracking(data_dir + "/" + row.closed_loop_csv, header);
  for (std::size_t k = 0; k < loop.samples.size(); ++k) {
    const Sample& smp = loop.samples[k];
    CommandVector q_ref, u_ref;
    commanded_reference(run, smp.t, q_ref, u_ref);
    std::vector<double> values{smp.t, 0};
    for (int j = 0; j < kCommandedCount; ++j) {
      const double e = q_ref(j) - smp.s(kCommandedSpeeds[static_cast<std::size_t>(j)]);
      values[1] = std::max(values[1], std::abs(e));
      values.push_back(e);
    }
    if (k == 0) row.start_error = values[1];
    if (2 * k >= reference.size() - 1) row.late_error = std::max(row.late_error, values[1]);
    tracking.row(values);
  }
  tracking.commit();
  return row;
}

EngineRow ReportRunner::physics_engine_of(const ReportRun& run, const std::string& data_dir) {
  EngineRow row;
  row.id = run.id;
  row.csv = run.id + "-mujoco.csv";
  // MuJoCo's machine at the run's parameters (the report's --params, the scenario's own): the
  // description's values replaced by them.
  nlohmann::json description = nlohmann::json::parse(description_text());
  Params params = run.scenario.params;
  for (nlohmann::json& parameter : description.at("parameters"))
    if (const double* value = find_param(params, parameter.at("name").get<std::string>())) parameter["value"] = *value;
  PhysicsEngine engine(description.dump(), std::vector<std::string>(gen::kCoordinateNames.begin(), gen::kCoordinateNames.end()));
  // The run's start and speeds; the controller's split is the run's.
  Coordinates s = run.trajectory.samples.front().s, sdot = run.trajectory.samples.front().sdot;
  engine.set_state(s, sdot);
  const Weighting weighting = *run.scenario.weighting;
  const double weight = model_.total_mass() * (model_.params().*gen::kGravity);
  const double step = engine.timestep();
  const long steps = std::lround(run.scenario.duration / step);
  std::vector<std::string> header{"t", "tracking_error_m", "tracking_error_rad"};
  for (int c = 0; c < kContactCount; ++c) {
    const std::string name = contact_name(c);
    header.insert(header.end(), {"slip_" + name, "normal_mujoco_" + name, "normal_wlx_" + name});
  }
  CsvWriter csv(data_dir + "/" + row.csv, header);
  DynamicsTerms terms;
  ContactForces predicted;
  double slip_sum = 0, force_sum = 0;
  long settled = 0;
  for (long n = 0; n <= steps; ++n) {
    const double t = static_cast<double>(n) * step;
    if (n % 100 == 0) throw_if_interrupted();
    engine.read_state(s, sdot);
    complete_tied_inputs(model_, data_, s, sdot);
    // The controller's model of the state: MuJoCo's inputs, the dependent joints solved from them
    // (MuJoCo holds the closure softly; the model's equations hold on it exactly).
    std::string out_of_reach;
    try {
      solve_ik_closed_form(model_, s, run.scenario.branches);
    } catch (const Error& e) {
      out_of_reach = e.what();
    }
    CommandVector q_ref, u_ref, q, u;
    commanded_reference(run, t, q_ref, u_ref);
    double length = 0, angle = 0;
    for (int j = 0; j < kCommandedCount; ++j) {
      const int c = kCommandedSpeeds[static_cast<std::size_t>(j)];
      q(j) = s(c), u(j) = sdot(c);
      double& worst = is_angle(c) ? angle : length;
      worst = std::max(worst, std::abs(q_ref(j) - q(j)));
    }
    // Leaving the reference ends the run where it happens: what follows is no longer the run. It
    // is a finding about the controller on another machine, not a failure of the model: it stays
    // out of the report's stopped simulations (and its exit status).
    const auto stop = [&](const std::string& reason) { row.stopped = Stop{t, reason}; };
    if (!s.allFinite() || !sdot.allFinite()) {
      stop("MuJoCo's state is not finite");
      break;
    }
    if (!out_of_reach.empty()) {
      stop("the model's IK of MuJoCo's state: " + out_of_reach);
      break;
    }
    if (length > kEngineLostLength || angle > kEngineLostAngle) {
      stop(fmt::format("the machine left its reference ({:.3g} m, {:.3g} deg): beyond {:g} m or {:g} deg", length, angle * kDegPerRad,
                       kEngineLostLength, kEngineLostAngle * kDegPerRad));
      break;
    }
    if (const std::string trouble = engine.trouble(); !trouble.empty()) {
      stop(trouble);
      break;
    }
    // The controller, and the model's contact forces for the torques MuJoCo applies (within the
    // motors' ranges, which it clamps to).
    const CommandVector u_dot = kTrackingKd * (u_ref - u) + kTrackingKp * (q_ref - q);
    TorqueVector applied;
    try {
      inverse_dynamics(model_, data_, s, u, u_dot, terms);
      applied = engine.set_torques(distribute_torques(terms.J_beta, terms.Qstar, weighting));
      contact_forces(model_, data_, s, terms, applied, predicted);
    } catch (const Error& e) {
      stop(std::string("the controller at MuJoCo's state: ") + e.what());
      break;
    }
    if (!applied.allFinite() || !predicted.normal.allFinite()) {
      stop("the controller's torques or the model's contact forces at MuJoCo's state are not finite");
      break;
    }
    const std::vector<EngineContact> contacts = engine.contacts();
    row.length_error = std::max(row.length_error, length);
    row.angle_error = std::max(row.angle_error, angle);
    if (2 * n >= steps) {
      row.late_length_error = std::max(row.late_length_error, length);
      row.late_angle_error = std::max(row.late_angle_error, angle);
    }
    std::vector<double> values{t, length, angle};
    for (int c = 0; c < kContactCount; ++c) {
      const EngineContact& e = contacts[static_cast<std::size_t>(c)];
      values.insert(values.end(), {e.slip, e.normal, predicted.normal(c)});
      // Without weight (gravity 0) the forces have no scale to compare at: slip only.
      if (t < kEngineSettle || !gen::kContacts[static_cast<std::size_t>(c)].supports) continue;
      const double difference = weight > 0 ? std::abs(e.normal - predicted.normal(c)) / weight : 0.0;
      row.max_slip = std::max(row.max_slip, e.slip);
      row.max_force_difference = std::max(row.max_force_difference, difference);
      slip_sum += e.slip;
      force_sum += difference;
      ++settled;
    }
    csv.row(values);
    ++row.samples;
    if (n < steps) engine.step();
  }
  csv.commit();
  if (settled > 0) row.mean_slip = slip_sum / static_cast<double>(settled), row.mean_force_difference = force_sum / static_cast<double>(settled);
  return row;
}

Stop ReportRunner::record_stop(const std::string& run, const std::string& part, const Trajectory& trajectory) {
  const Stop stop{trajectory.stop_time, trajectory.stop_reason};
  results_.stopped.push_back({run, part, stop});
  return stop;
}

const StoppedRun* ReportRunner::first_stop(const std::vector<std::string>& runs, const std::vector<std::string>& parts) const {
  for (const auto& s : results_.stopped)
    if (std::count(runs.begin(), runs.end(), s.run) && (parts.empty() || std::count(parts.begin(), parts.end(), s.part))) return &s;
  return nullptr;
}

const ReportRun* ReportRunner::find_run(const std::string& id) const {
  for (const auto& r : runs_)
    if (r.id == id) return &r;
  return nullptr;
}

// ---- measurements -------------------------------------------------------------------------------

std::optional<Measured> ReportRunner::measure(const report::Measure& m) {
  const std::string& q = m.quantity;
  const int c = m.coordinates.empty() ? -1 : coordinate_index(m.coordinates.front());
  // A claim about a run that stopped is not measured: it fails, saying which run stopped where.
  const auto stopped = [](const StoppedRun& s, const std::string& unit) {
    return Measured{NAN, unit, fmt::format("{} {}", s.label(), s.stop.describe())};
  };
  if (q == "total_mass") return Measured{model_.total_mass(), "kg"};
  if (q == "param_product") {
    Params p = model_.params();
    double v = m.factor * (m.times_total_mass ? model_.total_mass() : 1);
    for (const auto& name : m.params) v *= *find_param(p, name);
    return Measured{v, m.unit};
  }
  if (q == "max_ik_check_error" || q == "max_ik_method_difference") {
    // The method difference over the sweeps that have both methods: a limb without a closed form
    // has nothing to compare, and with none such the claim cannot be measured (skipped).
    double worst = 0;
    bool any = false;
    for (const auto& s : sweeps_) {
      if (q == "max_ik_method_difference" && !s.closed_form) continue;
      any = true;
      worst = std::max(worst, q == "max_ik_check_error" ? std::max(s.max_check_closed_form, s.max_check_newton) : s.max_newton_difference);
    }
    if (!any) return std::nullopt;
    return Measured{worst, q == "max_ik_check_error" ? "m" : "rad"};
  }
  if (q == "newton_branch_switch" || q == "newton_branch_settled") {
    for (const auto& s : sweeps_) {
      if (s.sweep.id != m.sweep) continue;
      // In the sweep's order; no switch: NaN, which no criterion passes.
      double first = NAN;
      for (std::size_t k = 0; k < s.points.size(); ++k) {
        const bool off_default = s.points[k].cold_newton_branch == 1;
        if (q == "newton_branch_switch" && off_default && std::isnan(first)) first = s.points[k].value;
        if (q == "newton_branch_settled") first = off_default ? (std::isnan(first) ? s.points[k].value : first) : NAN;
      }
      const double scale = s.sweep.degrees ? kDegPerRad : 1;
      return Measured{first * scale, s.sweep.degrees ? "deg" : "m"};
    }
    return std::nullopt;
  }
  if (q == "max_wheel_residual") {
    if (runs_.empty()) return std::nullopt;
    std::vector<std::string> all_runs;  // every sample of every run: a stopped one's are not all there
    for (const auto& r : runs_) all_runs.push_back(r.id);
    if (const StoppedRun* s = first_stop(all_runs)) return stopped(*s, "m/s");
    double worst = 0;
    for (const auto& r : runs_) worst = std::max(worst, r.summary.worst_rolling_residual());
    return Measured{worst, "m/s"};
  }
  if (q == "integrator_deviation") {
    if (quick_ || spec_.integrator_scenarios.empty()) return std::nullopt;  // not compared (run_all)
    const std::string& integrator = m.integrator;  // validated: one of integrator_name()'s
    double worst = 0;
    std::string unit = "m or rad";
    // A compared run stopped, at its own step or in a comparison: its deviation is not known.
    if (const StoppedRun* s = first_stop(m.runs.empty() ? spec_.integrator_scenarios : m.runs, {}))
      return stopped(*s, m.coordinates.empty() ? unit : display_unit(coordinate_index(m.coordinates.front())));
    for (const auto& r : results_.integrators) {
      if (r.integrator != integrator || (!m.runs.empty() && std::find(m.runs.begin(), m.runs.end(), r.id) == m.runs.end())) continue;
      if (m.coordinates.empty()) {
        worst = std::max(worst, r.inputs);
        continue;
      }
      for (const auto& name : m.coordinates) {
        const int k = coordinate_index(name);
        const auto at = std::find(results_.compared.begin(), results_.compared.end(), k) - results_.compared.begin();
        worst = std::max(worst, r.coordinates[static_cast<std::size_t>(at)] * display_scale(k));
        unit = display_unit(k);
      }
    }
    return Measured{worst, unit};
  }
  if (q == "static_torque") {
    Coordinates s = nominal_inputs();
    solve_ik_closed_form(model_, s);
    DynamicsTerms t;
    inverse_dynamics(model_, data_, s, CommandVector::Zero(), CommandVector::Zero(), t);
    const TorqueVector tau = distribute_torques(t.J_beta, t.Qstar, m.weighting == 1 ? Weighting::model_weights() : Weighting::contribution());
    double worst = 0;
    for (const auto& name : m.joints) {
      const auto at = std::find(kActuatorNames.begin(), kActuatorNames.end(), name) - kActuatorNames.begin();
      worst = std::max(worst, std::abs(tau(at)));
    }
    return Measured{worst, "N m"};
  }
  if (q == "peak_torque") {
    double worst = 0;
    for (const auto& id : m.runs)
      if (!find_run(id)) return std::nullopt;
    if (const StoppedRun* s = first_stop(m.runs)) return stopped(*s, "N m");
    for (const auto& id : m.runs) worst = std::max(worst, find_run(id)->summary.largest_tau());
    return Measured{worst, "N m"};
  }
  if (q == "round_trip_deviation" || q == "energy_balance" || q == "closed_loop_error") {
    double worst = 0;
    bool any = false;
    const std::string unit = q == "energy_balance" ? "" : "m or rad";
    for (const ForwardRow& r : results_.forward) {
      if (!m.runs.empty() && std::find(m.runs.begin(), m.runs.end(), r.id) == m.runs.end()) continue;
      any = true;
      // The inverse-dynamics run, or the simulation this quantity comes from, stopped: not measured.
      const std::string part = q == "closed_loop_error" ? "closed loop" : "round trip";
      if (const StoppedRun* s = first_stop({r.id}, {"", part})) return stopped(*s, unit);
      if (q == "round_trip_deviation") worst = std::max(worst, r.round_trip);
      else if (q == "energy_balance") worst = std::max(worst, r.energy_balance / std::max(r.work, 1.0));
      else worst = std::max(worst, r.late_error);
    }
    if (!any) return std::nullopt;
    return Measured{worst, unit};
  }
  // The rest concern one run.
  const ReportRun* run = find_run(m.run);
  if (!run) return std::nullopt;
  const auto& samples = run->trajectory.samples;
  const std::string unit = q == "end_value" ? display_unit(c) : q == "peak_condition_time" || q == "ground_contact_time" ? "s" : "";
  if (q == "end_ratio" && !find_run(m.of_run)) return std::nullopt;
  if (const StoppedRun* s = first_stop({m.run, m.of_run})) return stopped(*s, unit);
  if (q == "end_value") return Measured{samples.back().s(c) * display_scale(c), display_unit(c)};
  if (q == "end_ratio") return Measured{samples.back().s(c) / find_run(m.of_run)->trajectory.samples.back().s(c), ""};
  if (q == "peak_condition" || q == "peak_condition_time") {
    std::size_t peak = 0;
    for (std::size_t k = 0; k < samples.size(); ++k)
      if (samples[k].cond_J_beta > samples[peak].cond_J_beta) peak = k;
    return q == "peak_condition" ? Measured{samples[peak].cond_J_beta, ""} : Measured{samples[peak].t, "s"};
  }
  if (q == "ground_contact_time") {
    if (samples.size() < 2) return Measured{NAN, "s"};
    const Sample& a = samples[samples.size() - 2];
    const Sample& b = samples.back();
    const double rate = (b.clearance - a.clearance) / (b.t - a.t);  // negative while the body sinks
    return Measured{rate < 0 ? b.t - b.clearance / rate : NAN, "s"};
  }
  throw Error(report::where(spec_, m.line, "quantity"), "not measured by this build: " + q);
}

WLX_COMMANDS_END
