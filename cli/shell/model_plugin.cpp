#include "model_plugin.hpp"

#include "bounded_input.hpp"
#include "compile_jobs.hpp"
#include "interrupt.hpp"
#include "plugin_cache.hpp"
#include "process.hpp"
#include "sha256.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <wlx/support/diagnostics.hpp>
#include <wlx/support/atomic_file.hpp>
#include <wlx/support/bounded_file.hpp>
#include <wlx/error.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <dlfcn.h>
#include <fcntl.h>
#include <filesystem>
#include <map>
#include <mutex>
#include <fstream>
#include <sstream>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

// Set by CMake (CMakeLists.txt, wlx_cli_common; the compiler wlx was built with is
// compile_jobs.cpp's): the include folders of Eigen, fmt and nlohmann-json, the definitions of every
// part (wlx_plugin_defines says why), fmt's library, the source tree, and where an installed
// wlx keeps the runtime's headers and the sources a plugin compiles (relative to its bin folder).
#ifndef WLX_PLUGIN_INCLUDES
#define WLX_PLUGIN_INCLUDES ""
#endif
#ifndef WLX_PLUGIN_DEFINES
#define WLX_PLUGIN_DEFINES ""
#endif
#ifndef WLX_PLUGIN_LIBRARIES
#define WLX_PLUGIN_LIBRARIES ""
#endif
#ifndef WLX_SOURCE_TREE
#define WLX_SOURCE_TREE ""
#endif
#ifndef WLX_SHARE_FROM_BINDIR
#define WLX_SHARE_FROM_BINDIR "../share/wlx"
#endif
#ifndef WLX_INCLUDE_FROM_BINDIR
#define WLX_INCLUDE_FROM_BINDIR "../include"
#endif
// The build tree's precompiled headers (plugin_prelude.hpp, the commands' plugin_prelude_commands.hpp
// with its code beside it: CMakeLists.txt; none with GCC).
#ifndef WLX_PLUGIN_PRECOMPILED_DIR
#define WLX_PLUGIN_PRECOMPILED_DIR ""
#endif

namespace wlx::cli {

namespace {

namespace fs = std::filesystem;

// The plugin's entry points: its commands and the key it was built for; and its settings, from
// the model's description (model.json's text), null on success, else why they were refused.
using PluginEntry = const ModelCommands* (*)(const char** key);
using PluginSettings = const char* (*)(const char* description);
constexpr const char* kEntrySymbol = "wlx_model_plugin_v5";
constexpr const char* kSettingsSymbol = "wlx_model_plugin_v5_settings";
static_assert(kPluginInterface == 5, "rename kEntrySymbol and kSettingsSymbol with the interface's version");

// The runtime's sources (their generated-function files apart: each is its own translation unit)
// and the per-model commands: cmake/wlxModelBuild.cmake's lists, as for the built-in models, '|'-separated.
// The runtime in one translation unit, which shares Eigen's templates (measured at -O2: 27 s,
// where the files one by one take 48 s of CPU); it runs on one core while the commands and the
// generated functions take the others.
#if !defined(WLX_PLUGIN_RUNTIME_SOURCES) || !defined(WLX_PLUGIN_RUNTIME_OPTIMIZATION) || !defined(WLX_PLUGIN_COMMANDS_OPTIMIZATION)
#error "CMakeLists.txt defines WLX_PLUGIN_RUNTIME_SOURCES, WLX_PLUGIN_RUNTIME_APART, WLX_PLUGIN_GENERATED_SOURCES, WLX_PLUGIN_COMMAND_SOURCES and the parts' optimizations (cmake/wlxModelBuild.cmake)"
#endif

// FNV-1a, twice with different offsets: a 128-bit content key (a cache key, not a signature).
struct Hash {
  std::uint64_t a = 14695981039346656037ull, b = 1099511628211ull * 31 + 7;
  void add(std::string_view text) {
    for (const unsigned char c : text) {
      a = (a ^ c) * 1099511628211ull;
      b = (b ^ c) * 1099511628211ull + 0x9e3779b97f4a7c15ull;
    }
    a = (a ^ 0xff) * 1099511628211ull;  // a separator: ("ab", "c") and ("a", "bc") differ
  }
  std::string hex() const { return fmt::format("{:016x}{:016x}", a, b); }
};

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, '|'))
    if (!item.empty()) out.push_back(item);
  return out;
}

fs::path& host_bin_dir() {
  static fs::path dir;
  return dir;
}

