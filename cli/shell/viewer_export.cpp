#include "viewer_export.hpp"

#include "bounded_input.hpp"
#include "csv_columns.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <wlx/support/bounded_file.hpp>
#include <wlx/support/text.hpp>
#include <wlx/support/atomic_file.hpp>
#include <wlx/error.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

namespace wlx::cli {

namespace {

namespace fs = std::filesystem;

void check_run_id(const std::string& id) {
  const bool allowed = !id.empty() && id.size() <= 64 && id.front() != '.' &&
                       std::all_of(id.begin(), id.end(), [](char c) {
                         return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' ||
                                c == '_' || c == '+' || c == '-';
                       });
  if (!allowed)
    throw Error("run id", fmt::format("'{}' must be 1 to 64 of A-Z a-z 0-9 . _ + - and not start with '.' (it names "
                                      "the file runs/<id>.js)",
                                      excerpt(id)));
}

// The run's CSV columns by name (only those asked for), every value parsed and finite.
std::map<std::string, std::vector<double>> read_columns(const ViewerRun& run, const std::vector<std::string>& wanted,
                                                        std::vector<std::string>* header_out) {
  return read_csv_columns(run.trajectory_csv, "run " + run.id, "the trajectory CSV", wanted, header_out);
}

// The default plot: torques of a dynamics run, else the input rates that vary (the dependent ones).
void choose_plot(const std::vector<std::string>& header, const ViewerRun& run, std::vector<std::string>& columns,
                 std::string& title, std::string& unit) {
  for (const auto& name : header)
    if (name.starts_with("tau_")) columns.push_back(name);
  if (!columns.empty()) {
    title = "joint torques";
    unit = "N m";
    return;
  }
  std::vector<std::string> rates;
  for (const auto& name : header)
    if (name.ends_with("_dot")) rates.push_back(name);
  for (const auto& [name, values] : read_columns(run, rates, nullptr)) {
    const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
    if (*hi - *lo > 1e-12 * std::max(1.0, std::max(std::abs(*lo), std::abs(*hi)))) columns.push_back(name);
  }
  // In the CSV's order, not the map's.
  std::vector<std::string> ordered;
  for (const auto& name : rates)
    if (std::find(columns.begin(), columns.end(), name) != columns.end()) ordered.push_back(name);
  columns = ordered;
  title = "dependent rates";
  unit = "m/s, rad/s";
}

// A file this program reads back (the run index, the built viewer's files): bounded and regular
// (runs/index.js replaced by a link to /dev/zero is refused, not read until memory runs out).
std::string read_text(const fs::path& path, std::size_t limit) {
  const BoundedRead file = read_bounded_file(path.string(), limit);
  if (!file.ok()) throw Error(excerpt(path.string()), file.error);
  return file.text;
}

// A JSON value as JavaScript source: all ASCII, ill-formed UTF-8 replaced, and < > & escaped, the
// same rules as wlx::text::js_string (JSON has these characters only inside strings).
std::string js_json(const nlohmann::json& value) {
  const std::string dumped = value.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace);
  std::string out;
  for (const char c : dumped) {
    if (c == '<') out += "\\u003c";
    else if (c == '>') out += "\\u003e";
    else if (c == '&') out += "\\u0026";
    else out += c;
  }
  return out;
}

// The built viewer's largest file (the model's WebAssembly module in JavaScript) is a few MB.
constexpr std::size_t kMaxViewerFileBytes = std::size_t{64} << 20;

constexpr std::string_view kIndexOpen = "wlxViewer.registerIndex([\n";
constexpr std::string_view kIndexClose = "]);\n";

// The entries of runs/index.js, one JSON object per line as write_index writes them.
std::vector<nlohmann::json> read_index(const fs::path& path) {
  std::vector<nlohmann::json> entries;
  if (!fs::exists(path)) return entries;
  std::istringstream in(read_text(path, kMaxRunIndexBytes));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line.front() != '{') continue;
    if (line.back() == ',') line.pop_back();
    auto entry = nlohmann::json::parse(line, nullptr, false);
    if (entry.is_discarded() || !entry.is_object() || !entry.contains("id"))
      throw Error(path.string(), fmt::format("line '{}' is not an entry this program wrote; remove the file to start over",
                                             excerpt(line)));
    entries.push_back(std::move(entry));
  }
  return entries;
}

