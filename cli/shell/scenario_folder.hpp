// `--scenarios DIR`: a user's runs for any model (a built-in one, or a model file's, which embeds
// none). The folder's *.json files replace the model's embedded scenarios for every command
// (`simulate --list` and ids, `verify nonholonomic`, `report`, `viewer`), and its report.yaml, if
// any, the embedded report file (`--claims` still overrides it). The shell reads the folder once,
// bounded, before the model's commands run; the per-model code asks scenario_folder().
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace wlx::cli {

// At most this many scenario files in a folder: a design study's dozens of runs, not a data set
// (each file is read whole and kept while the command runs; kMaxFileBytes each).
inline constexpr std::size_t kMaxScenarioFiles = 1000;

struct ScenarioFolder {
  std::string dir;
  std::vector<std::pair<std::string, std::string>> scenarios;  // id (the file's name without .json), text; sorted by id
  std::string report_text;  // report.yaml's text, empty if the folder has none
  std::string report_path;  // its path, for messages
};

// Reads DIR: every regular *.json file (an id is letters, digits and . _ + -, as the built-in
// ids), and report.yaml. Errors (exit 2) name the folder or the file and the reason: not a folder,
// no scenario in it, too many files, a file that cannot be read or is too large.
void load_scenario_folder(const std::string& dir);

// The folder given with --scenarios, or null (the model's embedded scenarios apply).
const ScenarioFolder* scenario_folder();

}  // namespace wlx::cli