// The folder of wlx's programs: the host's (the Python module says where they are), else this
// program's own.
fs::path executable_dir() {
  if (!host_bin_dir().empty()) return host_bin_dir();
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

std::string read_small(const fs::path& path, std::size_t limit) {
  const BoundedRead r = read_bounded_file(path.string(), limit);
  return r.ok() ? r.text : std::string();
}

// Where the sources a plugin compiles are: an installed wlx's share/wlx, else the source tree.
struct Sources {
  fs::path runtime_include;  // holds wlx/*.hpp
  fs::path support_include;  // holds wlx/support/*.hpp (the support library the shell and commands include)
  fs::path runtime_sources;  // the runtime's *.cpp
  fs::path cli;              // holds shell/, commands/, report/
  fs::path viewer_module;    // holds viewer_module.cpp (the viewer's WebAssembly interface)
  fs::path precompiled;      // holds plugin_prelude-<flags>.pch (and .a, its code, for the commands' flags), if wlx built them
};

Sources find_sources() {
  std::error_code ec;
  const fs::path bin = executable_dir();
  const fs::path share = (bin / WLX_SHARE_FROM_BINDIR).lexically_normal();
  if (!bin.empty() && fs::is_regular_file(share / "cli" / "commands" / "per_model.hpp", ec))
    return {(bin / WLX_INCLUDE_FROM_BINDIR).lexically_normal(), share / "support", share / "runtime", share / "cli", share / "viewer_module",
            share / "precompiled"};
  const fs::path tree = WLX_SOURCE_TREE;
  if (!tree.empty() && fs::is_regular_file(tree / "cli" / "commands" / "per_model.hpp", ec))
    return {tree / "runtime", tree / "support", tree / "runtime" / "wlx", tree / "cli", tree / "viewer" / "wasm", WLX_PLUGIN_PRECOMPILED_DIR};
  throw Error("--model-file", fmt::format("the sources a model's plugin is compiled from are missing (looked in {} and {}): "
                                          "reinstall wlx",
                                          share.string(), tree.string()));
}

// Every header and source a plugin compiles, by name and content, into the key.
void hash_sources(const Sources& src, Hash& h) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const fs::path& dir : {src.runtime_include / "wlx", src.support_include / "wlx" / "support", src.runtime_sources, src.cli / "shell", src.cli / "commands", src.cli / "report",
                              src.viewer_module})
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
      if (const auto ext = it->path().extension(); (ext == ".hpp" || ext == ".cpp") && it->is_regular_file(ec)) files.push_back(it->path());
  std::sort(files.begin(), files.end());
  files.erase(std::unique(files.begin(), files.end()), files.end());
  for (const auto& f : files) {
    h.add(f.filename().string());
    h.add(read_small(f, kMaxFileBytes));
  }
}

fs::path generator_program() {
  if (const char* env = std::getenv("WLX_GEN"); env != nullptr && *env != '\0') return env;
  const fs::path beside = executable_dir() / "wlx-gen";
  std::error_code ec;
  if (fs::is_regular_file(beside, ec)) return beside;
  return "wlx-gen";  // from PATH
}

// Each part's optimization, as cmake/wlxModelBuild.cmake defines it for every builder of a model's
// code (the runtime and the generated functions -O3, the commands -O0: why, there).
// WLX_PLUGIN_CXXFLAGS replaces both (all part of the key).
// Whitespace-separated flags.
std::vector<std::string> split_flags(const char* text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string flag; in >> flag;) out.push_back(flag);
  return out;
}
// The flags an environment variable gives, else `fallback`'s.
std::vector<std::string> flags_from_environment(const char* variable, const char* fallback) {
  const char* env = std::getenv(variable);
  return split_flags(env != nullptr && *env != '\0' ? env : fallback);
}
std::vector<std::string> optimization_flags(bool commands = false) {
  return flags_from_environment("WLX_PLUGIN_CXXFLAGS", commands ? WLX_PLUGIN_COMMANDS_OPTIMIZATION : WLX_PLUGIN_RUNTIME_OPTIMIZATION);
}

// The plugins loaded in this process, by library and description: the same model with the same
// numbers is that plugin again; a second description of the same code (the same model with other
// numbers, in one Python process) gets a copy of the library of its own, since a library's
// settings are its globals and dlopen() returns the same handle for one file. A copy costs its
// library's size in memory for the process's life (a few MB), once per distinct set of numbers.
std::map<std::pair<std::string, std::string>, const ModelCommands*>& loaded_commands() {
  static std::map<std::pair<std::string, std::string>, const ModelCommands*> loaded;
  return loaded;
}

// The plugin of a complete entry, or null with the reason it cannot be used. Once loaded, it is
// given the model's settings from `description` (model.json's text); a refusal is an error.
constexpr const char* kNotAsBuilt = "plugin.so is missing or does not match its manifest (corrupt or replaced)";

const ModelCommands* try_load(const fs::path& entry, const std::string& key, const std::string& description, std::string& why) {
  std::error_code ec;
  // The same plugin with the same numbers, loaded before in this process: that one.
  const fs::path library = entry / "plugin.so";
  if (const auto it = loaded_commands().find({library.string(), description}); it != loaded_commands().end()) return it->second;
  if (!fs::exists(fs::symlink_status(entry, ec))) {  // a dangling link is there, and refused below
    why = "not built yet";
    return nullptr;
  }
  check_private(entry, "entry", false);
  check_private(entry / "manifest", "manifest", false);
  const std::string manifest = read_small(entry / "manifest", 1 << 16);
  if (manifest_value(manifest, "key") != key) {
    why = "its manifest is missing or names another key";
    return nullptr;
  }
  // The file that is checked is the file that is loaded: opened once (never through a link), its
  // owner and mode and its bytes' SHA-256 checked on that descriptor, and dlopen()ed by it, so no
  // swap of the path between the check and the load can run other code.
  const int fd = ::open(library.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    if (errno == ELOOP) check_private(library, "plugin", false);  // a link: refused, naming it
    why = kNotAsBuilt;
    return nullptr;
  }
  // Kept open once loaded: dlopen() knows a library by the name it was given, and a reused
  // /proc/self/fd/N would name another plugin by an earlier one's name.
  struct CloseFd {
    int fd;
    bool keep = false;
    ~CloseFd() {
      if (!keep) ::close(fd);
    }
  } closing{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    why = kNotAsBuilt;
    return nullptr;
  }
  check_private_stat(st, library, "plugin");
  std::uintmax_t size = 0;
  const std::string checksum = fd_checksum(fd, size);
  if (checksum.empty() || checksum != manifest_value(manifest, "checksum") || std::to_string(size) != manifest_value(manifest, "size")) {
    why = kNotAsBuilt;
    return nullptr;
  }
  if (checksum != indexed_digest(entry.parent_path(), entry.filename().string())) {
    why = fmt::format("plugin.so is not one this cache built (its SHA-256 is not the one {} recorded)", index_path(entry.parent_path()).string());
    return nullptr;
  }
  // Another description of this code is loaded already: this one gets a copy of its own (its
  // settings are the library's globals). The copy is checked as the original was.
  bool other_numbers = false;
  for (const auto& [loaded, commands] : loaded_commands()) other_numbers = other_numbers || loaded.first == library.string();
  CloseFd copy{other_numbers ? private_copy(fd, checksum) : -1, !other_numbers};
  const std::string load = fmt::format("/proc/self/fd/{}", other_numbers ? copy.fd : fd);
  void* handle = ::dlopen(load.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    why = fmt::format("dlopen refused it ({})", ::dlerror());
    return nullptr;
  }
  const auto entry_point = reinterpret_cast<PluginEntry>(::dlsym(handle, kEntrySymbol));
  const char* built_for = nullptr;
  const ModelCommands* commands = entry_point != nullptr ? entry_point(&built_for) : nullptr;
  const auto settings = reinterpret_cast<PluginSettings>(::dlsym(handle, kSettingsSymbol));
  if (commands == nullptr || built_for == nullptr || key != built_for || settings == nullptr) {
    ::dlclose(handle);
    why = "it is not a plugin of this wlx (no entry point of this interface, or another key)";
    return nullptr;
  }
  if (const char* refused = settings(description.c_str()); refused != nullptr)
    throw PluginBuildError(fmt::format("the plugin for model {} refused its description: {}", manifest_value(manifest, "model"), refused));
  loaded_commands().emplace(std::pair{library.string(), description}, commands);
  (other_numbers ? copy : closing).keep = true;
  return commands;  // never closed: its code and strings are in use until exit
}