void write_index(const fs::path& path, const std::vector<nlohmann::json>& entries) {
  std::string text = "// The runs of this viewer folder, written by wlx (cli/shell/viewer_export.cpp).\n";
  text += kIndexOpen;
  for (std::size_t k = 0; k < entries.size(); ++k) text += js_json(entries[k]) + (k + 1 < entries.size() ? ",\n" : "\n");
  text += kIndexClose;
  write_file_atomically(path.string(), text);
}

void create_folder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw OutputError(dir.string(), fmt::format("cannot create the folder ({})", ec.message()));
}

}  // namespace

void write_viewer_run(const fs::path& dir, const ViewerRun& run, std::span<const std::string_view> coordinate_names,
                      std::size_t max_samples) {
  check_run_id(run.id);
  if (run.model.empty()) throw Error("run " + run.id, "the model's name is empty");
  if (max_samples < 2) throw Error("max_samples", fmt::format("must be at least 2, got {}", max_samples));
  std::vector<std::string> wanted{"t"};
  for (const auto name : coordinate_names) wanted.emplace_back(name);
  std::vector<std::string> header;
  read_columns(run, {"t"}, &header);  // the header (and that the CSV has a t column)
  std::vector<std::string> plot = run.plot_columns;
  std::string title = run.plot_title, unit = run.plot_unit;
  std::string default_title = "rates", default_unit = "m/s, rad/s";
  if (plot.empty()) {
    choose_plot(header, run, plot, default_title, default_unit);
  } else if (std::all_of(plot.begin(), plot.end(), [](const std::string& c) { return c.starts_with("tau_"); })) {
    default_title = "joint torques";
    default_unit = "N m";
  }
  if (title.empty()) title = default_title;
  if (unit.empty()) unit = default_unit;
  wanted.insert(wanted.end(), plot.begin(), plot.end());
  // A dynamics run's contacts (`wlx simulate`'s columns, cli/commands/outputs.hpp): each contact's
  // force in K0 (f_x_, f_y_, f_n_: the ground's normal is K0's z) and friction margin, the CoM, the
  // zero-moment point and the margins, for the page's force overlay. The contacts' names are the
  // stems of the f_x_ columns (the model's, in its order); the page finds their frames by name.
  std::vector<std::string> contacts;
  const auto has = [&](const std::string& c) { return std::find(header.begin(), header.end(), c) != header.end(); };
  for (const auto& c : header) {
    if (!c.starts_with("f_x_")) continue;
    const std::string stem = c.substr(4);
    if (has("f_y_" + stem) && has("f_n_" + stem) && has("friction_margin_" + stem)) contacts.push_back(stem);
  }
  const std::array<std::string_view, 8> overall{"com_x", "com_y", "com_z", "zmp_x", "zmp_y", "margin_static", "margin_zmp", "margin_tip"};
  if (!contacts.empty() && std::all_of(overall.begin(), overall.end(), [&](std::string_view c) { return has(std::string(c)); })) {
    for (const auto& stem : contacts)
      for (const char* q : {"f_x_", "f_y_", "f_n_", "friction_margin_"}) wanted.push_back(q + stem);
    wanted.insert(wanted.end(), overall.begin(), overall.end());
  } else {
    contacts.clear();
  }
  const auto columns = read_columns(run, wanted, nullptr);
  const std::size_t n = columns.at("t").size();
  // Evenly thinned to at most max_samples, keeping the first and the last sample.
  std::vector<std::size_t> kept;
  if (n <= max_samples) {
    for (std::size_t i = 0; i < n; ++i) kept.push_back(i);
  } else {
    for (std::size_t k = 0; k < max_samples; ++k) kept.push_back(k * (n - 1) / (max_samples - 1));
  }
  std::string text = fmt::format("// Run {} for wlx's viewer (viewer.html?run=<id>), written by wlx.\nwlxViewer.registerRun(", run.id);
  nlohmann::ordered_json head;
  head["format"] = "wlx-viewer-run 1";
  head["id"] = run.id;
  head["model"] = run.model;
  head["description"] = run.description;
  head["samples"] = kept.size();
  head["plot"] = {{"title", title}, {"unit", unit}, {"columns", plot}};
  if (!contacts.empty()) head["contacts"] = contacts;
  std::string head_text = js_json(head);
  head_text.pop_back();  // the closing brace: the columns follow
  text += head_text + ",\"columns\":{";
  bool first = true;
  std::vector<std::string> written;
  for (const auto& name : wanted) {
    if (std::find(written.begin(), written.end(), name) != written.end()) continue;
    written.push_back(name);
    const auto& values = columns.at(name);
    text += fmt::format("{}\n{}:[", first ? "" : ",", text::js_string(name));
    first = false;
    for (std::size_t k = 0; k < kept.size(); ++k) {
      // 10 significant digits: 1e-10 relative, far below what the eye or the plot resolves.
      text += fmt::format("{}{:.10g}", k ? "," : "", values[kept[k]]);
    }
    text += "]";
  }
  text += "}});\n";
  const fs::path runs = dir / "runs";
  create_folder(runs);
  write_file_atomically((runs / (run.id + ".js")).string(), text);
  // One writer at a time for the index (read, updated, rewritten): a report may export its runs
  // from several threads.
  static std::mutex index_mutex;
  const std::lock_guard lock(index_mutex);
  auto entries = read_index(runs / "index.js");
  nlohmann::json entry = {{"id", run.id}, {"model", run.model}, {"description", run.description}};
  const auto same = std::find_if(entries.begin(), entries.end(), [&](const nlohmann::json& e) { return e["id"] == run.id; });
  if (same != entries.end()) *same = entry;
  else entries.push_back(entry);
  write_index(runs / "index.js", entries);
}

