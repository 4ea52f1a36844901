#include "compile_jobs.hpp"

#include "bounded_input.hpp"
#include "interrupt.hpp"
#include "model_plugin.hpp"
#include "process.hpp"

#include <fmt/format.h>
#include <wlx/support/bounded_file.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <map>
#include <sstream>
#include <unistd.h>

#ifndef WLX_PLUGIN_CXX
#define WLX_PLUGIN_CXX "c++"
#endif

namespace wlx::cli {

namespace fs = std::filesystem;

namespace {

// The first line of a compiler's log that reports an error (else its first line).
std::string first_error(const std::string& log) {
  std::istringstream in(log);
  std::string first;
  for (std::string l; std::getline(in, l);) {
    if (first.empty() && !l.empty()) first = l;
    if (l.find("error") != std::string::npos) return l;
  }
  return first.empty() ? "(no output)" : first;
}

// A compiler's command line that dies with wlx: util-linux's setpriv (Debian's essential set) sets
// its parent-death signal, then runs it, so a wlx killed (kill -9) during a first use leaves no
// compiler running. (GCC's driver dies so; the cc1plus it started finishes its file into the build
// folder, which the next first use removes. Clang compiles in its driver's process.)
std::vector<std::string> dying_with_wlx(const std::vector<std::string>& argv) {
  static const bool setpriv = ::access("/usr/bin/setpriv", X_OK) == 0;
  if (!setpriv) return argv;
  std::vector<std::string> out{"/usr/bin/setpriv", "--pdeathsig", "KILL", "--"};
  out.insert(out.end(), argv.begin(), argv.end());
  return out;
}

}  // namespace

const char* built_with_compiler() { return WLX_PLUGIN_CXX; }

std::string compiler() {
  if (const char* env = std::getenv("CXX"); env != nullptr && *env != '\0') return env;
  return built_with_compiler();
}

Timings run_jobs(const std::vector<Job>& jobs, unsigned parallel, const fs::path& failed_logs) {
  std::vector<std::pair<int, const Job*>> running;
  std::map<int, std::chrono::steady_clock::time_point> started;
  Timings timings;
  std::size_t next = 0;
  const auto stop_all = [&] {
    for (const auto& [pid, job] : running) ::kill(pid, SIGTERM);
    for (const auto& [pid, job] : running) wait_program(pid);
    running.clear();
  };
  while (next < jobs.size() || !running.empty()) {
    while (next < jobs.size() && running.size() < parallel) {
      const Job& job = jobs[next++];
      const int pid = start_program(dying_with_wlx(job.argv), {}, job.log.string());
      if (pid < 0) {
        stop_all();
        throw Error("--model-file", fmt::format("cannot run '{}' for the {}{}", job.argv.front(), job.name,
                                                job.argv.front() == compiler() ? " (set CXX to a C++ compiler)" : ""));
      }
      running.emplace_back(pid, &job);
      started[pid] = std::chrono::steady_clock::now();
    }
    // Whichever finishes first frees its core for the next job.
    int pid = 0;
    std::vector<int> pids;
    for (const auto& [p, job] : running) pids.push_back(p);
    const ProgramRun r = wait_any_program(pids, pid);
    if (pid == 0 && interrupt_signal() != 0) {  // within milliseconds of the signal, not when the compiles end
      stop_all();
      throw_if_interrupted();
    }
    const auto done = std::find_if(running.begin(), running.end(), [&](const auto& p) { return p.first == pid; });
    if (done == running.end()) {
      stop_all();
      throw PluginBuildError("lost track of the compiler's processes");
    }
    const Job* job = done->second;
    running.erase(done);
    timings.emplace_back(job->name, std::chrono::duration<double>(std::chrono::steady_clock::now() - started[pid]).count());
    if (interrupt_signal() != 0) {
      stop_all();
      throw_if_interrupted();
    }
    if (!r.started) {  // setpriv ran, the compiler did not (exit 127)
      stop_all();
      throw Error("--model-file", fmt::format("cannot run '{}' for the {}{}", job->argv.front(), job->name,
                                              job->argv.front() == compiler() ? " (set CXX to a C++ compiler)" : ""));
    }
    if (!r.ok()) {
      stop_all();
      const std::string log = read_bounded_file(job->log.string(), kMaxFileBytes).text;
      std::error_code ec;
      fs::remove_all(failed_logs, ec);
      fs::create_directories(failed_logs, ec);
      fs::copy_file(job->log, failed_logs / job->log.filename(), fs::copy_options::overwrite_existing, ec);
      throw PluginBuildError(fmt::format("compiling the model's {} failed: {}\n  the whole log: {}", job->name,
                                         first_error(log), (failed_logs / job->log.filename()).string()));
    }
  }
  return timings;
}

std::string timings_text(const Timings& timings) {
  std::string out = "part\tseconds\n";
  for (const auto& [name, seconds] : timings) out += fmt::format("{}\t{:.2f}\n", name, seconds);
  return out;
}

}  // namespace wlx::cli