// A path written into an #include: refused if it holds what a quoted include cannot carry.
std::string include_line(const fs::path& path) {
  const std::string p = path.string();
  if (p.find_first_of("\"\\\n\r") != std::string::npos)
    throw Error("--model-file", fmt::format("the path {} holds a quote, backslash or newline: move wlx or the cache "
                                            "(WLX_CACHE_DIR) to a plain path",
                                            excerpt(p)));
  return "#include \"" + p + "\"\n";
}

// A run of wlx-gen that did not succeed, as an error: the model file's mistake as wlx-gen states it
// (exit 2), else wlx-gen's failure.
void check_generator_run(const ProgramRun& run, const fs::path& log, const fs::path& model_file) {
  throw_if_interrupted();
  if (!run.started) throw Error("--model-file", fmt::format("cannot run wlx-gen ({}): reinstall wlx", generator_program().string()));
  if (run.ok()) return;
  std::string message = read_small(log, kMaxFileBytes);
  for (const std::string prefix : {"wlx-gen: error: ", "wlx-gen: "})
    if (message.rfind(prefix, 0) == 0) message = message.substr(prefix.size());
  while (!message.empty() && (message.back() == '\n' || message.back() == '\r')) message.pop_back();
  if (run.exit_status == 2) throw Error("", message);  // the file's mistake, as wlx-gen states it
  throw PluginBuildError(fmt::format("wlx-gen failed on {} (exit {}): {}", model_file.string(), run.exit_status, message));
}

// What wlx-gen parsed and derived from a model file (model.json): its text, the model's name and
// the fingerprint of its code. The cache key is made of these, never of the file's text.
struct Description {
  std::string text, name, code_key;
};

Description description_of(const std::string& text, const std::string& where) {
  Description d{text, {}, {}};
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    d.name = j.at("model").get<std::string>();
    d.code_key = j.at("code_key").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    throw PluginBuildError(fmt::format("wlx-gen's description of the model ({}) cannot be read: {}", where, e.what()));
  }
  // Pasted into the plugin's sources and file names: wlx-gen allows identifiers only; checked again.
  const bool identifier = !d.name.empty() && !std::isdigit(static_cast<unsigned char>(d.name[0])) &&
                          std::all_of(d.name.begin(), d.name.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
  if (!identifier || d.code_key.size() != 32 || d.code_key.find_first_not_of("0123456789abcdef") != std::string::npos)
    throw PluginBuildError(fmt::format("wlx-gen's description of the model ({}) names no model or code key", where));
  return d;
}

