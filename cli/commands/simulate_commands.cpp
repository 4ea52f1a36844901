// `wlx simulate` and `wlx verify nonholonomic`.
#include "per_model.hpp"
#include "model_commands.hpp"
#include "bounded_input.hpp"
#include "interrupt.hpp"
#include "output_checks.hpp"
#include "outputs.hpp"
#include "run_summary.hpp"
#include "scenario_io.hpp"

#include <fmt/format.h>
#include <wlx/support/csv.hpp>
#include <wlx/error.hpp>

#include <filesystem>
#include <optional>

WLX_COMMANDS_BEGIN

namespace {
bool has_level_rows(int contact) {
  for (int row : gen::kContacts[static_cast<std::size_t>(contact)].level_rows)
    if (row >= 0) return true;
  return false;
}
}  // namespace

std::vector<std::string> trajectory_header(const Scenario& sc) {
  const bool dynamics = sc.weighting || sc.driven_by_torques();
  const auto name = [](int k) { return std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]); };
  std::vector<std::string> h{"t"};
  for (int k = 0; k < kCoordinateCount; ++k) h.push_back(name(k));
  for (int w = 0; w < kWheelCount; ++w)
    for (const char* axis : {"x_", "y_"}) h.push_back(axis + contact_column_stem(w));
  for (const char* quantity : {"nh_residual_", "spin_rate_"})
    for (const gen::WheelInfo& wheel : gen::kWheels) h.push_back(quantity + std::string(wheel.name));
  for (int k = 0; k < kInputCount; ++k) h.push_back(name(k) + "_dot");
  h.emplace_back("cond_J_beta");
  // Only a model with a clearance box has the column (its sample's clearance is +infinity without
  // one, which no CSV holds): readers look for the column, as for the dynamics columns.
  if (gen::kHasClearance) h.emplace_back("clearance");
  for (int w = 0; w < kWheelCount; ++w)
    for (const char* axis : {"vx_", "vy_", "vz_"}) h.push_back(axis + contact_column_stem(w));
  if (dynamics) {
    for (const std::string_view a : kActuatorNames) h.push_back("tau_" + std::string(a));
    for (int k : kCommandedSpeeds) h.push_back("Qstar_" + name(k));
  }
  if (sc.driven_by_torques()) {
    for (int k : kCommandedSpeeds) h.push_back(name(k) + "_ddot");
    for (const char* energy : {"kinetic", "potential", "power"}) h.emplace_back(energy);
  }
  if (dynamics && kContactCount > 0) {
    for (int c = 0; c < kContactCount; ++c) {
      const gen::ContactInfo& info = gen::kContacts[static_cast<std::size_t>(c)];
      const std::string stem = contact_name(c);
      for (const char* q : {"f_x_", "f_y_", "f_n_", "f_t_"}) h.push_back(q + stem);
      if (info.wheel >= 0)
        for (const char* q : {"f_lat_", "f_long_"}) h.push_back(q + stem);
      if (has_level_rows(c)) h.push_back("moment_" + stem);
      if (info.supports) h.push_back("friction_margin_" + stem);
    }
    for (const char* q : {"com_x", "com_y", "com_z", "zmp_x", "zmp_y", "margin_static", "margin_zmp", "margin_tip",
                          "momentum_residual"})
      h.emplace_back(q);
  }
  return h;
}

std::vector<double> trajectory_row(const Sample& smp, const Scenario& sc) {
  const bool dynamics = sc.weighting || sc.driven_by_torques();
  std::vector<double> row{smp.t};
  for (int k = 0; k < kCoordinateCount; ++k) row.push_back(smp.s(k));
  for (int k = 0; k < smp.contacts.size(); ++k) row.push_back(smp.contacts(k));
  for (int w = 0; w < kWheelCount; ++w) row.push_back(smp.nh_residual(w));
  for (int w = 0; w < kWheelCount; ++w) row.push_back(smp.spin_rate(w));
  for (int k = 0; k < kInputCount; ++k) row.push_back(smp.sdot(k));
  row.push_back(smp.cond_J_beta);
  if (gen::kHasClearance) row.push_back(smp.clearance);
  for (int w = 0; w < kWheelCount; ++w)
    for (int i = 0; i < 3; ++i) row.push_back(smp.contact_velocity(i, w));
  if (dynamics) {
    for (int k = 0; k < kActuatedCount; ++k) row.push_back(smp.tau(k));
    for (int k = 0; k < kCommandedCount; ++k) row.push_back(smp.Qstar(k));
  }
  if (sc.driven_by_torques()) {
    for (int k = 0; k < kCommandedCount; ++k) row.push_back(smp.u_dot(k));
    row.insert(row.end(), {smp.kinetic, smp.potential, smp.power});
  }
  if (dynamics && kContactCount > 0) {
    const ContactForces& f = smp.forces;
    for (int c = 0; c < kContactCount; ++c) {
      const gen::ContactInfo& info = gen::kContacts[static_cast<std::size_t>(c)];
      row.insert(row.end(), {f.force(0, c), f.force(1, c), f.normal(c), f.tangential(c)});
      if (info.wheel >= 0) row.insert(row.end(), {f.lateral(c), f.longitudinal(c)});
      if (has_level_rows(c)) row.push_back(f.moment.col(c).norm());
      if (info.supports) row.push_back(f.friction_margin(c));
    }
    const Stability& st = smp.stability;
    row.insert(row.end(), {st.com.x(), st.com.y(), st.com.z(), st.zmp.x(), st.zmp.y(), st.static_margin, st.zmp_margin,
                           st.tip_angle, smp.momentum_residual});
  }
  return row;
}

