// One model's Python functions (compiled once per model, like the runtime: WLX_MODEL names it).
// They take the same JSON the command line reads (the Python package turns dicts into it), and
// reuse the command line's parsing and solving, so the grammar, the checks and the error messages
// are the CLI's own.
#include "../cli/commands/input.hpp"
#include "../cli/commands/limits.hpp"
#include "../cli/commands/outputs.hpp"
#include "../cli/commands/scenario_io.hpp"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <wlx/dynamics.hpp>
#include <wlx/forward_dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace py = pybind11;

WLX_COMMANDS_BEGIN

namespace {

nlohmann::json parse_json(const std::string& text, const char* what) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw Error(what, std::string("not JSON: ") + e.what());
  }
}

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

template <class Vector>
void check_finite(const Vector& v, const char* field) {
  for (Eigen::Index k = 0; k < v.size(); ++k)
    if (!std::isfinite(v(k))) throw Error(std::string(field) + "[" + std::to_string(k) + "]", "is not a finite number");
}

// What a function returns is finite, or it is an error: never NaN torques.
template <class Matrix>
void check_result(const Matrix& m, const char* what) {
  if (!m.allFinite()) throw Error(what, "is not finite at these inputs (a state the model does not compute)");
}

}  // namespace

void bind_python(py::module_& parent) {
  py::module_ m = parent.def_submodule(std::string(gen::kModelName).c_str(), std::string(gen::kModelDescription).c_str());

  py::dict info;
  py::list coordinates, units, frames, parameters, scenarios;
  for (auto n : gen::kCoordinateNames) coordinates.append(std::string(n));
  for (auto u : gen::kCoordinateUnits) units.append(std::string(u));
  for (auto f : gen::kFrameNames) frames.append(std::string(f));
  py::dict defaults;
  const Params p;
  for (const auto& info_p : gen::kParamInfo) defaults[py::str(std::string(info_p.name))] = p.*info_p.member;
  for (const auto& id : scenario_ids()) scenarios.append(id);
  py::list commanded, actuators;
  for (int k : kCommandedSpeeds) commanded.append(std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]));
  for (const std::string_view a : kActuatorNames) actuators.append(std::string(a));
  info["commanded"] = commanded;
  info["actuators"] = actuators;
  info["name"] = std::string(gen::kModelName);
  info["description"] = std::string(gen::kModelDescription);
  info["coordinates"] = coordinates;
  info["units"] = units;
  info["input_count"] = kInputCount;
  info["frames"] = frames;
  info["params"] = defaults;
  info["scenarios"] = scenarios;
  m.attr("info") = info;

  m.def(
      "ik",
      [](const std::string& request_json) {
        Coordinates s;
        const auto result = solve_ik_request(parse_ik_request(parse_json(request_json, "request")), nullptr, &s);
        return py::make_tuple(Eigen::VectorXd(s), result.dump());
      },
      "ik(request_json) -> (s, result_json): what `wlx ik` answers for that request, and all coordinates");

  m.def(
      "fk",
      [](const Eigen::VectorXd& s_in, const std::string& params_json) {
        const Model model(params_of(params_json));
        Data data;
        forward_kinematics(model, data, coordinates_of(s_in, "s"));
        py::list rotations;
        for (const auto& R : data.frame_rotations) rotations.append(Eigen::Matrix3d(R));
        return py::make_tuple(Eigen::MatrixXd(data.frame_positions.transpose()), rotations);
      },
      "fk(s, params_json) -> (positions (frames x 3), [rotation 3 x 3 per frame])");

  m.def(
      "dependent_rates",
      [](const Eigen::VectorXd& s_in, const Eigen::VectorXd& rates, const std::vector<std::string>& pair,
         const std::string& params_json) {
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
        return py::make_tuple(Eigen::VectorXd(sdot), data.cond_J_beta);
      },
      "dependent_rates(s, input_rates, pair, params_json) -> (sdot, cond_J_beta)");

  m.def(
      "inverse_dynamics",
      [](const Eigen::VectorXd& s_in, const Eigen::VectorXd& u_in, const Eigen::VectorXd& u_dot_in, const std::string& params_json,
         const std::string& weighting_json) {
        const CommandVector u = commands_of(u_in, "u"), u_dot = commands_of(u_dot_in, "u_dot");
        const Model model(params_of(params_json));
        Data data;
        DynamicsTerms terms;
        check_finite(u, "u");
        check_finite(u_dot, "u_dot");
        const Coordinates s = coordinates_of(s_in, "s");
        inverse_dynamics(model, data, s, u, u_dot, terms);
        DynamicsTerms motion;  // M, b and Q_gravity, which the result returns too (Kane's sums)
        equations_of_motion(model, data, s, u, motion);
        terms.M = motion.M, terms.b = motion.b, terms.Q_gravity = motion.Q_gravity;
        const TorqueVector tau = distribute_torques(
            terms.J_beta, terms.Qstar, parse_weighting(parse_json(weighting_json, "weighting"), "weighting"));
        check_result(tau, "tau");
        check_result(terms.M, "M");
        py::dict out;
        out["tau"] = Eigen::VectorXd(tau);
        out["Qstar"] = Eigen::VectorXd(terms.Qstar);
        out["M"] = Eigen::MatrixXd(terms.M);
        out["b"] = Eigen::VectorXd(terms.b);
        out["Q_gravity"] = Eigen::VectorXd(terms.Q_gravity);
        out["J_beta"] = Eigen::MatrixXd(terms.J_beta);
        out["sdot"] = Eigen::VectorXd(terms.sdot);
        return out;
      },
      "inverse_dynamics(s, u, u_dot, params_json, weighting_json) -> dict tau, Qstar, M, b, Q_gravity, J_beta, sdot");

  m.def(
      "forward_dynamics",
      [](const Eigen::VectorXd& s_in, const Eigen::VectorXd& u_in, const Eigen::VectorXd& tau_in, const std::string& params_json) {
        const CommandVector u = commands_of(u_in, "u");
        if (tau_in.size() != kActuatedCount)
          throw Error("tau", "has " + std::to_string(tau_in.size()) + " entries; the model has " + std::to_string(kActuatedCount) +
                                 " actuators");
        const TorqueVector tau = tau_in;
        const Model model(params_of(params_json));
        Data data;
        DynamicsTerms terms;
        check_finite(u, "u");
        check_finite(tau, "tau");
        const Coordinates s = coordinates_of(s_in, "s");
        CommandVector u_dot;
        forward_dynamics(model, data, s, u, tau, u_dot, terms);
        check_result(u_dot, "u_dot");
        check_result(terms.sddot, "sddot");
        py::dict out;
        out["u_dot"] = Eigen::VectorXd(u_dot);
        out["sddot"] = Eigen::VectorXd(terms.sddot);
        out["sdot"] = Eigen::VectorXd(terms.sdot);
        out["Qstar"] = Eigen::VectorXd(terms.Qstar);
        out["M"] = Eigen::MatrixXd(terms.M);
        return out;
      },
      "forward_dynamics(s, u, tau, params_json) -> dict u_dot, sddot, sdot, Qstar (= J_beta^T tau), M");

  m.def(
      "simulate",
      [](const std::string& scenario_json, long every, const py::object& torques) {
        const nlohmann::json j = parse_json(scenario_json, "scenario");
        // A Python function as the torque source: a controller in the loop, called at every
        // evaluation of the right-hand side (each stage of a step) with t, s and u. Its own
        // exceptions reach the caller unchanged; a wrong shape is a TypeError, not a stopped run.
        TorqueSource function;
        if (!torques.is_none()) {
          if (!PyCallable_Check(torques.ptr())) throw Error("torques", "must be a function f(t, s, u) -> tau, or None");
          function = [f = py::function(torques)](double t, const Coordinates& s, const CommandVector& u) -> TorqueVector {
            const py::object r = f(t, Eigen::VectorXd(s), Eigen::VectorXd(u));
            Eigen::VectorXd tau;
            try {
              tau = r.cast<Eigen::VectorXd>();
            } catch (const py::cast_error&) {
              throw py::type_error("torques: the function must return " + std::to_string(kActuatedCount) +
                                   " numbers (the order of .actuators), got " + std::string(py::str(py::type::of(r))));
            }
            if (tau.size() != kActuatedCount)
              throw py::type_error("torques: the function returned " + std::to_string(tau.size()) + " numbers; the model has " +
                                   std::to_string(kActuatedCount) + " actuators (.actuators)");
            return tau;
          };
        }
        const Scenario sc = j.is_string() ? parse_scenario(read_scenario_json(j.get<std::string>()), {},
                                                           scenario_directory(j.get<std::string>()), std::move(function))
                                          : parse_scenario(j, {}, {}, std::move(function));
        if (every < 1) throw Error("every", "must be at least 1 (keep every k-th sample), got " + std::to_string(every));
        const std::vector<std::string> header = trajectory_header(sc);
        // The columns are written as the run streams its samples (no table, no copy), and bounded:
        // a run's samples beyond kMaxSimulateBytes are an error before anything is allocated,
        // where `wlx simulate` streams any length to a file.
        const long kept = (sc.samples() + every - 1) / every;
        const double bytes = static_cast<double>(kept) * static_cast<double>(header.size()) * sizeof(double);
        constexpr double kMaxSimulateBytes = 256.0 * 1024 * 1024;
        if (bytes > kMaxSimulateBytes)
          throw Error("every", "the run would keep " + std::to_string(kept) + " samples of " + std::to_string(header.size()) +
                                   " columns (" + std::to_string(static_cast<long>(bytes / (1024 * 1024))) +
                                   " MiB, more than 256 MiB): keep every k-th sample (every=k), shorten the run, or stream it "
                                   "to a file with `wlx simulate`");
        std::vector<py::array_t<double>> columns_out;
        columns_out.reserve(header.size());
        for (std::size_t c = 0; c < header.size(); ++c) columns_out.emplace_back(kept);
        long index = 0, rows = 0;
        const Trajectory run = simulate_each(sc, [&](const Sample& smp) {
          if (index++ % every != 0 || rows >= kept) return;
          const std::vector<double> row = trajectory_row(smp, sc);
          for (std::size_t c = 0; c < row.size(); ++c) columns_out[c].mutable_at(rows) = row[c];
          ++rows;
        });
        py::dict columns;
        for (std::size_t c = 0; c < header.size(); ++c) {
          columns_out[c].resize({rows}, false);  // a run that stopped early: only its samples
          columns[py::str(header[c])] = columns_out[c];
        }
        py::dict out;
        out["columns"] = columns;
        out["id"] = sc.id;
        out["complete"] = run.complete;
        out["stopped"] = run.error;
        out["evaluations"] = run.evaluations;
        return out;
      },
      py::arg("scenario_json"), py::arg("every") = 1, py::arg("torques") = py::none(),
      "simulate(scenario_json, every=1, torques=None) -> dict: columns (the CSV's, as arrays; every k-th sample), complete, "
      "stopped (why, if early); torques: a function f(t, s, u) -> tau driving the run");
}

WLX_COMMANDS_END