// wlx-gen --data-at-run-time --describe: the model file checked and derived (tens of milliseconds),
// nothing written; its mistakes are reported as wlx-gen reports them.
Description describe(const fs::path& model_file, const fs::path& scratch) {
  // A folder of its own (mkdtemp): two loads at once (Python threads, processes of other pid
  // namespaces sharing the cache) never read each other's description.
  std::string pattern = (scratch / ".describe-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr)
    throw Error("--model-file", fmt::format("cannot create a scratch folder in {} ({})", scratch.string(), std::strerror(errno)));
  const TemporaryFolder folder{pattern};
  const fs::path out = folder.path / "model.json", log = folder.path / "wlx-gen.log";
  const ProgramRun run = run_program(
      {generator_program().string(), fs::absolute(model_file).string(), "--data-at-run-time", "--describe", "--quiet"}, {},
      out.string(), log.string());
  check_generator_run(run, log, model_file);
  return description_of(read_small(out, kMaxFileBytes), "wlx-gen --describe");
}

// The generated functions' sources (WLX_PLUGIN_GENERATED_SOURCES) gathered into translation units
// of at most kGeneratedUnitBytes of generated headers each (first fit, the largest first). Each
// translation unit costs about 0.8 s of its own (the headers every one parses) and then about
// 5 us per byte of generated code (clang 14, -O3, the precompiled headers; 9 us at -O2 without
// them): a small model's four sources compile in 2.9 s as one instead of 5.0 s apart, while a large
// model's largest source stays alone, so that no unit outlasts the runtime's (about 7 s).
struct GeneratedUnit {
  std::string stem;
  std::vector<std::string> sources;
  std::uintmax_t bytes = 0;
};
constexpr std::uintmax_t kGeneratedUnitBytes = 500'000;
std::vector<GeneratedUnit> generated_units(const fs::path& runtime_sources, const fs::path& generated) {
  // Each source's share: the generated headers it includes (`#include <wlx/gen/NAME.hpp>`, which
  // a model may not have), by their size.
  std::vector<std::pair<std::uintmax_t, std::string>> sized;
  for (const auto& f : split_list(WLX_PLUGIN_GENERATED_SOURCES)) {
    std::uintmax_t bytes = 0;
    std::istringstream lines(read_small(runtime_sources / f, kMaxFileBytes));
    const std::string prefix = "#include <wlx/gen/";
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind(prefix, 0) != 0 || line.back() != '>') continue;
      std::error_code ec;
      const std::uintmax_t size = fs::file_size(generated / line.substr(prefix.size(), line.size() - prefix.size() - 1), ec);
      if (!ec) bytes += size;
    }
    sized.emplace_back(bytes, f);
  }
  std::stable_sort(sized.begin(), sized.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<GeneratedUnit> units;
  for (const auto& [size, f] : sized) {
    const std::uintmax_t bytes = size;  // (a lambda cannot capture a structured binding in clang 14)
    auto fits = std::find_if(units.begin(), units.end(), [&](const GeneratedUnit& u) { return u.bytes + bytes <= kGeneratedUnitBytes; });
    if (fits == units.end()) fits = units.insert(units.end(), GeneratedUnit{fmt::format("generated_unit_{}", units.size() + 1), {}, 0});
    fits->sources.push_back(f);
    fits->bytes += bytes;
  }
  return units;  // the largest first: the longest compiles start first
}

// The plugin's common headers precompiled for a part: the arguments that load them, and the archive
// that holds their code where they were precompiled with it (-fpch-codegen: the commands' header,
// plugin_prelude_commands.hpp), which the plugin then links; none of either when there is no such
// header, or the compiler refuses it.
struct PrecompiledPrelude {
  std::vector<std::string> flags;
  std::string archive;
};

// The name of the precompiled header for `flags`: each flag without its '-', joined by '_' ("-O3"
// -> "O3", as CMakeLists.txt names them); empty for flags that make no such name.
std::string prelude_name(const std::vector<std::string>& flags) {
  std::string name;
  for (const std::string& flag : flags) {
    if (flag.size() < 2 || flag[0] != '-') return {};
    name += (name.empty() ? "" : "_") + flag.substr(1);
  }
  if (!std::all_of(name.begin(), name.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; })) return {};
  return name;
}

// The precompiled header for a part compiled with `argv` (the compiler, then its flags:
// `optimization`'s last). wlx's build precompiles one per optimization of a model's parts, named
// after those flags (plugin_prelude-O3.pch for "-O3"; CMakeLists.txt), with its code beside it in
// plugin_prelude-<name>.a where it has some; only the Clang wlx was built with, with the same flags,
// can load one (CXX may name it another way), and not once a header it was made from has changed.
// A compile of nothing with it (60 ms) asks the compiler first, so that a header it refuses
// (another compiler, GCC, a changed header) costs the plugin its speed, never its build; its answer
// is in precompiled-<name>.log. WLX_PLUGIN_PRECOMPILED_DIR names another folder to look in (empty:
// none).
PrecompiledPrelude precompiled_prelude(const Sources& src, const std::vector<std::string>& optimization, std::vector<std::string> argv,
                                       const fs::path& dir) {
  const char* env = std::getenv("WLX_PLUGIN_PRECOMPILED_DIR");
  const fs::path folder = env != nullptr ? fs::path(env) : src.precompiled;
  const std::string name = prelude_name(optimization);
  if (folder.empty() || name.empty()) return {};
  const fs::path pch = folder / fmt::format("plugin_prelude-{}.pch", name);
  std::error_code ec;
  if (!fs::is_regular_file(pch, ec)) return {};
  const std::vector<std::string> use{"-include-pch", pch.string()};
  argv.insert(argv.end(), use.begin(), use.end());
  argv.insert(argv.end(), {"-fsyntax-only", "-x", "c++", "/dev/null"});
  const fs::path log = dir / fmt::format("precompiled-{}.log", name);
  if (!run_program(argv, {}, log.string()).ok()) return {};
  // The header precompiled for the commands' flags holds no code of its own (-fpch-codegen): its
  // units only call that code, which its archive holds. Without the archive the plugin would link
  // and then fail to load, so the header is not used.
  const fs::path archive = fs::path(pch).replace_extension(".a");
  const bool has_archive = fs::is_regular_file(archive, ec);
  if (!has_archive && name == prelude_name(split_flags(WLX_PLUGIN_COMMANDS_OPTIMIZATION))) {
    write_file_atomically(log.string(), read_bounded_file(log.string(), kMaxFileBytes).text +
                                             fmt::format("{} holds no code and {} is missing: not used\n", pch.string(), archive.string()));
    return {};
  }
  return {use, has_archive ? archive.string() : std::string()};
}

