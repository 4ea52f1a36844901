// `wlx fk`, the parameters of --params, and this model's entry in the registry of built-in models.
#include "bounded_input.hpp"
#include "interrupt.hpp"
#include "input.hpp"
#include "limits.hpp"
#include "model_commands.hpp"
#include "scenario_io.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <wlx/support/bounded_file.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>

#include <cmath>
#include <fstream>
#include <iostream>
#include <numbers>

WLX_COMMANDS_BEGIN

namespace {

// Rounding residue such as -1e-17 would print as "-0.0000" in a table.
double tidy(double v) { return std::abs(v) < 5e-13 ? 0.0 : v; }

constexpr std::size_t kMaxParamsFileBytes = std::size_t{1} << 20;

}  // namespace

Params load_params(const ModelOptions& model) {
  if (model.params_file.empty()) return settings().params;
  // Bounded, regular files only (wlx/support/bounded_file.hpp): a FIFO without a writer is an error, not a hang.
  const BoundedRead file = read_bounded_file(model.params_file, kMaxParamsFileBytes);
  if (!file.ok()) {
    if (file.error.rfind("cannot open", 0) == 0)
      throw Error("--params", fmt::format("cannot open '{}' for reading{}", excerpt(model.params_file), file.error.substr(14)));
    throw Error("--params", fmt::format("'{}' {}", excerpt(model.params_file), file.error));
  }
  const nlohmann::json j = parse_json_bounded(file.text, model.params_file);
  // The file holds {"name": value, ...}, or the same under "params" (like an ik request).
  try {
    return parse_params(j.is_object() && j.contains("params") && j.size() == 1 ? j.at("params") : j);
  } catch (const Error& e) {
    throw Error(excerpt(model.params_file) + ": " + e.field(), e.reason());
  }
}

// `wlx fk`: a pose from stdin (any of the coordinates; missing inputs take the nominal state,
// missing dependent joints are solved by the IK when none is given: the closed form, Newton's
// method for a limb without one), its dependent joints and the forward kinematics of every frame.
int run_fk(const ModelOptions& model_options, bool as_json) {
  const Model model(load_params(model_options));
  const std::string text = read_all_capped(std::cin, "stdin", kMaxLineBytes);
  throw_if_interrupted();
  const nlohmann::json j =
      text.find_first_not_of(" \t\r\n") == std::string::npos ? nlohmann::json::object() : parse_json_bounded(text, "stdin");
  if (!j.is_object()) throw Error("stdin", fmt::format("expected a JSON object of coordinates, e.g. {{\"{}\": 1.8}}", gen::kCoordinateNames[0]));
  std::vector<std::string> names;
  for (const auto& n : gen::kCoordinateNames) names.emplace_back(n);
  // A branch picks one of the IK's solutions: fk solves for none of its own choosing, so a branch
  // is a question for `wlx ik`, whose answer's joints fk then takes.
  if (j.contains("branch"))
    throw Error(
        "branch",
        fmt::format("unknown key: branches apply to the IK (`wlx ik` takes \"branch\"), not to fk, which takes all "
                    "joint values: give fk the {} dependent joints of the branch you want (from `wlx ik`'s answer)",
                    kDependentCount));
  reject_unknown_keys(j, names, "");
  Coordinates s = nominal_inputs();
  int dependents_given = 0;
  for (int k = 0; k < kCoordinateCount; ++k) {
    const std::string name(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    if (!j.contains(name)) continue;
    s(k) = si_value(j.at(name), name, quantity_of(is_angle(k)));  // one grammar with ik and scenarios: SI or {"deg": x}
    dependents_given += k >= kInputCount;
  }
  // How the dependent joints are found when none is given: the closed form where wlx-gen derived
  // one, Newton's method for the other limbs (limb_methods).
  const auto methods = limb_methods(IkMethod::closed_form);
  if (dependents_given == 0) solve_ik_closed_form(model, s, {});
  else if (dependents_given != kDependentCount)
    throw Error("stdin", fmt::format("give all {} dependent joints or none, {} given; with none, fk solves them by {}",
                                     kDependentCount, dependents_given, methods_in_words(methods)));
  Data data;
  forward_kinematics(model, data, s);
  closure(model, data, s, false);
  const double residual = data.Phi.cwiseAbs().maxCoeff();
  if (as_json) {
    nlohmann::ordered_json out;
    for (int k = 0; k < kCoordinateCount; ++k) out["coordinates"][std::string(gen::kCoordinateNames[k])] = s(k);
    for (int f = 0; f < gen::kFrameCount; ++f) {
      auto& fr = out["frames"][std::string(gen::kFrameNames[f])];
      fr["position"] = {data.frame_positions(0, f), data.frame_positions(1, f), data.frame_positions(2, f)};
      const auto& R = data.frame_rotations[static_cast<std::size_t>(f)];
      fr["rotation"] = {{R(0, 0), R(0, 1), R(0, 2)}, {R(1, 0), R(1, 1), R(1, 2)}, {R(2, 0), R(2, 1), R(2, 2)}};
    }
    out["closure_residual"] = residual;
    // Per limb how its dependent joints were found: "given", or the method that solved them.
    nlohmann::ordered_json solved = nlohmann::ordered_json::object();
    for (Limb limb : kLimbs)
      solved[std::string(gen::kLimbs[static_cast<std::size_t>(limb)].name)] =
          dependents_given ? "given" : method_name(methods[static_cast<std::size_t>(limb)]);
    out["limb_methods"] = solved;
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  // SI like every other input and output (rad); degrees beside them only for reading.
  fmt::print("{} pose, dependent joints {}:\n", gen::kModelName,
             dependents_given ? "as given" : "by " + methods_in_words(methods));
  for (int k = kInputCount; k < kCoordinateCount; ++k) {
    const std::string_view unit = gen::kCoordinateUnits[static_cast<std::size_t>(k)];
    fmt::print("  {:<12} {:>10.6f} {:<3}", gen::kCoordinateNames[k], tidy(s(k)), unit);
    if (is_angle(k)) fmt::print(" {:>10.4f} deg", tidy(s(k)) * 180 / std::numbers::pi);
    fmt::print("\n");
  }
  fmt::print("\nForward kinematics, frame origins in K0 (m):\n  {:<12} {:>9} {:>9} {:>9}\n", "frame", "x", "y", "z");
  for (int f = 0; f < gen::kFrameCount; ++f)
    fmt::print("  {:<12} {:>9.4f} {:>9.4f} {:>9.4f}\n", gen::kFrameNames[f], tidy(data.frame_positions(0, f)),
               tidy(data.frame_positions(1, f)), tidy(data.frame_positions(2, f)));
  fmt::print("\nclosure residual max|Phi| = {:.2e}; total mass {:.2f} kg\n", residual, model.total_mass());
  return 0;
}

extern const char* const kEmbeddedDescription;  // the model's model.json, embedded by CMake

const ModelCommands& entry() {
  static const ModelCommands commands{gen::kModelName, gen::kModelDescription, &run_fk, &run_ik, &run_verify_ik,
                                      &run_verify_nonholonomic, &run_simulate, &run_report, &run_viewer, &api(),
                                      kEmbeddedDescription};
  return commands;
}

WLX_COMMANDS_END
