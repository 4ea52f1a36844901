// `wlx report` for any model: the page (index.html), its figures (PNG and SVG, with the CSV files
// behind them) and the 3D viewer's runs, from one model's side of the report (results.hpp's
// ModelReport). Compiled once, into wlx itself; the model's side is compiled per model
// (report/runner.hpp).
#pragma once

#include "commands.hpp"
#include "report/results.hpp"
#include "report/spec.hpp"

namespace wlx::cli::report {

// Runs everything of `model`, writes the report into options.out_dir (index.html last: its
// presence says the report is complete) and prints a summary. Returns 0, or 1 if a check failed or
// a simulation stopped (each listed on stderr); a signal ends it with Interrupted's exit code and
// no index.html. Throws wlx::Error for an --out that cannot be written.
int write_report(ModelReport& model, const ReportSpec& spec, const ModelOptions& model_options, const ReportOptions& options);

}  // namespace wlx::cli::report
