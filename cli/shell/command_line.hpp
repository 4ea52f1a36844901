// The command line follows the rules of JSON input: every parse error exits 2 with a message that
// names the option or argument and the reason, with "did you mean" for misspelt subcommands and
// options; an option given twice is an error, not a silent last-one-wins.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace wlx::cli {

// Call before adding subcommands and options: --version, extras collected (checked by
// parse_command_line), single-valued options limited to one occurrence.
void prepare_command_line(CLI::App& app, const std::string& version);

// Parses argv. Nothing: go on and run the command. A code: exit with it (0 after --help or
// --version, 2 after an error, which is printed to stderr).
std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv);

}  // namespace wlx::cli
