// `wlx --model-file FILE`: a user's own model in every command, without rebuilding wlx. On first
// use wlx runs wlx-gen on the file and compiles the runtime and the per-model commands for it with
// the system's C++ compiler into a shared library (a plugin), which it loads with dlopen; later
// uses load the cached plugin. Every use runs `wlx-gen --data-at-run-time --describe` (tens of
// milliseconds: the file checked and derived, nothing written), which gives the model's name and
// its description (model.json): the model's structure, the numbers of the file that no generated
// function holds (parameters' values, nominal state, starts, sweeps, weights, torque limits,
// friction) and `code_key`, the fingerprint of the code its headers hold. The cache entry is keyed
// by the code key (so by everything wlx-gen read, a URDF too, and by nothing that is data), wlx's
// version, the plugin interface's version, the compiler, the flags and the sources; the loaded
// plugin is handed the description's numbers. Editing only numbers finds the same plugin: no
// compiler runs.
//
// Cache: $WLX_CACHE_DIR, else $XDG_CACHE_HOME/wlx, else $HOME/.cache/wlx; one folder per entry,
// <model>-<key>/ with plugin.so and manifest (the key, and the plugin's size and checksum). An
// entry appears under its final name only when complete (built in a temporary folder, renamed);
// two processes building the same entry take turns (flock on <model>-<key>.lock): one compiles,
// the other waits and loads its result. An entry whose manifest, checksum or key does not match,
// or that dlopen refuses, is removed and rebuilt, never used.
#pragma once

#include "commands.hpp"

#include <wlx/error.hpp>

#include <string>

namespace wlx::cli {

// The plugin interface's version: part of every key and of the entry point's name, so a plugin
// of another interface is never loaded.
inline constexpr int kPluginInterface = 5;

// A plugin that could not be built from a correct model file (the compiler failed): exit 1, not
// the 2 of a bad input.
class PluginBuildError : public Error {
 public:
  explicit PluginBuildError(const std::string& reason) : Error("--model-file", reason) {}
};

// Loads the commands of the model in `model_file` (building the plugin on first use, with progress
// on stderr). Throws wlx::Error naming --model-file for a missing file or a mistake wlx-gen
// finds in it (its message, `file:line:column: field: reason`, before any compiling), and for a
// failed compile (the compiler's first error and where the whole log is).
const ModelCommands& load_model_file(const std::string& model_file, const std::string& version);

// The description (model.json's text) of the model in `model_file`, as wlx-gen gives it: nothing
// is compiled (`wlx export` reads the model as data). Errors as load_model_file's.
std::string describe_model_file(const std::string& model_file);

// Where wlx's programs (wlx-gen) and, beside them, its installed sources are, for a host other than
// the wlx program (the Python module); by default, the running program's folder.
void set_plugin_host_bin_dir(const std::string& bin_dir);

// The viewer's WebAssembly module (a script, wasm/wlx_<model>.js) of the model file loaded last:
// compiled with the emscripten wlx was built with into its cache entry on first use (about half a
// minute; progress on stderr), then reused. Throws Error when there is no emscripten.
std::string model_file_viewer_module();

// The cache folder (created if missing).
std::string model_cache_dir();

}  // namespace wlx::cli
