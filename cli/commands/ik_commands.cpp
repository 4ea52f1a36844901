// `wlx ik` and `wlx verify ik`.
#include "per_model.hpp"
#include "bounded_input.hpp"
#include "model_commands.hpp"
#include "input.hpp"
#include "interrupt.hpp"
#include "output_checks.hpp"
#include "outputs.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <wlx/support/diagnostics.hpp>
#include <wlx/support/csv.hpp>
#include <wlx/error.hpp>
#include <wlx/ik_verification.hpp>
#include <wlx/kinematics.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <numbers>

WLX_COMMANDS_BEGIN

nlohmann::ordered_json solve_ik_request(const IkRequest& r, Coordinates* warm, Coordinates* solution) {
  const Model model(r.params);
  Data data;
  Coordinates s = r.s;
  nlohmann::ordered_json out;
  NewtonReport report;  // the limbs Newton's method solved
  if (r.method == IkMethod::closed_form) {
    // The limbs without a closed form by Newton's method: in a batch from the previous answer (each
    // line's solution then follows the last, as with "method": "newton", instead of starting again
    // from the model's start values, which may find another of the limb's solutions), then from
    // the request's start.
    if (warm != nullptr && warm->allFinite())
      for (Limb limb : kLimbs) {
        if (has_closed_form(limb)) continue;
        const LimbBlock block = limb_block(limb);
        for (int j = 0; j < block.size; ++j) s(block.joints[static_cast<std::size_t>(j)]) = (*warm)(block.joints[static_cast<std::size_t>(j)]);
      }
    for (const auto& [index, value] : r.start) s(index) = value;
    solve_ik_closed_form(model, s, r.branches, &report);  // Newton for the limbs without a closed form
    if (warm != nullptr) *warm = s;
  } else {
    // Start: the previous solution in a batch, else the assembled nominal pose (as MOBILE does).
    Coordinates start = nominal_inputs();
    try {
      solve_ik_closed_form(model, start);
    } catch (const Error&) {
      // The nominal pose does not fit this geometry: start from the closed form at the target
      // instead, which names the target's own problem if it has one.
      start = s;
      solve_ik_closed_form(model, start, r.branches);
    }
    if (warm != nullptr && warm->allFinite()) start = *warm;
    s.tail(kDependentCount) = start.tail(kDependentCount);
    for (const auto& [index, value] : r.start) s(index) = value;
    report = solve_ik_newton(model, data, s);
    if (warm != nullptr) *warm = s;
  }
  s.array() += 0.0;  // no "-0.0" in the output
  if (solution != nullptr) *solution = s;
  forward_kinematics(model, data, s);
  for (int k = kInputCount; k < kCoordinateCount; ++k) out[std::string(gen::kCoordinateNames[k])] = s(k);
  for (const auto& wheel : gen::kWheels) {  // the contact points: x_W<wheel>, y_W<wheel>
    out["x_W" + std::string(wheel.name)] = data.frame_positions(0, wheel.contact_frame);
    out["y_W" + std::string(wheel.name)] = data.frame_positions(1, wheel.contact_frame);
  }
  double check = 0;
  for (Limb limb : kLimbs) check = std::max(check, analytic_check(model, data, limb, s).position_error);
  closure(model, data, s, false);
  // A result that does not satisfy the model is an error, never an answer (1e-9: far above
  // rounding, which leaves about 1e-15).
  const double residual = data.Phi.cwiseAbs().maxCoeff();
  if (!(residual <= 1e-9))
    throw Error("closure_residual", fmt::format("{:.3e}: the solution does not satisfy the model's closure", residual));
  out["closure_residual"] = residual;
  out["analytic_check_error"] = check;
  // What solved each limb, not what was asked: a limb without a closed form is Newton's whatever
  // the request's method (README, "wlx ik": the answer's method, limb_methods).
  const auto methods = limb_methods(r.method);
  const auto name = [](Limb limb) { return std::string(gen::kLimbs[static_cast<std::size_t>(limb)].name); };
  out["method"] = overall_method(methods, r.method);
  nlohmann::ordered_json per_limb = nlohmann::ordered_json::object();
  for (Limb limb : kLimbs) per_limb[name(limb)] = method_name(methods[static_cast<std::size_t>(limb)]);
  out["limb_methods"] = per_limb;
  nlohmann::ordered_json branches;
  for (Limb limb : kLimbs) branches[name(limb)] = classify_branch(model, limb, s);
  out["branch"] = branches;
  // The joints' limits (the model file's `limits`, a URDF's <limit>s): said, not enforced, for a
  // solution asked for on a branch, or on none within them.
  if (const int k = first_outside_limits(s); k >= 0) {
    out["within_limits"] = false;
    out["outside_limits"] = describe_outside_limits(s, k);
  } else {
    out["within_limits"] = true;
    out["outside_limits"] = nullptr;
  }
  nlohmann::ordered_json it;
  int total = 0;
  for (Limb limb : kLimbs) {
    if (methods[static_cast<std::size_t>(limb)] != IkMethod::newton) continue;
    it[name(limb)] = report.iterations[static_cast<std::size_t>(limb)];
    total += report.iterations[static_cast<std::size_t>(limb)];
  }
  if (r.method == IkMethod::newton || !it.empty()) {  // Newton's iterations for the limbs it solved, only where it ran
    out["iterations"] = it;
    out["iterations_total"] = total;
  }
  return out;
}