// Generates the model's headers and compiles its plugin into `dir`.
void build_plugin(const fs::path& model_file, const Description& description, const std::string& key, const fs::path& dir,
                  const fs::path& failed_logs) {
  const std::string& name = description.name;
  // wlx-gen first: a mistake in the model file is reported as wlx-gen reports it, before any compiling.
  // The headers leave the file's numbers out (--data-at-run-time): they come from model.json at load.
  const auto start = std::chrono::steady_clock::now();
  const fs::path gen = dir / "generated";
  const fs::path gen_log = dir / "wlx-gen.log";
  const ProgramRun generated = run_program(
      {generator_program().string(), fs::absolute(model_file).string(), "--data-at-run-time", "--out", gen.string(), "--quiet"}, {},
      gen_log.string());
  Timings timings{{"wlx-gen", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()}};
  check_generator_run(generated, gen_log, model_file);
  // The file may have changed since it was described: the code must be the code the key names.
  if (description_of(read_small(gen / "wlx" / "gen" / "model.json", kMaxFileBytes), "model.json").code_key != description.code_key)
    throw Error("--model-file", fmt::format("{} changed while wlx was reading it: run the command again", model_file.string()));

  wlx::diagnose("wlx: compiling model {} for first use ({}) ...\n", name, model_file.string());
  const Sources src = find_sources();
  const auto write = [&](const fs::path& path, const std::string& text) { write_file_atomically(path.string(), text); };
  // The runtime's sources in one translation unit, but those CMake names apart
  // (WLX_PLUGIN_RUNTIME_APART: simulation.cpp, torque_distribution.cpp and nonholonomic.cpp, the
  // runtime's longest compiles, each on its own), so that
  // the two cores share the longest compile instead of one core waiting for it.
  const std::vector<std::string> apart = split_list(WLX_PLUGIN_RUNTIME_APART);
  std::string runtime_unity = "// The runtime's sources in one translation unit (those compiled apart excepted).\n";
  for (const auto& f : split_list(WLX_PLUGIN_RUNTIME_SOURCES))
    if (std::find(apart.begin(), apart.end(), f) == apart.end()) runtime_unity += include_line(src.runtime_sources / f);
  write(dir / "runtime_unity.cpp", runtime_unity);
  std::string commands_unity = "// The per-model commands in one translation unit (as CMake's unity build of wlx_cli_<model>).\n";
  for (const auto& f : split_list(WLX_PLUGIN_COMMAND_SOURCES)) commands_unity += include_line(src.cli / f);
  // (No embedded runs: the list ends with commands/no_embedded_runs.cpp.)
  commands_unity += fmt::format(
      "// The entry points wlx looks up with dlsym: the commands, and the key this plugin was built for;\n"
      "// and the model's settings, from its description (model.json), which its headers leave out.\n"
      "extern \"C\" __attribute__((visibility(\"default\"))) const wlx::cli::ModelCommands* {1}(const char** key) {{\n"
      "  *key = \"{2}\";\n"
      "  return &wlx::{0}::commands::entry();\n"
      "}}\n"
      "extern \"C\" __attribute__((visibility(\"default\"))) const char* {3}(const char* description) {{\n"
      "  static std::string refused;\n"
      "  refused = wlx::{0}::commands::load_description(description);\n"
      "  return refused.empty() ? nullptr : refused.c_str();\n"
      "}}\n",
      name, kEntrySymbol, key, kSettingsSymbol);
  write(dir / "commands_unity.cpp", commands_unity);

  const std::string cxx = compiler();
  std::vector<std::string> common{cxx, "-std=c++20", "-fPIC", "-DNDEBUG", "-DWLX_MODEL=" + name, "-DWLX_GEN_COMPILED_" + name};
  for (const fs::path& include : {gen, src.runtime_include, src.support_include, src.cli / "shell", src.cli, src.cli / "commands"}) common.push_back("-I" + include.string());
  for (const auto& include : split_list(WLX_PLUGIN_INCLUDES)) common.push_back("-isystem" + include);
  for (const auto& definition : split_list(WLX_PLUGIN_DEFINES)) common.push_back(definition);
  std::vector<Job> jobs;
  std::vector<std::string> objects;
  std::map<bool, std::vector<std::string>> part_flags;  // by "is the commands' part"
  std::vector<std::string> prelude_archives;            // the code of the precompiled headers the parts load
  const auto probing = std::chrono::steady_clock::now();
  for (const bool commands : {false, true}) {
    // Both parts at the same flags (WLX_PLUGIN_CXXFLAGS): the runtime's, checked once.
    if (commands && optimization_flags(true) == optimization_flags(false)) {
      part_flags[true] = part_flags[false];
      continue;
    }
    std::vector<std::string> argv = common;
    const std::vector<std::string> optimization = optimization_flags(commands);
    argv.insert(argv.end(), optimization.begin(), optimization.end());
    const PrecompiledPrelude prelude = precompiled_prelude(src, optimization, argv, dir);
    argv.insert(argv.end(), prelude.flags.begin(), prelude.flags.end());
    if (!prelude.archive.empty()) prelude_archives.push_back(prelude.archive);
    part_flags[commands] = argv;
  }
  timings.emplace_back("precompiled headers checked", std::chrono::duration<double>(std::chrono::steady_clock::now() - probing).count());
  // Each compile with its expected seconds on one core, for the order below.
  std::vector<std::pair<double, Job>> planned;
  const auto compile = [&](const std::string& what, const fs::path& source, const std::string& stem, double seconds) {
    std::vector<std::string> argv = part_flags.at(what == "commands");
    argv.insert(argv.end(), {"-c", source.string(), "-o", (dir / (stem + ".o")).string()});
    planned.push_back({seconds, {what, argv, dir / (stem + ".log")}});
    objects.push_back((dir / (stem + ".o")).string());
  };
  // Expected seconds (clang 14, 2 cores, the precompiled headers; excavator, wheeled quadruped and a
  // 43-joint model measured): the runtime's unity 7-8.5 and the commands' 6-7 whatever the model,
  // each file compiled apart 2.4-3.6, a unit of generated functions 0.8 s plus about 5 us per byte
  // of the generated headers it includes (2-4.5 s; kGeneratedUnitBytes bounds it). Only the order
  // depends on them.
  compile("commands", dir / "commands_unity.cpp", "commands_unity", 6.5);
  compile("runtime", dir / "runtime_unity.cpp", "runtime_unity", 7.0);
  for (const auto& f : apart) compile("runtime " + f, src.runtime_sources / f, "runtime_" + fs::path(f).stem().string(), 3.0);
  for (const GeneratedUnit& unit : generated_units(src.runtime_sources, gen / "wlx" / "gen")) {
    std::string text = "// The generated functions of " + fmt::format("{}", fmt::join(unit.sources, ", ")) + ", in one translation unit.\n";
    for (const auto& f : unit.sources) text += include_line(src.runtime_sources / f);
    write(dir / (unit.stem + ".cpp"), text);
    compile("generated functions " + fmt::format("{}", fmt::join(unit.sources, " ")), dir / (unit.stem + ".cpp"), unit.stem,
            0.8 + 5e-6 * static_cast<double>(unit.bytes));
  }
  // The longest first, each started as a core frees (longest processing time first), so that the
  // cores finish together: with the generated functions last, as before, the excavator's cores
  // stood 2 s apart at the end.
  std::stable_sort(planned.begin(), planned.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (auto& [seconds, job] : planned) jobs.push_back(std::move(job));
  const unsigned cores = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  const auto compiling = std::chrono::steady_clock::now();
  for (const auto& t : run_jobs(jobs, cores, failed_logs)) timings.push_back(t);
  timings.emplace_back(fmt::format("all compiles, {} at once", cores),
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - compiling).count());

  // -Bsymbolic: the plugin's calls stay inside it, even where wlx itself has a model of the same
  // name (a user's copy of a built-in model, with other geometry, must not run wlx's).
  std::vector<std::string> link{cxx, "-shared", "-Wl,-Bsymbolic", "-o", (dir / "plugin.so").string()};
  link.insert(link.end(), objects.begin(), objects.end());
  // The precompiled headers' code holds every inline function of their headers, some of which call
  // what the standard library keeps to itself (std::filesystem::path's private parts): those the
  // plugin does not call must go, or dlopen would refuse it. Its symbols not exported
  // (--exclude-libs), every function in a section of its own, --gc-sections drops them.
  if (!prelude_archives.empty()) link.push_back("-Wl,--gc-sections");
  for (const auto& archive : prelude_archives) {
    link.push_back("-Wl,--exclude-libs," + fs::path(archive).filename().string());
    link.push_back(archive);
  }
  for (const auto& library : split_list(WLX_PLUGIN_LIBRARIES)) link.push_back(library);
  for (const auto& t : run_jobs({{"link", link, dir / "link.log"}}, 1, failed_logs)) timings.push_back(t);

  std::uintmax_t size = 0;
  const std::string checksum = file_checksum(dir / "plugin.so", size);
  write(dir / "manifest", fmt::format("wlx model plugin (interface {})\nkey {}\nmodel {}\ncode {}\nsize {}\nchecksum {}\nsource {}\n",
                                      kPluginInterface, key, name, description.code_key, size, checksum,
                                      fs::absolute(model_file).string()));
  // What the plugin no longer needs: the objects and the unity sources (the headers stay, to read).
  std::error_code ec;
  for (const auto& object : objects) fs::remove(object, ec);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  timings.emplace_back("first use, in all", seconds);
  write(dir / "build-times.tsv", timings_text(timings));
  wlx::diagnose("wlx: compiled model {} in {:.1f} s\n", name, seconds);
}

