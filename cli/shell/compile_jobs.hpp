// The compiles of a model's plugin and viewer module (model_plugin.cpp): the compiler, and jobs
// run a few at a time, each dying with wlx, timed, and stopped together at the first failure.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace wlx::cli {

// The compiler that builds a missing plugin: CXX, else the one wlx was built with. Not part of the
// key: a cached plugin is loaded whichever compiler built it (they share the C++ ABI and the
// standard library), so that a run whose compiler cannot work (CXX=/bin/false) still loads what is
// cached; another compiler's code for a key of its own takes other flags (WLX_PLUGIN_CXXFLAGS).
std::string compiler();
// The compiler wlx was built with (CMake's, whatever CXX says): part of a plugin's key.
const char* built_with_compiler();

// One program run of a build: what it makes (for messages and timings), its command line and the
// file its output goes to.
struct Job {
  std::string name;
  std::vector<std::string> argv;
  std::filesystem::path log;
};

// The wall time of each part of a first use (written to the entry's build-times.tsv: where the
// time goes, for the user and for tools/readme_figures.sh).
using Timings = std::vector<std::pair<std::string, double>>;

// Runs the jobs, up to `parallel` at once; stops the others at the first failure or signal (a
// failed job's log is copied into `failed_logs`, and PluginBuildError names its first error).
// Returns each job's wall time, in the order they finished.
Timings run_jobs(const std::vector<Job>& jobs, unsigned parallel, const std::filesystem::path& failed_logs);

// build-times.tsv's text.
std::string timings_text(const Timings& timings);

}  // namespace wlx::cli