void write_trajectory(const std::string& path, const Trajectory& tr, const Scenario& sc) {
  CsvWriter csv(path, trajectory_header(sc));
  for (const auto& smp : tr.samples) csv.row(trajectory_row(smp, sc));
  csv.commit();
}

int run_simulate(const ModelOptions& model_options, const SimulateOptions& o) {
  if (o.list) {
    for (const auto& id : scenario_ids()) {
      const auto j = model_scenario_json(id);
      fmt::print("{:<8} {}\n", id, j.value("description", ""));
      // A closed pipe or a full disk: stop and say so (main checks stdout again at the end).
      if (std::ferror(stdout)) break;
    }
    return 0;
  }
  nlohmann::json file = read_scenario_json(o.scenario);
  // --integrator replaces the file's before it is read, so that what depends on the integrator
  // (a tolerance applies to dopri5 only) is checked against the one that runs.
  if (!o.integrator.empty()) {
    if (!integrator_from_name(o.integrator)) throw Error("--integrator", fmt::format("must be rk4, euler or dopri5, got '{}'", o.integrator));
    if (file.is_object()) file["integrator"] = o.integrator;
  }
  Scenario sc = parse_scenario(file, load_params(model_options), scenario_directory(o.scenario));
  if (o.dt) sc.dt = *o.dt;
  if (o.tolerance) {
    if (sc.integrator != Integrator::dopri5)
      throw Error("--tolerance", "applies to the adaptive integrator only: add --integrator dopri5");
    sc.tolerance = *o.tolerance;
  }
  if (!o.weighting.empty()) {
    const std::string& w = o.weighting;
    if (w != "model-weights" && w != "contribution" && w != "contacts" && w != "1" && w != "2" && w != "3")
      throw Error("--weighting", fmt::format("must be model-weights, contribution or contacts (or 1, 2, 3), got '{}'", excerpt(w)));
    sc.weighting = w == "model-weights" || w == "1" ? Weighting::model_weights()
                   : w == "contribution" || w == "2" ? Weighting::contribution()
                                                     : Weighting::contacts();
  }
  sc.validate();
  prepare_out_dir("--out", o.out_dir);
  return stream_simulation(sc, sc.id.empty() ? o.scenario : sc.id, o.out_dir);
}

int run_verify_nonholonomic(const ModelOptions& model_options, const std::string& out_dir) {
  const Params params = load_params(model_options);
  constexpr double kLimit = 1e-10;
  bool ok = true;
  prepare_out_dir("--out", out_dir);
  std::string header = fmt::format("{:<6} {:>8}", "run", "samples");
  for (const gen::WheelInfo& wheel : gen::kWheels)
    header += fmt::format(" {:>16}", fmt::format("max |res_{}| m/s", wheel.name));
  fmt::print("{} {:>14}\n", header, "max cond");
  std::vector<std::string> ids;  // the model's scenarios marked "verify": "nonholonomic"
  for (const auto& id : scenario_ids())
    if (model_scenario_json(id).value("verify", "") == "nonholonomic") ids.push_back(id);
  if (ids.empty()) throw Error("verify nonholonomic", "the model has no scenario marked \"verify\": \"nonholonomic\"");
  for (const std::string& id : ids) {
    throw_if_interrupted();
    const Scenario sc = parse_scenario(model_scenario_json(id), params, model_scenario_directory());
    const Trajectory tr = simulate(sc);
    write_trajectory((std::filesystem::path(out_dir) / (id + ".csv")).string(), tr, sc);
    const RunSummary summary = summarize(tr, false);
    const WheelVector& worst = summary.worst_residual;
    const double cond = summary.worst_cond;
    const bool pass = tr.complete && summary.worst_rolling_residual() <= kLimit;
    ok = ok && pass;
    std::string line = fmt::format("{:<6} {:>8}", id, tr.samples.size());
    for (int w = 0; w < kWheelCount; ++w)
      line += tr.samples.empty() ? fmt::format(" {:>16}", "-") : fmt::format(" {:>16.2e}", worst(w));
    if (tr.samples.empty())  // nothing computed: no maxima to print
      fmt::print("{} {:>14}  FAIL: {}\n", line, "-", tr.error);
    else
      fmt::print("{} {:>14.3g}{}\n", line, cond, pass ? "" : (tr.complete ? "  FAIL" : "  FAIL: " + tr.error));
  }
  fmt::print("\nresidual = v_W . n_W from the generated C(s) and the solved rates; CSV files: {}/\n{}\n",
             out_dir, ok ? "all runs pass (every residual <= 1e-10 m/s)" : "SOME RUNS FAIL");
  return ok ? 0 : 1;
}

WLX_COMMANDS_END