// The cache entry of the model file loaded last (load_model_file), for its viewer module.
struct LoadedEntry {
  fs::path cache, entry;
  std::string stem, name;
  fs::path model_file;
  std::string description;  // model.json's text: the viewer's module compiles its numbers in
};
LoadedEntry& loaded_entry() {
  static LoadedEntry e;
  return e;
}

}  // namespace

void set_plugin_host_bin_dir(const std::string& bin_dir) { host_bin_dir() = bin_dir; }

std::string model_cache_dir() {
  fs::path dir;
  if (const char* env = std::getenv("WLX_CACHE_DIR"); env != nullptr && *env != '\0') dir = env;
  else if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg == '/') dir = fs::path(xdg) / "wlx";
  else if (const char* home = std::getenv("HOME"); home != nullptr && *home == '/') dir = fs::path(home) / ".cache" / "wlx";
  else throw Error("--model-file", "no cache folder: set WLX_CACHE_DIR (or HOME)");
  std::error_code ec;
  const bool existed = fs::exists(dir, ec);
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir, ec))
    throw Error("--model-file", fmt::format("the cache folder {} cannot be created ({})", dir.string(), ec.message()));
  if (!existed) ::chmod(dir.c_str(), 0700);  // made here: the user's alone
  check_private(dir, "folder", true);
  return dir.string();
}

std::string describe_model_file(const std::string& model_file) {
  const BoundedRead file = read_bounded_file(model_file, kMaxFileBytes);
  if (!file.ok()) throw Error("--model-file", fmt::format("{}: {}", excerpt(model_file), file.error));
  return describe(model_file, model_cache_dir()).text;
}

