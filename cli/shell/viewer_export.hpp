// The 3D viewer's files (viewer/, built with emscripten): copying the built page into a folder and
// writing a run's data in the form the page reads. Model-independent: callers pass their model's
// name and coordinate names (gen::kModelName, gen::kCoordinateNames).
//
// A viewer folder:
//   viewer.html, viewer.js          the page and its one bundled script (three.js and the page)
//   wasm/wlx_<model>.js             each model's WebAssembly module, inlined (SINGLE_FILE)
//   runs/index.js                   wlxViewer.registerIndex([{"id", "model", "description"}, ...])
//   runs/<id>.js                    wlxViewer.registerRun({...}) (format below)
// Everything loads by <script> tags, so the page works opened from file:// with no server; open
// viewer.html?run=<id> for one run (the id URI-encoded: ST-A1%2B; a bare '+' is accepted too),
// viewer.html?model=<name> for a model's
// nominal pose.
//
// runs/<id>.js holds one object: {"format": "wlx-viewer-run 1", "id", "model", "description",
// "samples": n, "plot": {"title", "unit", "columns": [names]}, "columns": {"t": [n numbers], each
// coordinate by name: [n], each plotted column: [n]}}. Numbers carry 10 significant digits.
// A dynamics run whose CSV has the contacts' columns also has "contacts": [names], and the columns
// f_x_<c>, f_y_<c>, f_n_<c>, friction_margin_<c> for each, com_x/y/z, zmp_x/y, margin_static,
// margin_zmp and margin_tip (the page's force overlay).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace wlx::cli {

struct ViewerRun {
  std::string id;              // 1 to 64 of A-Z a-z 0-9 . _ + -, not starting with '.' (the file name)
  std::string model;           // the model's name (gen::kModelName)
  std::string description;     // shown in the page's run list; may be empty
  std::string trajectory_csv;  // the text of a trajectory CSV (`wlx simulate`'s columns: t, the coordinates, ...)
  // The columns plotted against t beside the 3D view. Empty: the joint torques tau_* if the CSV
  // has them (an inverse-dynamics run), else the input rates <name>_dot that vary over the run
  // (the commanded ones are constant, so these are the dependent rates).
  std::vector<std::string> plot_columns;
  std::string plot_title;      // empty: "joint torques" or "dependent rates"
  std::string plot_unit;       // empty: "N m" or "m/s, rad/s"
};

// Writes DIR/runs/<run.id>.js (at most max_samples samples, evenly thinned, the last one kept) and
// adds or replaces the run's entry in DIR/runs/index.js, both atomically. Every name in
// coordinate_names, "t" and every plotted column must be a column of the CSV, every value a finite
// number; throws wlx::Error naming the run, the column or row and the reason, wlx::OutputError if a
// file cannot be written. The page draws the run with the model's default parameters: a run whose
// parameters differ from them must not be exported (the caller knows its parameters; the CSV does not).
// Safe to call from several threads for different runs (the index update is serialized).
void write_viewer_run(const std::filesystem::path& dir, const ViewerRun& run,
                      std::span<const std::string_view> coordinate_names, std::size_t max_samples = 1000);

// The built viewer's folder: the environment variable WLX_VIEWER_DIR if set, else the build tree's
// (CMake: WLX_BUILD_VIEWER), else an installation's <prefix>/share/wlx/viewer beside <prefix>/bin/wlx;
// empty when this wlx was built without the viewer.
std::filesystem::path built_viewer_dir();

// Copies viewer.html, viewer.js and wasm/*.js from `source` (default: built_viewer_dir()) into DIR
// (each file atomically) and writes an empty DIR/runs/index.js when there is none. Throws
// wlx::Error when `source` lacks one of them (the viewer was not built: its message says how).
void copy_viewer_files(const std::filesystem::path& dir, const std::filesystem::path& source = built_viewer_dir());

// A model file's own viewer module (cli/shell/model_plugin.hpp, built with emscripten on first use):
// copy_viewer_files then asks `module_js` for its path (only then: a command that writes no viewer
// compiles none) and writes it as wasm/wlx_<model>.js instead of any built-in module of that name
// (a user's copy of a built-in model has its own geometry). What `module_js` throws (no
// emscripten) is copy_viewer_files' error: never another model's module in its place.
void use_viewer_module(const std::string& model, std::function<std::string()> module_js);

}  // namespace wlx::cli
