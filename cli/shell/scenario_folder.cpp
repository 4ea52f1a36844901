#include "scenario_folder.hpp"

#include "bounded_input.hpp"

#include <fmt/format.h>
#include <wlx/support/bounded_file.hpp>
#include <wlx/error.hpp>

#include <algorithm>
#include <filesystem>
#include <memory>

namespace wlx::cli {

namespace {

namespace fs = std::filesystem;

std::unique_ptr<ScenarioFolder>& folder() {
  static std::unique_ptr<ScenarioFolder> loaded;
  return loaded;
}

// The built-in ids' characters: a run id is pasted into file names, links and CSV cells.
bool valid_id(const std::string& id) {
  if (id.empty() || id.size() > 64) return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '+' || c == '-';
  });
}

}  // namespace

void load_scenario_folder(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Error("--scenarios", fmt::format("'{}' is not a folder", excerpt(dir)));
  auto out = std::make_unique<ScenarioFolder>();
  out->dir = dir;
  std::vector<fs::path> files;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    // Hidden files (an editor's lock file, .#run.json) are not runs.
    if (it->path().extension() != ".json" || it->path().filename().string().front() == '.') continue;
    if (files.size() == kMaxScenarioFiles)
      throw Error("--scenarios", fmt::format("'{}' holds more than {} scenario files", excerpt(dir), kMaxScenarioFiles));
    files.push_back(it->path());
  }
  if (ec) throw Error("--scenarios", fmt::format("'{}' cannot be listed ({})", excerpt(dir), ec.message()));
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) {
    const std::string id = f.stem().string();
    if (!valid_id(id))
      throw Error("--scenarios", fmt::format("{}: a scenario's id is its file name without .json: 1 to 64 letters, digits and "
                                             ". _ + - (rename the file)",
                                             excerpt(f.string())));
    const BoundedRead r = read_bounded_file(f.string(), kMaxFileBytes);
    if (!r.ok()) throw Error("--scenarios", fmt::format("{} {}", excerpt(f.string()), r.error));
    out->scenarios.emplace_back(id, r.text);
  }
  if (out->scenarios.empty()) throw Error("--scenarios", fmt::format("'{}' holds no scenario file (*.json)", excerpt(dir)));
  const fs::path report = fs::path(dir) / "report.yaml";
  if (fs::exists(fs::symlink_status(report, ec))) {
    const BoundedRead r = read_bounded_file(report.string(), kMaxReportFileBytes);
    if (!r.ok()) throw Error("--scenarios", fmt::format("{} {}", excerpt(report.string()), r.error));
    out->report_text = r.text;
    out->report_path = report.string();
  }
  folder() = std::move(out);
}

const ScenarioFolder* scenario_folder() { return folder().get(); }

}  // namespace wlx::cli