const ModelCommands& load_model_file(const std::string& model_file, const std::string& version) {
  // One load at a time in a process (Python threads): the loaded plugins' table, the settings a
  // plugin is handed and the cache's files are not shared mid-way.
  static std::mutex loading;
  const std::lock_guard<std::mutex> one_at_a_time(loading);
  const BoundedRead file = read_bounded_file(model_file, kMaxFileBytes);
  if (!file.ok()) throw Error("--model-file", fmt::format("{}: {}", excerpt(model_file), file.error));
  const fs::path cache = model_cache_dir();
  // What wlx-gen parsed and derived: the model's name and the fingerprint of the code its headers
  // hold, which covers every file it read (a URDF too) and leaves out the numbers a plugin reads at
  // run time (model.json): editing those finds the same plugin and compiles nothing.
  const Description description = describe(model_file, cache);
  const std::string& name = description.name;

  // The key: everything the plugin's code depends on.
  Hash h;
  h.add(fmt::format("wlx model plugin, interface {}", kPluginInterface));
  h.add(version);
  h.add(name);
  h.add(description.code_key);
  h.add(built_with_compiler());
  for (const bool commands : {false, true})
    for (const auto& f : optimization_flags(commands)) h.add(f);
  h.add(WLX_PLUGIN_INCLUDES);
  h.add(WLX_PLUGIN_DEFINES);
  h.add(WLX_PLUGIN_LIBRARIES);
  // The sources the plugin is compiled from and the interface it is loaded through (a rebuilt wlx
  // may have other sources under the same version); the generator's part is the code key.
  // Not the loading binary: `wlx` and Python's module share one entry per model.
  hash_sources(find_sources(), h);
  const std::string key = h.hex();

  const std::string stem = name + "-" + key.substr(0, 24);
  const fs::path entry = cache / stem;
  loaded_entry() = {cache, entry, stem, name, fs::absolute(model_file), description.text};  // for its viewer module
  std::string why;
  if (const ModelCommands* commands = try_load(entry, key, description.text, why)) return *commands;

  const FileLock lock(cache / (stem + ".lock"),
                      fmt::format("wlx: waiting for another wlx compiling model {} ({})", name, (cache / stem).string()));
  if (const ModelCommands* commands = try_load(entry, key, description.text, why)) return *commands;  // the other one built it
  std::error_code ec;
  if (fs::exists(entry, ec)) {
    wlx::diagnose("wlx: the cached plugin {} cannot be used ({}): building it again\n", entry.string(), why);
    fs::remove_all(entry, ec);
  }
  remove_abandoned_builds(cache, stem);
  TemporaryFolder building{cache / (stem + ".build-" + std::to_string(::getpid()))};
  fs::remove_all(building.path, ec);
  fs::create_directories(building.path, ec);
  if (ec) throw Error("--model-file", fmt::format("cannot create {} ({})", building.path.string(), ec.message()));
  build_plugin(model_file, description, key, building.path, cache / (stem + ".failed"));
  // Whatever the umask (002 is common): the entry is the user's alone, as the next load checks.
  for (fs::recursive_directory_iterator it(building.path, ec), end; !ec && it != end; it.increment(ec))
    if (!it->is_symlink(ec)) fs::permissions(it->path(), fs::perms::group_write | fs::perms::others_write, fs::perm_options::remove, ec);
  ::chmod(building.path.c_str(), 0700);
  record_digest(cache, stem, manifest_value(read_small(building.path / "manifest", 1 << 16), "checksum"));
  fs::rename(building.path, entry, ec);
  if (ec) throw Error("--model-file", fmt::format("cannot put the plugin in place at {} ({})", entry.string(), ec.message()));
  building.keep = true;
  fs::remove_all(cache / (stem + ".failed"), ec);
  wlx::diagnose("wlx: cached in {}\n", entry.string());
  if (const ModelCommands* commands = try_load(entry, key, description.text, why)) return *commands;
  throw PluginBuildError(fmt::format("the plugin just built for model {} cannot be loaded: {}", name, why));
}

}  // namespace wlx::cli

