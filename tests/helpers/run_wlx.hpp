// Runs the wlx binary as a user would, without a shell: posix_spawn with an argument vector,
// stdin from a string (or a pipe), stdout and stderr captured (or stdout sent elsewhere).
#pragma once

#include <doctest/doctest.h>

#include <cerrno>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <spawn.h>
#include <sstream>
#include <string>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

extern char** environ;

namespace wlx_test {

namespace fs = std::filesystem;

// A folder of this test process's own, removed when the process ends.
inline const fs::path& work_dir() {
  struct Folder {
    fs::path path = fs::temp_directory_path() / ("wlx_faults_" + std::to_string(::getpid()));
    Folder() {
      fs::remove_all(path);
      fs::create_directories(path);
    }
    ~Folder() {
      std::error_code ignored;  // a leftover folder in /tmp is no reason to fail at exit
      fs::remove_all(path, ignored);
    }
  };
  static const Folder folder;
  return folder.path;
}

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

struct Io {
  std::string input;           // stdin's content
  fs::path stdin_path;         // set: stdin from this file instead (large inputs not held in memory)
  std::string stdout_path;     // empty: captured; else where stdout goes (e.g. /dev/full)
  bool stdout_closed_pipe = false;  // stdout is a pipe whose reading end is already closed
  bool stdin_pipe = false;     // stdin is a pipe the test writes to (Spawned::stdin_fd)
  fs::path cwd;                // empty: the test's
  std::string program;         // empty: wlx; else the program to run (args are its arguments)
  std::string stderr_path;     // empty: captured; else where stderr goes (e.g. /dev/full)
};

struct Spawned {
  pid_t pid = -1;
  int stdin_fd = -1;
  fs::path out, err;
};

struct Result {
  int code = -1;    // exit code; -1 if ended by a signal
  int signal = 0;
  std::string out, err;
  long peak_rss_kib = 0;
};

inline Spawned start(const std::vector<std::string>& args, const Io& io = {}) {
  static int counter = 0;
  const std::string tag = std::to_string(counter++);
  Spawned s;
  s.out = work_dir() / ("out-" + tag);
  s.err = work_dir() / ("err-" + tag);
  const fs::path in = work_dir() / ("in-" + tag);
  write(in, io.input);

  std::vector<std::string> argv{io.program.empty() ? std::string(WLX_BINARY) : io.program};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> cargs;
  for (auto& a : argv) cargs.push_back(a.data());
  cargs.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  int in_pipe[2] = {-1, -1}, out_pipe[2] = {-1, -1};
  if (io.stdin_pipe) {
    REQUIRE(::pipe(in_pipe) == 0);
    posix_spawn_file_actions_adddup2(&actions, in_pipe[0], STDIN_FILENO);
    posix_spawn_file_actions_addclose(&actions, in_pipe[1]);
  } else {
    const fs::path source = io.stdin_path.empty() ? in : io.stdin_path;
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, source.c_str(), O_RDONLY, 0);
  }
  if (io.stdout_closed_pipe) {
    REQUIRE(::pipe(out_pipe) == 0);
    posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&actions, out_pipe[0]);
  } else {
    const std::string out = io.stdout_path.empty() ? s.out.string() : io.stdout_path;
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  }
  const std::string err = io.stderr_path.empty() ? s.err.string() : io.stderr_path;
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (!io.cwd.empty()) posix_spawn_file_actions_addchdir_np(&actions, io.cwd.c_str());
  if (io.stdout_closed_pipe) ::close(out_pipe[0]);  // closed before wlx writes anything
  const int spawned = posix_spawn(&s.pid, cargs[0], &actions, nullptr, cargs.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  REQUIRE(spawned == 0);
  if (io.stdout_closed_pipe) ::close(out_pipe[1]);
  if (io.stdin_pipe) {
    ::close(in_pipe[0]);
    s.stdin_fd = in_pipe[1];
  }
  return s;
}

inline Result finish(const Spawned& s) {
  int status = 0;
  rusage usage{};
  while (::wait4(s.pid, &status, 0, &usage) < 0) REQUIRE(errno == EINTR);
  if (s.stdin_fd >= 0) ::close(s.stdin_fd);
  Result r;
  if (WIFEXITED(status)) r.code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  r.out = slurp(s.out);
  r.err = fs::exists(s.err) ? slurp(s.err) : std::string();
  r.peak_rss_kib = usage.ru_maxrss;
  return r;
}

inline Result run(const std::vector<std::string>& args, const Io& io = {}) { return finish(start(args, io)); }

}  // namespace wlx_test
