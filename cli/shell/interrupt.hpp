// SIGINT, SIGTERM and SIGHUP during a long run: the handler only records the signal; the loops of the
// commands poll it and unwind by exception, so destructors remove temporary files and the samples
// computed so far can still be written (marked partial) before the process exits 128 + signal.
#pragma once

#include <exception>
#include <string>

namespace wlx::cli {

// Installs the handlers (no SA_RESTART: a blocked read returns so the command can stop) and
// ignores SIGPIPE, so a closed stdout becomes a write error with a message, not a silent death.
void install_interrupt_handlers();
// The signal received (SIGINT, SIGTERM, SIGHUP), or 0.
int interrupt_signal() noexcept;

class Interrupted : public std::exception {
 public:
  explicit Interrupted(int signal);
  const char* what() const noexcept override { return message_.c_str(); }
  int signal() const noexcept { return signal_; }
  // The shell's convention: 128 + the signal number (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP).
  int exit_code() const noexcept { return 128 + signal_; }

 private:
  int signal_;
  std::string message_;
};

// Throws Interrupted if a signal arrived.
void throw_if_interrupted();

}  // namespace wlx::cli