void write_ik_sweep_csv(const std::string& path, const IkSweepResult& r) {
  // A sweep of a limb without a closed form has Newton's solution in the joint columns and no
  // closed-form columns: there was no closed form to check or to compare with.
  std::vector<std::string> header{r.sweep.input};
  for (int k = kInputCount; k < kCoordinateCount; ++k) header.emplace_back(gen::kCoordinateNames[k]);
  for (int w = 0; w < kWheelCount; ++w)
    for (const char* axis : {"x_", "y_"}) header.push_back(axis + contact_column_stem(w));
  if (r.closed_form) {
    for (const char* h : {"check_error_closed_form", "check_error_newton", "level_error_closed_form",
                          "level_error_newton", "newton_minus_closed_form"})
      header.emplace_back(h);
  } else {
    for (const char* h : {"check_error_newton", "level_error_newton"}) header.emplace_back(h);
  }
  for (const char* h : {"newton_iterations", "newton_branch", "cold_start_branch", "within_limits"}) header.emplace_back(h);
  CsvWriter csv(path, header);
  for (const auto& p : r.points) {
    std::vector<double> row{p.value};
    for (int k = kInputCount; k < kCoordinateCount; ++k) row.push_back(r.solution(p)(k));
    for (int k = 0; k < p.contacts.size(); ++k) row.push_back(p.contacts(k));
    if (r.closed_form)
      row.insert(row.end(), {p.check_closed_form.position_error, p.check_newton.position_error,
                             p.check_closed_form.level_error, p.check_newton.level_error, p.newton_difference});
    else
      row.insert(row.end(), {p.check_newton.position_error, p.check_newton.level_error});
    row.insert(row.end(), {static_cast<double>(p.newton_iterations), static_cast<double>(p.newton_branch),
                           static_cast<double>(p.cold_newton_branch), p.within_limits ? 1.0 : 0.0});
    csv.row(row);
  }
  csv.commit();
}

int run_ik(const ModelOptions& model_options, bool batch) {
  const Params base = load_params(model_options);
  if (!batch) {
    const std::string text = read_all_capped(std::cin, "stdin", kMaxLineBytes);
    throw_if_interrupted();  // a signal ends the read early: the text is not the whole request
    const nlohmann::json j = parse_json_bounded(text, "stdin");
    std::cout << solve_ik_request(parse_ik_request(j, base), nullptr).dump() << "\n";
    return 0;
  }
  std::string line;
  long number = 0, failures = 0;
  Coordinates warm = Coordinates::Constant(std::numeric_limits<double>::quiet_NaN());
  for (LineRead read; (read = read_line_capped(std::cin, line)) != LineRead::end;) {
    ++number;
    throw_if_interrupted();
    // Stop computing for an output nobody receives (a closed pipe, a full disk).
    if (std::ferror(stdout)) break;
    if (read == LineRead::line && line.find_first_not_of(" \t\r") == std::string::npos) continue;
    try {
      if (read == LineRead::too_long)
        throw Error("", fmt::format("longer than {} bytes; the line was skipped", kMaxLineBytes));
      const nlohmann::json j = parse_json_bounded(line, "");
      std::cout << solve_ik_request(parse_ik_request(j, base), &warm).dump() << "\n";
    } catch (const Error& e) {
      ++failures;
      wlx::diagnose("wlx ik: line {}: {}\n", number, e.what());
      // replace: an ill-formed byte in a message must not end the batch (excerpts are valid UTF-8 already).
      std::cout << nlohmann::ordered_json{{"error", e.what()}, {"kind", error_kind_name(e.kind())}, {"line", number}}.dump(-1, ' ', false,
                                                                                     nlohmann::json::error_handler_t::replace)
                << "\n";
    }
  }
  throw_if_interrupted();
  std::string reason;
  if (!stdout_ok(reason)) throw OutputError("stdout", fmt::format("writing failed at input line {} ({})", number, reason));
  if (failures > 0) wlx::diagnose("wlx ik: {} of the input lines failed\n", failures);
  return failures > 0 ? 2 : 0;
}

