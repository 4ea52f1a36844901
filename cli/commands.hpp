// The CLI's subcommands, one function each.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace wlx::cli {

int run_fk(bool as_json);
int run_ik(bool batch);
int run_verify_ik(const std::string& out_dir, const std::vector<std::string>& sweep_ids);

struct SimulateOptions {
  std::string scenario;
  std::string out_dir = "out/simulate";
  std::string integrator;    // empty: the scenario's
  std::optional<double> dt;  // empty: the scenario's
  std::optional<double> tolerance;  // dopri5 only; empty: the scenario's
  std::string weighting;     // "1" or "2" overrides the scenario's (and makes it a dynamics run)
  bool list = false;
};
int run_simulate(const SimulateOptions& options);
int run_verify_nonholonomic(const std::string& out_dir);

struct ReportOptions {
  std::string out_dir = "report";
  bool quick = false;  // a reduced set of runs (for tests)
};
int run_report(const ReportOptions& options);

}  // namespace wlx::cli
