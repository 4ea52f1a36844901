// Where the CLI's outputs go, checked: the --out folder, and stdout at the end of a command.
#pragma once

#include <string>

namespace wlx::cli {

// Exit code of a command whose output could not be written (sysexits.h's EX_IOERR): distinct
// from 2, a bad input, and 1, a failed check.
inline constexpr int kExitOutputError = 74;

// Refuses "", "-" and an existing non-folder for `option` (wlx::Error, exit 2), then creates the
// folder (wlx::OutputError naming it if that fails).
void prepare_out_dir(const std::string& option, const std::string& path);

// The exit code of a command that returned `code`: kExitOutputError (with a message) if stdout
// lost anything, since its output is then incomplete.
int finish(int code);

// Flushes stdout; false (with errno's text in `reason`) if anything written to it was lost.
bool stdout_ok(std::string& reason);

}  // namespace wlx::cli