int run_verify_ik(const ModelOptions& model_options, const std::string& out_dir, const std::vector<std::string>& sweep_ids) {
  std::vector<IkSweep> sweeps;
  if (sweep_ids.empty()) {
    sweeps = model_ik_sweeps();
  } else {
    for (const auto& id : sweep_ids) {
      const IkSweep* s = find_ik_sweep(id);
      if (s == nullptr) {
        std::vector<std::string> ids;
        for (const auto& t : model_ik_sweeps()) ids.push_back(t.id);
        const std::string hint = nearest(id, ids);
        throw Error("--sweep", fmt::format("no sweep '{}'{}", id, hint.empty() ? "" : "; did you mean '" + hint + "'?"));
      }
      sweeps.push_back(*s);
    }
  }
  const Model model(load_params(model_options));
  prepare_out_dir("--out", out_dir);
  Data data;
  constexpr double kLimit = 1e-10;  // m: the pass/fail bound of the analytic check
  bool ok = true;
  // The closed form's columns only where a swept limb has one; a sweep of a limb without one shows
  // "-" there, and the lines below the table say why (its closed form would be Newton's method
  // again, so a comparison would prove nothing).
  std::vector<std::string> without;  // "<limb title> (<sweep ids>)" for each limb without a closed form
  std::vector<Limb> limbs_without;
  bool any_closed_form = false;
  for (const auto& sweep : sweeps) {
    if (has_closed_form(sweep.limb)) {
      any_closed_form = true;
    } else if (std::find(limbs_without.begin(), limbs_without.end(), sweep.limb) == limbs_without.end()) {
      limbs_without.push_back(sweep.limb);
    }
  }
  for (Limb limb : limbs_without) {
    std::vector<std::string> ids;
    for (const auto& sweep : sweeps)
      if (sweep.limb == limb) ids.push_back(sweep.id);
    without.push_back(fmt::format("{} ({})", limb_name(limb), fmt::join(ids, ", ")));
  }
  const auto closed_form_cell = [&](const std::string& text) {
    return any_closed_form ? fmt::format(" {:>12}", text) : "";
  };
  std::size_t id_width = 7, input_width = 9;  // the columns as wide as the longest id and input
  for (const auto& sweep : sweeps) {
    id_width = std::max(id_width, sweep.id.size());
    input_width = std::max(input_width, sweep.input.size());
  }
  fmt::print("{:<{}} {:<{}} {:>6}{} {:>12} {:>11}{} {:>11} {:>8} {:>11}\n", "sweep", id_width, "input", input_width,
             "points", closed_form_cell("check CF (m)"), "check N (m)", "level err", closed_form_cell("|CF-N| (rad)"),
             "N iter avg", "N max", "cold start");
  for (const auto& sweep : sweeps) {
    throw_if_interrupted();
    const IkSweepResult r = run_ik_sweep(model, data, sweep);
    write_ik_sweep_csv((std::filesystem::path(out_dir) / (sweep.id + ".csv")).string(), r);
    const bool pass = r.max_check_closed_form <= kLimit && r.max_check_newton <= kLimit && r.max_level_error <= kLimit &&
                      r.newton_branch_changes == 0 && r.outside_limits == 0;
    ok = ok && pass;
    const auto shown = [&](double v) { return r.closed_form ? fmt::format("{:.2e}", v) : std::string("-"); };
    fmt::print("{:<{}} {:<{}} {:>6}{} {:>12.2e} {:>11.2e}{} {:>11.2f} {:>8} {:>11}{}\n", sweep.id, id_width,
               sweep.input, input_width, r.points.size(), closed_form_cell(shown(r.max_check_closed_form)),
               r.max_check_newton, r.max_level_error, closed_form_cell(shown(r.max_newton_difference)),
               r.mean_newton_iterations, r.max_newton_iterations, fmt::format("{} off", r.cold_start_off_default),
               pass                      ? ""
               : r.newton_branch_changes ? "  FAIL (Newton changed branch)"
               : r.outside_limits        ? "  FAIL (outside the joints' limits)"
                                         : "  FAIL");
    if (r.outside_limits > 0)
      fmt::print("        {} of {} points leave a joint's range on branch {}, first {}\n", r.outside_limits, r.points.size(),
                 r.branch, r.first_outside);
  }
  fmt::print(
      "\n'check' is |target - FK(solution)| with the generated forward kinematics \n"
      "Newton is warm-started along the sweep; 'cold start' counts points where Newton started from the\n"
      "sweep's start pose lands off the sweep's branch (the model's choice at that pose, within the\n"
      "joints' limits where a branch is). CSV files: {}/\n",
      out_dir);
  if (!without.empty())
    fmt::print(
        "No closed form for {}: wlx-gen derived none.\n"
        "Their sweeps check Newton's method alone{}: there is no closed-form solution to check or to compare with.\n",
        fmt::join(without, ", "), any_closed_form ? " ('-' in the closed form's columns)" : "");
  fmt::print("{}\n", ok ? "all sweeps pass (every error <= 1e-10 m)" : "SOME SWEEPS FAIL");
  return ok ? 0 : 1;
}

WLX_COMMANDS_END
