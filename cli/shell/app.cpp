#include "app.hpp"

#include "command_line.hpp"

namespace wlx::cli {

void define_command_line(CLI::App& app, Invocation& inv, const std::vector<std::string>& model_names,
                         const std::string& version) {
  prepare_command_line(app, version);
  inv.model_name = model_names.front();
  std::string names;
  for (const auto& n : model_names) names += (names.empty() ? "" : ", ") + n;
  // --model and --params before the subcommand or after it (each subcommand has them too, so that
  // an unknown option of a subcommand is reported there, with its own did-you-mean).
  const auto add_model_options = [&](CLI::App* a) {
    a->add_option("--model", inv.model_name, "the built-in model (" + names + "; wlx models lists them)")
        ->capture_default_str();
    a->add_option("--model-file", inv.model_file,
                  "your own model file (docs/model-format.md): compiled on first use into a cached plugin, then loaded "
                  "(instead of --model)");
    a->add_option("--scenarios", inv.scenarios_dir,
                  "a folder of scenario files (*.json, and report.yaml for `report`) replacing the model's own runs; "
                  "a model file has none of its own");
    a->add_option("--params", inv.model_options.params_file,
                  "JSON file {\"name\": value, ...} overriding the model's parameters (SI units; default: the model file's values)");
  };
  add_model_options(&app);
  inv.list_models = app.add_subcommand("models", "list the built-in models");
  inv.fk = app.add_subcommand("fk", "forward kinematics of a pose on stdin (JSON; {} for the nominal pose)");
  inv.fk->add_flag("--json", inv.fk_json, "print JSON instead of a table");

  inv.ik = app.add_subcommand("ik", "inverse kinematics: one JSON object of inputs on stdin, one JSON object out");
  inv.ik->add_flag("--batch", inv.batch, "NDJSON: one object per line in, one per line out (Newton warm-starts along the lines)");

  auto* verify = app.add_subcommand("verify", "the verifications: IK sweeps and wheel constraints");
  verify->require_subcommand(1);
  inv.verify_ik = verify->add_subcommand("ik", "the model's IK sweeps (its file's ik_sweeps), closed form and Newton");
  inv.verify_ik->add_option("--out", inv.ik_out, "folder for one CSV per sweep")->capture_default_str();
  inv.verify_ik->add_option("--sweep", inv.sweep_ids, "only these sweeps (ids as wlx verify ik lists them; default: all)");

  inv.verify_nh = verify->add_subcommand("nonholonomic", "the model's scenarios marked \"verify\": \"nonholonomic\": the wheels' sideways-velocity residual");
  inv.verify_nh->add_option("--out", inv.nh_out, "folder for one trajectory CSV per run")->capture_default_str();

  inv.simulate = app.add_subcommand("simulate", "integrate a scenario (a file, or a built-in id: --list shows them)");
  inv.simulate->add_option("SCENARIO", inv.sim.scenario, "scenario file or id (--list shows the model's ids)");
  inv.simulate->add_option("--out", inv.sim.out_dir, "output folder for trajectory.csv")->capture_default_str();
  inv.simulate->add_option("--integrator", inv.sim.integrator,
                       "rk4, euler or dopri5 (adaptive Dormand-Prince 5(4)); default: the scenario's");
  inv.simulate->add_option("--dt", inv.sim.dt, "step in seconds, or with dopri5 the output interval (default: the scenario's)");
  inv.simulate->add_option("--tolerance", inv.sim.tolerance, "dopri5's local error bound per step, relative to 1 + |q| (default 1e-10)");
  inv.simulate->add_option("--weighting", inv.sim.weighting, "torque weighting: model-weights (the model file's), contribution or contacts (keeps the machine on its contacts), also 1, 2, 3; for inverse dynamics (default: the scenario's)");
  inv.simulate->add_flag("--list", inv.sim.list, "list the built-in scenarios");

  inv.report = app.add_subcommand("report", "run the model's verifications and scenarios, check the claims of its report file, and write an HTML report with figures");
  inv.report->add_option("--out", inv.report_options.out_dir, "output folder (index.html, fig/, data/, plots/)")->capture_default_str();
  inv.report->add_flag("--quick", inv.report_options.quick, "a reduced set of runs, for a fast look");
  inv.report->add_option("--claims", inv.report_options.claims_file,
                         "a report file (claims and figure layout, format of scenarios/<model>/report.yaml; default: the model's own)");

  inv.viewer = app.add_subcommand("viewer", "the 3D viewer (viewer.html, drag-and-drop IK in WebAssembly) written to a folder, with runs to play");
  inv.viewer->add_option("RUN", inv.viewer_options.runs, "scenario files or ids to simulate and show (wlx simulate --list shows the ids)");
  inv.viewer->add_option("--out", inv.viewer_options.out_dir, "output folder (viewer.html, viewer.js, wasm/, runs/)")->capture_default_str();

  auto* exporter = app.add_subcommand("export", "the model in another tool's format, from its description (no compile)");
  exporter->require_subcommand(1);
  inv.export_mjcf = exporter->add_subcommand("mjcf", "the model as MuJoCo's MJCF: bodies, joints, inertias, wheels, contacts, motors "
                                                     "(docs/export.md)");
  inv.export_mjcf->add_option("--out", inv.export_out, "the MJCF file to write (default: out/mjcf/<model>.xml)");

  inv.sweep = app.add_subcommand("sweep", "a parameter sweep of a spec file (YAML: model, parameters, runs, metrics) on Dask, "
                                          "resumable; writes results.csv and plots (runs python3 -m wlx sweep)");
  inv.sweep->add_option("SPEC", inv.sweep_options.spec, "the sweep's spec file (README.md, \"Parameter sweeps\")");
  inv.sweep->add_option("--out", inv.sweep_options.out, "output folder (default: the spec's `out`, else sweep/ beside the spec)");
  inv.sweep->add_option("--scheduler", inv.sweep_options.scheduler,
                        "a running Dask scheduler, tcp://HOST:8786 (default: a local cluster on this machine's cores)");
  inv.sweep->add_option("--workers", inv.sweep_options.workers, "the local cluster's worker processes (default: this machine's cores)");
  inv.sweep->add_option("--batch-size", inv.sweep_options.batch_size, "variants per Dask task (default: sized to about 2 s a task)");

  for (CLI::App* a : {inv.fk, inv.ik, inv.verify_ik, inv.verify_nh, inv.simulate, inv.report, inv.viewer, inv.export_mjcf}) add_model_options(a);
}

}  // namespace wlx::cli
