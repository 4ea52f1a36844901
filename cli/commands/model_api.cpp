// One model's computations for a binding that names no model (cli/shell/model_api.hpp; Python's
// wlx.Model). They take the same JSON the command line reads and reuse the command line's parsing
// and solving, so the grammar, the checks and the error messages are the CLI's own.
#include "bounded_input.hpp"
#include "input.hpp"
#include "limits.hpp"
#include "model_api.hpp"
#include "model_commands.hpp"
#include "outputs.hpp"
#include "run_summary.hpp"
#include "scenario_io.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <wlx/contacts.hpp>
#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/forward_dynamics.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

WLX_COMMANDS_BEGIN

namespace {

// The command line's reader (bounded depth, keys given once), so Python's JSON meets the same rules.
nlohmann::json parse_json(const std::string& text, const char* what) { return parse_json_bounded(text, what); }

// The CLI's checks, argument by argument: finite values within the bounds of cli/commands/limits.hpp (a
// rate of NaN or a coordinate of 1e308 gave NaN torques before), so Python and the command line
// refuse the same inputs with the same messages.
Params params_of(const std::string& params_json) {
  const Params params = parse_params(parse_json(params_json, "params"));
  check_param_bounds(params, "params.");
  return params;
}

// u or u' from Python: one entry per commanded speed (the model file's dynamics.commanded).
CommandVector commands_of(const Eigen::VectorXd& u, const char* field) {
  if (u.size() != kCommandedCount)
    throw Error(field, "has " + std::to_string(u.size()) + " entries; the model commands " + std::to_string(kCommandedCount) +
                           " speeds");
  return u;
}

Coordinates coordinates_of(const Eigen::VectorXd& s, const char* field) {
  if (s.size() != kCoordinateCount)
    throw Error(field, "has " + std::to_string(s.size()) + " entries; the model has " + std::to_string(kCoordinateCount) +
                           " coordinates");
  for (int k = 0; k < kCoordinateCount; ++k) {
    const std::string name = std::string(field) + "." + std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    if (!std::isfinite(s(k))) throw Error(name, "is not a finite number");
    // Inputs by their own bounds; dependent joints by the bound of their unit.
    if (k < kInputCount) check_input_bound(k, s(k), name);
    else if (std::abs(s(k)) > (is_angle(k) ? kMaxAngle : kMaxPosition))
      throw Error(name, "is beyond the bound of " + std::to_string(is_angle(k) ? kMaxAngle : kMaxPosition) + (is_angle(k) ? " rad" : " m"));
  }
  return s;
}

// What a function returns is finite, or it is an error: never NaN torques.
template <class Matrix>
void check_result(const Matrix& m, const char* what) {
  if (!m.allFinite()) throw Error(what, "is not finite at these inputs (a state the model does not compute)");
}

// u from a caller: one entry per commanded speed (the model file's dynamics.commanded), each finite
// and within the bound of its coordinate's rate (as a scenario's rates are).
CommandVector speeds_of(const Eigen::VectorXd& u, const char* field) {
  const CommandVector out = commands_of(u, field);
  for (int k = 0; k < kCommandedCount; ++k) {
    const int c = kCommandedSpeeds[static_cast<std::size_t>(k)];
    const std::string name = std::string(field) + "." + std::string(gen::kCoordinateNames[static_cast<std::size_t>(c)]);
    if (!std::isfinite(out(k))) throw Error(name, "is not a finite number");
    check_rate_bound(c, out(k), name);
  }
  return out;
}

// u' from a caller: finite, and at most kMaxRateChange per second (per unit of its coordinate).
constexpr double kMaxRateChange = 1e4;  // m/s^2 or rad/s^2: 1000 g; beyond, a step's terms overflow nothing but mean no machine
CommandVector accelerations_of(const Eigen::VectorXd& u_dot, const char* field) {
  const CommandVector out = commands_of(u_dot, field);
  for (int k = 0; k < kCommandedCount; ++k) {
    const int c = kCommandedSpeeds[static_cast<std::size_t>(k)];
    const std::string name = std::string(field) + "." + std::string(gen::kCoordinateNames[static_cast<std::size_t>(c)]);
    if (!std::isfinite(out(k))) throw Error(name, "is not a finite number");
    if (std::abs(out(k)) > kMaxRateChange)
      throw Error(name, "is beyond the bound of 1e4 " + std::string(is_angle(c) ? "rad/s^2" : "m/s^2"));
  }
  return out;
}

// tau from a caller: one per actuator, finite, within kMaxTorque (as a torque table's).
TorqueVector torques_of(const Eigen::VectorXd& tau, const char* field) {
  if (tau.size() != kActuatedCount)
    throw Error(field, "has " + std::to_string(tau.size()) + " entries; the model has " + std::to_string(kActuatedCount) + " actuators");
  for (int k = 0; k < kActuatedCount; ++k) {
    const std::string name = std::string(field) + "." + std::string(kActuatorNames[static_cast<std::size_t>(k)]);
    if (!std::isfinite(tau(k))) throw Error(name, "is not a finite number");
    if (std::abs(tau(k)) > kMaxTorque) throw Error(name, "is beyond the bound of 1e9 (N m or N)");
  }
  return tau;
}

std::string info_text() {
  nlohmann::json info;
  std::vector<std::string> coordinates, units, frames, scenarios, commanded, actuators, contacts;
  for (auto n : gen::kCoordinateNames) coordinates.emplace_back(n);
  for (auto u : gen::kCoordinateUnits) units.emplace_back(u);
  for (auto f : gen::kFrameNames) frames.emplace_back(f);
  nlohmann::json defaults = nlohmann::json::object(), param_units = nlohmann::json::object();
  const Params& p = settings().params;
  for (const auto& info_p : gen::kParamInfo) {
    defaults[std::string(info_p.name)] = p.*info_p.member;
    param_units[std::string(info_p.name)] = std::string(info_p.unit);
  }
  for (const auto& id : scenario_ids()) scenarios.push_back(id);
  for (int k : kCommandedSpeeds) commanded.emplace_back(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
  for (const std::string_view a : kActuatorNames) actuators.emplace_back(a);
  for (int c = 0; c < kContactCount; ++c) contacts.push_back(contact_name(c));
  info["name"] = std::string(gen::kModelName);
  info["description"] = std::string(gen::kModelDescription);
  info["coordinates"] = coordinates;
  info["units"] = units;
  info["input_count"] = kInputCount;
  info["frames"] = frames;
  info["params"] = defaults;
  info["param_units"] = param_units;
  info["scenarios"] = scenarios;
  info["commanded"] = commanded;
  info["actuators"] = actuators;
  info["contacts"] = contacts;
  return info.dump();
}

std::pair<Eigen::VectorXd, std::string> api_ik(const std::string& request_json) {
  Coordinates s;
  const auto result = solve_ik_request(parse_ik_request(parse_json(request_json, "request")), nullptr, &s);
  return {Eigen::VectorXd(s), result.dump()};
}

std::pair<Eigen::MatrixXd, std::vector<Eigen::Matrix3d>> api_fk(const Eigen::VectorXd& s_in, const std::string& params_json) {
  const Model model(params_of(params_json));
  Data data;
  forward_kinematics(model, data, coordinates_of(s_in, "s"));
  std::vector<Eigen::Matrix3d> rotations;
  for (const auto& R : data.frame_rotations) rotations.emplace_back(R);
  return {Eigen::MatrixXd(data.frame_positions.transpose()), rotations};
}

std::pair<Eigen::VectorXd, double> api_dependent_rates(const Eigen::VectorXd& s_in, const Eigen::VectorXd& rates,
                                                       const std::vector<std::string>& pair, const std::string& params_json) {
  const Model model(params_of(params_json));
  Data data;
  const Coordinates s = coordinates_of(s_in, "s");
  if (rates.size() != kInputCount) throw Error("rates", "needs one entry per input (" + std::to_string(kInputCount) + ")");
  for (int k = 0; k < kInputCount; ++k) {
    const std::string name = "rates." + std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    if (!std::isfinite(rates(k))) throw Error(name, "is not a finite number");
    check_rate_bound(k, rates(k), name);
  }
  Coordinates sdot = Coordinates::Zero();
  sdot.head<kInputCount>() = rates;
  const DependentPair dependent = pair.empty() ? default_pair() : dependent_pair(pair);
  solve_dependent_rates(model, data, s, sdot, dependent);
  check_result(sdot, "sdot");
  return {Eigen::VectorXd(sdot), data.cond_J_beta};
}

NamedArrays api_inverse_dynamics(const Eigen::VectorXd& s_in, const Eigen::VectorXd& u_in, const Eigen::VectorXd& u_dot_in,
                                 const std::string& params_json, const std::string& weighting_json) {
  const CommandVector u = speeds_of(u_in, "u"), u_dot = accelerations_of(u_dot_in, "u_dot");
  const Model model(params_of(params_json));
  Data data;
  DynamicsTerms terms;
  const Coordinates s = coordinates_of(s_in, "s");
  const Weighting weighting = parse_weighting(parse_json(weighting_json, "weighting"), "weighting");
  inverse_dynamics(model, data, s, u, u_dot, terms);
  DynamicsTerms motion;  // M, b and Q_gravity, which the result returns too (reduced_dynamics)
  equations_of_motion(model, data, s, u, motion);
  const TorqueVector tau = weighting.kind == Weighting::Kind::contacts
                               ? distribute_torques_on_contacts(model, data, s, terms).tau
                               : distribute_torques(terms.J_beta, terms.Qstar, weighting);
  check_result(tau, "tau");
  check_result(motion.M, "M");
  NamedArrays out{{"tau", Eigen::VectorXd(tau)},           {"Qstar", Eigen::VectorXd(terms.Qstar)},
                  {"M", Eigen::MatrixXd(motion.M), false}, {"b", Eigen::VectorXd(motion.b)},
                  {"Q_gravity", Eigen::VectorXd(motion.Q_gravity)}, {"J_beta", Eigen::MatrixXd(terms.J_beta), false},
                  {"sdot", Eigen::VectorXd(terms.sdot)}};
  // The ground's forces for these torques (one column per contact, in .contacts' order; K0) and the
  // margins: inverse_dynamics above left data's factorizations at s.
  if constexpr (kContactCount > 0) {
    ContactForces forces;
    Stability st;
    contact_forces(model, data, s, terms, tau, forces);
    stability(model, data, s, forces, st);
    check_result(forces.force, "contact_force");
    out.push_back({"contact_force", Eigen::MatrixXd(forces.force.transpose()), false});
    out.push_back({"contact_point", Eigen::MatrixXd(forces.point.transpose()), false});
    out.push_back({"friction_margin", Eigen::VectorXd(forces.friction_margin)});
    out.push_back({"margins", Eigen::VectorXd(Eigen::Vector3d(st.static_margin, st.zmp_margin, st.tip_angle))});
  }
  return out;
}

NamedArrays api_forward_dynamics(const Eigen::VectorXd& s_in, const Eigen::VectorXd& u_in, const Eigen::VectorXd& tau_in,
                                 const std::string& params_json) {
  const CommandVector u = speeds_of(u_in, "u");
  const TorqueVector tau = torques_of(tau_in, "tau");
  const Model model(params_of(params_json));
  Data data;
  DynamicsTerms terms;
  const Coordinates s = coordinates_of(s_in, "s");
  CommandVector u_dot;
  forward_dynamics(model, data, s, u, tau, u_dot, terms);
  check_result(u_dot, "u_dot");
  check_result(terms.sddot, "sddot");
  return {{"u_dot", Eigen::VectorXd(u_dot)},
          {"sddot", Eigen::VectorXd(terms.sddot)},
          {"sdot", Eigen::VectorXd(terms.sdot)},
          {"Qstar", Eigen::VectorXd(terms.Qstar)},
          {"M", Eigen::MatrixXd(terms.M), false}};
}

// A run's summary as named arrays (model_api.hpp's SimulationOutcome::summary).
NamedArrays summary_arrays(const RunSummary& summary, bool dynamics) {
  NamedArrays out;
  if (summary.samples == 0) return out;
  out.push_back({"peak_cond_J_beta", Eigen::VectorXd::Constant(1, summary.worst_cond)});
  if (gen::kHasClearance) out.push_back({"min_clearance", Eigen::VectorXd::Constant(1, summary.min_clearance)});
  if (dynamics) {
    Eigen::VectorXd rms(kActuatedCount);
    for (int k = 0; k < kActuatedCount; ++k) rms(k) = summary.rms_tau(k);
    out.push_back({"peak_tau", Eigen::VectorXd(summary.peak_tau)});
    out.push_back({"rms_tau", rms});
    // Will it slip or tip: the supporting contacts' smallest normal force and friction margin (N),
    // and the smallest force-angle margin (rad), as the report's contacts table gives them.
    if (summary.normal.contact >= 0) {
      out.push_back({"min_normal_force", Eigen::VectorXd::Constant(1, summary.normal.value)});
      out.push_back({"min_friction_margin", Eigen::VectorXd::Constant(1, summary.friction.value)});
    }
    if (summary.tip.contact >= 0) out.push_back({"min_tip_margin", Eigen::VectorXd::Constant(1, summary.tip.value)});
  }
  return out;
}

SimulationOutcome api_simulate(const std::string& scenario_json, const std::string& params_json, long every, TorqueFunction torques,
                               const SimulationSink& sink) {
  const nlohmann::json j = parse_json(scenario_json, "scenario");
  const nlohmann::json overrides = parse_json(params_json, "params");
  if (!overrides.is_object()) throw Error("params", "must be an object {\"name\": value}, got " + excerpt(overrides));
  if (every < 1) throw Error("every", "must be at least 1 (keep every k-th sample), got " + std::to_string(every));
  // A function as the torque source: a controller in the loop, called at every evaluation of the
  // right-hand side (each stage of a step) with t, s and u.
  TorqueSource function;
  if (torques)
    function = [f = std::move(torques)](double t, const Coordinates& s, const CommandVector& u) -> TorqueVector {
      const Eigen::VectorXd tau = f(t, Eigen::VectorXd(s), Eigen::VectorXd(u));
      if (tau.size() != kActuatedCount)
        throw Error("torques", "the function returned " + std::to_string(tau.size()) + " numbers; the model has " +
                                   std::to_string(kActuatedCount) + " actuators");
      // Within a torque table's bound (a 1e300 overflowed the step into NaN, and the run stopped for
      // another cause); a non-finite torque the run itself names.
      for (int k = 0; k < kActuatedCount; ++k)
        if (std::isfinite(tau(k)) && std::abs(tau(k)) > kMaxTorque)
          throw Error("torques." + std::string(kActuatorNames[static_cast<std::size_t>(k)]),
                      fmt::format("the function gave {:g} at t = {:.6f} s, beyond the bound of {:g} (N m or N)", tau(k), t, kMaxTorque));
      return tau;
    };
  // The overrides win over the scenario's own "params" (an id's, a file's or an object's), key by
  // key, and go through the scenario's checks with them.
  nlohmann::json scenario = j.is_string() ? read_scenario_json(j.get<std::string>()) : j;
  if (!overrides.empty() && scenario.is_object())
    for (const auto& [name, value] : overrides.items()) scenario["params"][name] = value;
  const Scenario sc = parse_scenario(scenario, {}, j.is_string() ? scenario_directory(j.get<std::string>()) : std::string(),
                                     std::move(function));
  const std::vector<std::string> header = trajectory_header(sc);
  const long kept = (sc.samples() + every - 1) / every;
  sink.begin(header, kept);
  long index = 0, rows = 0;
  const bool dynamics = sc.weighting || sc.driven_by_torques();
  RunSummary summary;
  const Trajectory run = simulate_each(sc, [&](const Sample& smp) {
    if (sink.poll) sink.poll();
    summary.add(smp, dynamics);
    if (index++ % every != 0 || rows >= kept) return;
    sink.row(rows++, trajectory_row(smp, sc));
  });
  return {sc.id, run.complete, run.error, run.complete ? std::string() : error_kind_name(run.stop_kind), run.evaluations, rows,
          summary_arrays(summary, dynamics)};
}

// The fast paths (model_api.hpp): a workspace, and states by the array.
struct Workspace {
  Model model;
  Data data;
  DynamicsTerms terms;
  explicit Workspace(const Params& p) : model(p) {}
};

void* api_new_workspace(const std::string& params_json) { return new Workspace(params_of(params_json)); }
void api_delete_workspace(void* workspace) { delete static_cast<Workspace*>(workspace); }

// Row `row` of a caller's array as coordinates: the cheap test first, the named error of
// coordinates_of only for a state that fails it ("s.<name>" for one state, "s[row].<name>" in a batch).
Coordinates state_row(const double* s, long row, long count) {
  const Eigen::Map<const Coordinates> state(s + row * kCoordinateCount);
  // Within the smaller of the two bounds: within its own (no unit to look up); else the full check,
  // which throws for a value beyond its unit's bound and lets the others through.
  constexpr double kWithinEither = std::min(kMaxAngle, kMaxPosition);
  for (int k = 0; k < kCoordinateCount; ++k)
    if (!(std::abs(state(k)) <= kWithinEither)) {
      const std::string field = count == 1 ? std::string("s") : "s[" + std::to_string(row) + "]";
      coordinates_of(Eigen::VectorXd(state), field.c_str());
      break;
    }
  return state;
}

void api_fk_many(void* workspace, const double* s, long count, double* positions, double* rotations) {
  auto& w = *static_cast<Workspace*>(workspace);
  for (long row = 0; row < count; ++row) {
    forward_kinematics(w.model, w.data, state_row(s, row, count));
    double* p = positions + row * 3 * gen::kFrameCount;
    double* r = rotations + row * 9 * gen::kFrameCount;
    // As they lie in Data (positions one frame's x, y, z after another; each rotation by columns):
    // whole blocks copied, no element by element transposition (that took as long as the FK).
    static_assert(sizeof(gen::FramePositions) == sizeof(double) * 3 * gen::kFrameCount);
    std::memcpy(p, w.data.frame_positions.data(), sizeof(double) * 3 * gen::kFrameCount);
    for (int f = 0; f < gen::kFrameCount; ++f)
      std::memcpy(r + 9 * f, w.data.frame_rotations[static_cast<std::size_t>(f)].data(), sizeof(double) * 9);
  }
}

void api_inverse_dynamics_many(void* workspace, const std::string& weighting_json, const double* s, const double* u,
                               const double* u_dot, long count, double* tau, double* Qstar) {
  auto& w = *static_cast<Workspace*>(workspace);
  const Weighting weighting = parse_weighting(parse_json(weighting_json, "weighting"), "weighting");
  if (weighting.kind == Weighting::Kind::contacts)
    throw Error("weighting", "the contacts' distribution solves an optimisation per state: call inverse_dynamics state by state");
  for (long row = 0; row < count; ++row) {
    const Coordinates state = state_row(s, row, count);
    const CommandVector speeds = Eigen::Map<const CommandVector>(u + row * kCommandedCount);
    const CommandVector rates = Eigen::Map<const CommandVector>(u_dot + row * kCommandedCount);
    if (!speeds.allFinite() || !rates.allFinite() || speeds.cwiseAbs().maxCoeff() > std::min(kMaxLinearRate, kMaxAngularRate) ||
        rates.cwiseAbs().maxCoeff() > kMaxRateChange) {  // the named errors of the state-by-state path
      const std::string field = count == 1 ? std::string() : "[" + std::to_string(row) + "]";
      speeds_of(Eigen::VectorXd(speeds), ("u" + field).c_str());
      accelerations_of(Eigen::VectorXd(rates), ("u_dot" + field).c_str());
    }
    inverse_dynamics(w.model, w.data, state, speeds, rates, w.terms);
    const TorqueVector t = distribute_torques(w.terms.J_beta, w.terms.Qstar, weighting);
    if (!t.allFinite()) throw Error("tau[" + std::to_string(row) + "]", "is not finite at these inputs (a state the model does not compute)");
    Eigen::Map<TorqueVector>(tau + row * kActuatedCount) = t;
    Eigen::Map<CommandVector>(Qstar + row * kCommandedCount) = w.terms.Qstar;
  }
}

}  // namespace

const ModelApi& api() {
  static const ModelApi functions{&info_text,           &api_ik,           &api_fk, &api_dependent_rates, &api_inverse_dynamics,
                                  &api_forward_dynamics, &api_simulate, &api_new_workspace, &api_delete_workspace, &api_fk_many,
                                  &api_inverse_dynamics_many};
  return functions;
}

WLX_COMMANDS_END
