// `wlx viewer`: the 3D viewer's page (built with emscripten, viewer/) copied into a folder, with
// the given scenarios simulated and written as runs the page plays (cli/shell/viewer_export.hpp).
#include "per_model.hpp"
#include "interrupt.hpp"
#include "model_commands.hpp"
#include "outputs.hpp"
#include "scenario_io.hpp"
#include "viewer_export.hpp"

#include <fmt/format.h>
#include <wlx/support/csv.hpp>
#include <wlx/support/diagnostics.hpp>
#include <wlx/error.hpp>

#include <filesystem>
#include <vector>

WLX_COMMANDS_BEGIN

std::string trajectory_csv_text(const Trajectory& trajectory, const Scenario& scenario) {
  std::string text;
  const auto header = trajectory_header(scenario);
  for (std::size_t k = 0; k < header.size(); ++k) text += (k ? "," : "") + header[k];
  text += "\n";
  for (const auto& sample : trajectory.samples) {
    CsvWriter::append_numbers(text, trajectory_row(sample, scenario), false);
    text += '\n';
  }
  return text;
}

void write_viewer_run(const std::filesystem::path& dir, const Scenario& scenario, const Trajectory& trajectory,
                      const std::string& id, const std::string& description) {
  for (const auto& info : gen::kParamInfo)
    if (scenario.params.*info.member != settings().params.*info.member)
      throw Error("run " + scenario.id,
                  fmt::format("sets params.{} = {:g}; the viewer draws the model's default parameters (its WebAssembly "
                              "module is built from them), so it would show another machine",
                              info.name, scenario.params.*info.member));
  const bool dynamics = scenario.weighting || scenario.driven_by_torques();  // its torques are plotted
  ViewerRun run;
  run.id = id.empty() ? scenario.id : id;
  run.model = std::string(gen::kModelName);
  run.description = description.empty() ? scenario.description : description;
  run.trajectory_csv = trajectory_csv_text(trajectory, scenario);
  if (!dynamics)  // the dependent pair's rates (a dynamics run plots its torques, the default)
    for (int k : scenario.pair.index) run.plot_columns.push_back(std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]) + "_dot");
  if (!dynamics) run.plot_title = "dependent rates " + scenario.pair.label();
  cli::write_viewer_run(dir, run, gen::kCoordinateNames);
}

int run_viewer(const ModelOptions& model_options, const ViewerOptions& options) {
  if (!model_options.params_file.empty())
    throw Error("--params", "the viewer draws the model with its default parameters (its WebAssembly module is built "
                            "from them): leave --params out");
  if (options.out_dir.empty()) throw Error("--out", "must name a folder");
  const std::filesystem::path dir(options.out_dir);
  // Every run named is read first: a bad id is a bad input (exit 2, "did you mean"), whether or
  // not this wlx has the viewer, and nothing is written for a request that cannot be met.
  std::vector<Scenario> scenarios;
  for (const auto& id : options.runs) scenarios.push_back(parse_scenario(read_scenario_json(id), {}, scenario_directory(id)));
  copy_viewer_files(dir);
  const std::string module = fmt::format("wasm/wlx_{}.js", gen::kModelName);
  if (!std::filesystem::is_regular_file(dir / module))
    throw Error("--model", fmt::format("the viewer was built without model '{}' ({} is missing)", gen::kModelName, module));
  for (const Scenario& scenario : scenarios) {
    // Asked after every sample: SIGINT, SIGTERM or SIGHUP stop a long run at once (exit 128 + signal),
    // and the run's file is not written.
    const Trajectory trajectory = simulate(scenario, [](long, long) { throw_if_interrupted(); });
    if (!trajectory.complete) wlx::diagnose("wlx viewer: run {} stopped early ({}); its samples up to then are shown\n", scenario.id, trajectory.error);
    write_viewer_run(dir, scenario, trajectory);
    fmt::print("run {}: {} samples -> {}\n", scenario.id, trajectory.samples.size(), (dir / "runs" / (scenario.id + ".js")).string());
  }
  throw_if_interrupted();
  fmt::print("wrote {} (open it in a browser; viewer.html?run=<id> for one run)\n", (dir / "viewer.html").string());
  return 0;
}

WLX_COMMANDS_END
