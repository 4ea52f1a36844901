#include "process.hpp"

#include <ctime>

#include "interrupt.hpp"

#include <cerrno>
#include <csignal>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace wlx::cli {

ProgramRun run_program(const std::vector<std::string>& argv, const std::string& working_directory,
                       const std::string& log_path, const std::string& error_path) {
  return wait_program(start_program(argv, working_directory, log_path, error_path));
}

int start_program(const std::vector<std::string>& argv, const std::string& working_directory, const std::string& log_path,
                  const std::string& error_path) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  const std::string log = log_path.empty() ? "/dev/null" : log_path;
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0666);
  if (error_path.empty()) posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  else posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, error_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0666);
  if (!working_directory.empty()) posix_spawn_file_actions_addchdir_np(&actions, working_directory.c_str());

  // The child starts with default dispositions: wlx ignores SIGPIPE and catches SIGINT/SIGTERM,
  // and an ignored signal would stay ignored across exec.
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGPIPE);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGTERM);
  sigaddset(&defaults, SIGHUP);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);

  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, args[0], &actions, &attributes, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  return spawned == 0 ? static_cast<int>(pid) : -1;
}

namespace {

ProgramRun run_of(pid_t pid, int status, int& reaped) {
  ProgramRun result;
  reaped = static_cast<int>(pid);
  result.started = true;
  if (WIFEXITED(status)) {
    result.exit_status = WEXITSTATUS(status);
    // posix_spawnp reports a failed exec as exit status 127 from the child.
    if (result.exit_status == 127) result.started = false;
  }
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  return result;
}

}  // namespace

ProgramRun wait_program(int pid) {
  if (pid <= 0) return {};
  int status = 0, reaped = 0;
  pid_t done = 0;
  // EINTR: our own SIGINT/SIGTERM/SIGHUP handler ran; the caller decides after, keep waiting.
  while ((done = ::waitpid(pid, &status, 0)) < 0)
    if (errno != EINTR) return {};
  return run_of(done, status, reaped);
}

ProgramRun wait_any_program(const std::vector<int>& pids, int& pid) {
  // Only these children, never waitpid(-1): in a host that has children of its own (Python's
  // subprocess, a multiprocessing pool) that would reap theirs and lose track of ours. Polled
  // every 10 ms, which a compile of seconds does not notice, and a signal stops the wait in 10 ms.
  for (;;) {
    for (const int candidate : pids) {
      int status = 0;
      const pid_t done = ::waitpid(candidate, &status, WNOHANG);
      if (done == candidate) return run_of(done, status, pid);
    }
    if (pids.empty() || interrupt_signal() != 0) {
      pid = 0;
      return {};
    }
    const timespec pause{0, 10'000'000};
    ::nanosleep(&pause, nullptr);
  }
}

}  // namespace wlx::cli