fs::path built_viewer_dir() {
  if (const char* env = std::getenv("WLX_VIEWER_DIR"); env != nullptr && *env != '\0') return env;
#ifdef WLX_VIEWER_BUILD_DIR
  const fs::path build_tree = WLX_VIEWER_BUILD_DIR;
  std::error_code ec;
  if (fs::is_regular_file(build_tree / "viewer.html", ec)) return build_tree;
  // An installed wlx: <prefix>/bin/wlx finds <prefix>/share/wlx/viewer.
  const fs::path executable = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = (executable.parent_path() / WLX_VIEWER_FROM_BINDIR).lexically_normal();
    if (fs::is_regular_file(installed / "viewer.html", ec)) return installed;
  }
  return build_tree;  // neither: the error names the build tree's folder
#else
  return {};
#endif
}

namespace {
struct ViewerModule {
  std::string model;
  std::function<std::string()> path;
};
ViewerModule& own_module() {
  static ViewerModule m;
  return m;
}
}  // namespace

void use_viewer_module(const std::string& model, std::function<std::string()> module_js) {
  own_module() = {model, std::move(module_js)};
}

void copy_viewer_files(const fs::path& dir, const fs::path& source) {
  const std::string how = "build it with emscripten and node installed (tools/setup.sh installs them; CMake option "
                          "WLX_BUILD_VIEWER), or point WLX_VIEWER_DIR at a built viewer folder";
  if (source.empty()) throw Error("viewer", "this wlx was built without the viewer: " + how);
  const ViewerModule& own = own_module();
  const fs::path own_name = own.model.empty() ? fs::path() : fs::path("wasm") / ("wlx_" + own.model + ".js");
  std::vector<std::pair<fs::path, fs::path>> files{{source / "viewer.html", "viewer.html"}, {source / "viewer.js", "viewer.js"}};
  std::error_code ec;
  if (fs::is_directory(source / "wasm", ec))
    for (const auto& e : fs::directory_iterator(source / "wasm", ec))
      if (const fs::path name = fs::path("wasm") / e.path().filename(); e.path().extension() == ".js" && name != own_name)
        files.emplace_back(e.path(), name);
  if (!own.model.empty()) files.emplace_back(own.path(), own_name);
  if (files.size() == 2) files.emplace_back(source / "wasm/wlx_<model>.js", "");  // reported missing below
  for (const auto& [from, to] : files)
    if (!fs::is_regular_file(from)) throw Error("viewer", fmt::format("{} is missing: {}", from.string(), how));
  create_folder(dir / "wasm");
  create_folder(dir / "runs");
  for (const auto& [from, to] : files) write_file_atomically((dir / to).string(), read_text(from, kMaxViewerFileBytes));
  if (!fs::exists(dir / "runs" / "index.js")) write_index(dir / "runs" / "index.js", {});
}

}  // namespace wlx::cli
