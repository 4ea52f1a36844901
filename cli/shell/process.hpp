// External programs run without a shell: an argument vector for posix_spawnp, so no character of
// a path (quotes, spaces, $, backquotes, newlines) is ever interpreted.
#pragma once

#include <string>
#include <vector>

namespace wlx::cli {

struct ProgramRun {
  bool started = false;  // false: the program was not found or could not be run
  int exit_status = -1;  // its exit code when it exited normally
  int signal = 0;        // the signal that ended it, if any
  bool ok() const { return started && exit_status == 0 && signal == 0; }
};

// Runs argv[0] (looked up in PATH) with `argv` in the folder `working_directory` (empty: this
// process's), stdin from /dev/null, stdout and stderr written to `log_path` (truncated first) (empty:
// /dev/null); stderr to `error_path` instead where one is given (the output apart from the messages).
ProgramRun run_program(const std::vector<std::string>& argv, const std::string& working_directory = {},
                       const std::string& log_path = {}, const std::string& error_path = {});

// The same in two halves, to run several programs at once: start_program returns the child's pid
// (or -1 if it could not be started), wait_program waits for it (a signal to wlx while waiting
// does not stop the wait: the caller decides, after, what to do with the other children).
int start_program(const std::vector<std::string>& argv, const std::string& working_directory = {},
                  const std::string& log_path = {}, const std::string& error_path = {});
ProgramRun wait_program(int pid);
// Waits for whichever of `pids` (children started by start_program) ends first; `pid` is set to
// it, or to 0 if there is none or a signal arrived (interrupt.hpp) while waiting: then the caller
// stops its children. Other children of the process (a host's own) are left alone.
ProgramRun wait_any_program(const std::vector<int>& pids, int& pid);

}  // namespace wlx::cli
