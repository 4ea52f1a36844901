#include "interrupt.hpp"

#include <csignal>
#include <cstring>

namespace wlx::cli {

namespace {

volatile std::sig_atomic_t received = 0;

extern "C" void record_signal(int signal) { received = signal; }

}  // namespace

void install_interrupt_handlers() {
  struct sigaction action {};
  action.sa_handler = record_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGHUP, &action, nullptr);  // the terminal closed: stop like SIGTERM, temporaries removed
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGPIPE, &ignore, nullptr);
}

int interrupt_signal() noexcept { return received; }

Interrupted::Interrupted(int signal)
    : signal_(signal),
      message_(signal == SIGINT    ? "interrupted (SIGINT)"
               : signal == SIGTERM ? "terminated (SIGTERM)"
               : signal == SIGHUP  ? "hung up (SIGHUP)"
                                   : std::string("stopped by signal ") + std::to_string(signal)) {}

void throw_if_interrupted() {
  if (const int s = interrupt_signal()) throw Interrupted(s);
}

}  // namespace wlx::cli