namespace wlx::cli {

std::string model_file_viewer_module() {
  const LoadedEntry& loaded = loaded_entry();
  if (loaded.entry.empty()) throw Error("viewer", "no model file is loaded");
#ifndef WLX_VIEWER_EMCC
  throw Error("viewer", "this wlx was built without the viewer (emscripten, node and npm were missing when it was built), so it "
                        "cannot build one for a model file");
#else
  // The viewer's optimization (cmake/wlxModelBuild.cmake) by default; WLX_PLUGIN_EMCCFLAGS replaces
  // it (the tests' -O0).
  const std::vector<std::string> flags = flags_from_environment("WLX_PLUGIN_EMCCFLAGS", WLX_VIEWER_OPTIMIZATION);
  // The module's folder is named by what it is compiled with beyond the entry's key (which holds
  // the sources): emscripten itself, the flags, the exports and the source lists that
  // viewer/CMakeLists.txt gave this wlx. Another wlx or other flags: another folder, never a stale
  // module.
  const fs::path emcc = WLX_VIEWER_EMCC;
  Hash h;
  for (const char* fact : {WLX_VIEWER_EMCC, WLX_VIEWER_NODE_PATH, WLX_VIEWER_FMT_INCLUDE, WLX_VIEWER_EIGEN_INCLUDES, WLX_VIEWER_EXPORTS,
                           WLX_VIEWER_RUNTIME_SOURCES, WLX_VIEWER_CLI_SOURCES})
    h.add(fact);
  for (const auto& f : flags) h.add(f);
  // The module compiles the model's numbers in (it has no loader for model.json): they are keyed too.
  h.add(loaded.description);
  struct stat emcc_file {};
  if (::stat(emcc.c_str(), &emcc_file) == 0)
    h.add(fmt::format("{} {} {}", emcc_file.st_size, emcc_file.st_mtim.tv_sec, emcc_file.st_mtim.tv_nsec));
  const fs::path module = loaded.entry / ("viewer-" + h.hex().substr(0, 16)) / ("wlx_" + loaded.name + ".js");
  std::error_code ec;
  if (fs::is_regular_file(module, ec)) return module.string();
  const FileLock lock(loaded.cache / (loaded.stem + ".lock"),
                      fmt::format("wlx: waiting for another wlx building model {}'s viewer module", loaded.name));
  if (fs::is_regular_file(module, ec)) return module.string();  // the other one built it
  if (!fs::is_regular_file(emcc, ec))
    throw Error("viewer", fmt::format("the viewer's module for model file {} is compiled with emscripten, and {} is missing "
                                      "(Debian: apt-get install emscripten)",
                                      loaded.name, emcc.string()));
  const auto start = std::chrono::steady_clock::now();
  wlx::diagnose("wlx: compiling model {}'s viewer module with emscripten for first use ...\n", loaded.name);
  const Sources src = find_sources();
  TemporaryFolder building{loaded.entry / ("viewer.build-" + std::to_string(::getpid()))};
  fs::remove_all(building.path, ec);
  fs::create_directories(building.path / "include", ec);
  if (ec) throw Error("viewer", fmt::format("cannot create {} ({})", building.path.string(), ec.message()));
  // fmt's headers alone on the include path: all of /usr/include would shadow emscripten's libc.
  fs::create_directory_symlink(fs::path(WLX_VIEWER_FMT_INCLUDE) / "fmt", building.path / "include" / "fmt", ec);
  if (ec) throw Error("viewer", fmt::format("cannot link fmt's headers into {} ({})", building.path.string(), ec.message()));
  // The model's headers with its numbers compiled in (settings.hpp), which the plugin's leave out.
  const fs::path gen_log = building.path / "wlx-gen.log";
  const ProgramRun generated = run_program(
      {generator_program().string(), loaded.model_file.string(), "--out", (building.path / "generated").string(), "--quiet"}, {},
      gen_log.string());
  check_generator_run(generated, gen_log, loaded.model_file);
  // The numbers compiled in must be those the loaded plugin was given (the file may have changed since).
  const auto numbers = [](const std::string& text) {
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    return j.is_object() ? nlohmann::json{j.value("source", nlohmann::json()), j.value("parameters", nlohmann::json()),
                                          j.value("settings", nlohmann::json())}
                         : nlohmann::json();
  };
  if (numbers(read_small(building.path / "generated" / "wlx" / "gen" / "model.json", kMaxFileBytes)) != numbers(loaded.description))
    throw Error("viewer", fmt::format("{} changed while wlx was reading it: run the command again", loaded.model_file.string()));
  std::string unity = "// The viewer module's sources in one translation unit (viewer/CMakeLists.txt's lists).\n";
  for (const auto& f : split_list(WLX_VIEWER_RUNTIME_SOURCES)) unity += include_line(src.runtime_sources / f);
  for (const auto& f : split_list(WLX_VIEWER_CLI_SOURCES)) unity += include_line(src.cli / f);
  unity += include_line(src.viewer_module / "viewer_module.cpp");
  write_file_atomically((building.path / "module_unity.cpp").string(), unity);
  const fs::path out = building.path / module.filename();
  // emcc runs node, whose optimizer needs Debian's acorn: env sets NODE_PATH (a program, no shell).
  std::vector<std::string> argv{"/usr/bin/env", std::string("NODE_PATH=") + WLX_VIEWER_NODE_PATH, emcc.string(), "-std=c++20"};
  argv.insert(argv.end(), flags.begin(), flags.end());
  argv.insert(argv.end(), {"-fexceptions", "-DFMT_HEADER_ONLY", "-DWLX_MODEL=" + loaded.name, "-I" + src.runtime_include.string(),
                           "-I" + (src.cli / "commands").string(), "-I" + (src.cli / "shell").string(),
                           "-isystem" + (building.path / "include").string(), "-isystem" + (building.path / "generated").string()});
  for (const auto& include : split_list(WLX_VIEWER_EIGEN_INCLUDES)) argv.push_back("-isystem" + include);
  // SINGLE_FILE: the WebAssembly inlined in the script, which a page opened from file:// can load.
  argv.insert(argv.end(), {(building.path / "module_unity.cpp").string(), "-o", out.string(), "-sMODULARIZE=1",
                           "-sEXPORT_NAME=wlxModule_" + loaded.name, "-sSINGLE_FILE=1", "-sALLOW_MEMORY_GROWTH=1",
                           std::string("-sEXPORTED_FUNCTIONS=") + WLX_VIEWER_EXPORTS, "-sEXPORTED_RUNTIME_METHODS=UTF8ToString"});
  const Timings timings = run_jobs({{"viewer module (emcc)", argv, building.path / "emcc.log"}}, 1,
                                    loaded.cache / (loaded.stem + ".viewer-failed"));
  fs::create_directories(module.parent_path(), ec);
  write_file_atomically((module.parent_path() / "build-times.tsv").string(), timings_text(timings));
  fs::rename(out, module, ec);
  if (ec) throw Error("viewer", fmt::format("cannot put the viewer module in place at {} ({})", module.string(), ec.message()));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  wlx::diagnose("wlx: compiled model {}'s viewer module in {:.1f} s\n", loaded.name, seconds);
  return module.string();
#endif
}

}  // namespace wlx::cli
