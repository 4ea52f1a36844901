// wlx-gen: derives the model's equations with GiNaC and emits header-only C++ into a folder.
#include "derivations.hpp"
#include "emit.hpp"
#include "model_file.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <wlx/support/diagnostics.hpp>
#include <wlx/support/atomic_file.hpp>
#include <wlx/support/bounded_file.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <iterator>
#include <set>
#include <sstream>
#include <string_view>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

#ifndef WLX_VERSION
#define WLX_VERSION "unknown"
#endif

namespace fs = std::filesystem;
using namespace wlx::codegen;

namespace {

// ---- signals ----
// SIGINT, SIGTERM and SIGHUP. While wlx-gen derives (GiNaC, possibly minutes, with no place to
// poll often enough) it has written nothing, so the handler ends the process at once. Once the
// headers are being written it only records the signal: the writing polls it before every step
// and unwinds, so the temporaries are removed and the previous header set is restored.
volatile std::sig_atomic_t received_signal = 0;
volatile std::sig_atomic_t writing = 0;

const char* signal_message(int signal) {
  return signal == SIGINT ? "wlx-gen: interrupted (SIGINT)\n" : signal == SIGTERM ? "wlx-gen: terminated (SIGTERM)\n" : "wlx-gen: hung up (SIGHUP)\n";
}

extern "C" void on_signal(int signal) {
  received_signal = signal;
  if (writing) return;
  // Only async-signal-safe calls here: write(2) and _exit(2).
  const char* message = signal_message(signal);
  const ssize_t ignored = ::write(STDERR_FILENO, message, std::strlen(message));
  static_cast<void>(ignored);
  ::_exit(128 + signal);
}

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &action, nullptr);
  // A closed stdout is then a write error with a message and exit code 74, not a silent death.
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGPIPE, &ignore, nullptr);
}

struct Interrupted {
  int signal;
};

// A check point of the writing: unwinds (removing temporaries, restoring the old set) on a signal.
void stop_if_signalled() {
  if (const int signal = received_signal) throw Interrupted{signal};
}

// Everything wlx-gen prints goes through here, and stdout is checked when flushed: a full disk or
// a closed pipe is an output error (exit 74), not a success with the output lost.
void write_stdout(const std::string& text) {
  if (!text.empty() && std::fwrite(text.data(), 1, text.size(), stdout) != text.size())
    throw wlx::OutputError("stdout", std::strerror(errno));
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) throw wlx::OutputError("stdout", std::strerror(errno));
}

// The replacement of a header set: each header renamed over the old one, which stays reachable
// under a backup name (a hard link, created exclusively) until all are in place. Unless keep()
// is called (a failed rename, a signal), the destructor undoes every replacement in reverse, so
// the folder holds the previous set again, and removes the backups.
class SetReplacement {
 public:
  SetReplacement() = default;
  SetReplacement(const SetReplacement&) = delete;
  SetReplacement& operator=(const SetReplacement&) = delete;
  ~SetReplacement() {
    for (auto step = steps_.rbegin(); step != steps_.rend(); ++step) {
      if (!kept_ && step->renamed) {
        if (step->backup.empty()) ::unlink(step->path.c_str());  // a header that was not there before
        else if (::rename(step->backup.c_str(), step->path.c_str()) == 0) continue;
        else {  // the only copy of the previous header: kept, and said where
          wlx::diagnose("wlx-gen: error: {}: the previous version could not be put back ({}); it is kept as {}\n", step->path,
                        std::strerror(errno), step->backup);
          continue;
        }
      }
      if (!step->backup.empty()) ::unlink(step->backup.c_str());
    }
  }

  void replace(wlx::AtomicFile& file) {
    Step step{file.path(), {}, false};
    struct stat old {};
    // Regular files and links are kept (a link as itself: link(2) does not follow it); anything
    // else under a header's name makes the rename fail, which undoes the set.
    if (::lstat(step.path.c_str(), &old) == 0 && (S_ISREG(old.st_mode) || S_ISLNK(old.st_mode))) {
      for (int attempt = 0; step.backup.empty(); ++attempt) {
        const std::string name = fmt::format("{}.{}-{}.old", step.path, static_cast<long>(::getpid()), attempt);
        if (::link(step.path.c_str(), name.c_str()) == 0) step.backup = name;
        // A file system without hard links (vfat, some FUSE): a copy, created exclusively.
        else if ((errno == EPERM || errno == EOPNOTSUPP || errno == EXDEV) && S_ISREG(old.st_mode)) {
          std::error_code ec;
          if (std::filesystem::copy_file(step.path, name, std::filesystem::copy_options::none, ec)) step.backup = name;
          else if (ec != std::errc::file_exists || attempt >= 100)
            throw wlx::OutputError(step.path, fmt::format("cannot keep the previous version while replacing it ({})", ec.message()));
        } else if (errno != EEXIST || attempt >= 100)
          throw wlx::OutputError(step.path, fmt::format("cannot keep the previous version while replacing it ({})", std::strerror(errno)));
      }
    }
    steps_.push_back(step);
    file.commit();
    steps_.back().renamed = true;
  }
  void keep() { kept_ = true; }

 private:
  struct Step {
    std::string path, backup;  // backup: the previous header's second name; empty when there was none
    bool renamed;
  };
  std::vector<Step> steps_;
  bool kept_ = false;
};

// The header set is replaced as a whole: every changed header is first written and synced under
// a unique temporary name beside it (created with O_EXCL, so a planted file or symlink there is
// never written through; wlx::AtomicFile), and only when all are complete are they renamed into
// place (SetReplacement). A full disk, a failed rename, a signal or any other failure leaves the
// previous set intact and no temporary behind (the AtomicFiles' destructors remove them).
// Unchanged headers keep their time stamps, except all.hpp: it is written whenever any header
// changes, so that a build system that names it as the generation's output (CMake's BYPRODUCTS)
// recompiles everything that includes it, which every runtime source does; without that, Ninja
// decides what is stale before the generator runs and keeps objects built from the old headers.
int write_header_set(const fs::path& out_dir, const std::vector<EmittedFile>& files) {
  std::vector<bool> changed(files.size(), false);
  bool any = false;
  for (std::size_t i = 0; i < files.size(); ++i) {
    // A header's size is far below the bound; an old "header" that is a device or a link to one
    // is simply replaced (the rename replaces the link, not its target).
    const wlx::BoundedRead old = wlx::read_bounded_file((out_dir / files[i].path).string(), std::size_t{64} << 20);
    changed[i] = !(old.ok() && old.text == files[i].text);
    any = any || changed[i];
  }
  std::vector<std::unique_ptr<wlx::AtomicFile>> pending;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const auto& f = files[i];
    stop_if_signalled();
    const fs::path path = out_dir / f.path;
    if (!changed[i] && !(any && path.filename() == "all.hpp")) continue;
    std::error_code error;
    fs::create_directories(path.parent_path(), error);
    if (error) throw wlx::OutputError(path.parent_path().string(), fmt::format("cannot create the folder ({})", error.message()));
    auto file = std::make_unique<wlx::AtomicFile>(path.string());
    file->write(f.text);
    stop_if_signalled();
    file->finish();
    pending.push_back(std::move(file));
  }
  SetReplacement replacement;
  for (auto& file : pending) {
    stop_if_signalled();
    replacement.replace(*file);
  }
  stop_if_signalled();
  replacement.keep();
  return static_cast<int>(pending.size());
}

// Removes the headers in OUT/wlx/gen/ that an earlier wlx-gen wrote and this one no longer
// produces (a renamed or dropped function), so that nobody includes a stale one. Only files whose
// banner says wlx-gen generated them; anything else there is left alone.
int remove_stale(const fs::path& dir, const std::vector<EmittedFile>& files) {
  std::set<fs::path> produced;
  for (const auto& f : files) produced.insert(fs::path(f.path).lexically_normal());
  int removed = 0;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(dir / "wlx" / "gen", error)) {
    const fs::path relative = fs::relative(entry.path(), dir).lexically_normal();
    if (!entry.is_regular_file() || entry.path().extension() != ".hpp" || produced.count(relative)) continue;
    std::ifstream in(entry.path());
    std::string first, second, third;
    std::getline(in, first);
    std::getline(in, second);
    std::getline(in, third);
    if (third.rfind("// Generated by wlx-gen ", 0) != 0) continue;
    if (!fs::remove(entry.path(), error) || error)
      throw wlx::OutputError(entry.path().string(), fmt::format("cannot remove this stale header ({})", error.message()));
    ++removed;
  }
  return removed;
}

// A Makefile-style depfile, "TARGET: INPUT...", which Ninja and Make read (CMake's add_custom_command
// DEPFILE): absolute paths, with Make's escapes for spaces, '#' and '$'. A path with a newline
// cannot be written in one, so it is an error rather than a depfile that names another file.
std::string depfile_path(const std::string& path) {
  const std::string absolute = fs::absolute(path).lexically_normal().string();
  std::string out;
  for (const char c : absolute) {
    if (c == '\n' || c == '\r') throw ModelFileError(fmt::format("--depfile: the path {} holds a line break", absolute.substr(0, 200)));
    if (c == ' ' || c == '#') out += '\\';
    if (c == '$') out += '$';
    out += c;
  }
  return out;
}

void write_depfile(const std::string& depfile, const std::string& target, const std::vector<std::string>& inputs) {
  std::string text = depfile_path(target) + ":";
  for (const auto& input : inputs) text += " \\\n  " + depfile_path(input);
  wlx::write_file_atomically(depfile, text + "\n");
}

// What the command line asks for.
struct Request {
  std::string model_path, out_dir, with_path;
  std::vector<std::string> bake_args;
  bool bake_defaults = false, stats_only = false, quiet = false, print_model = false, describe = false;
  std::string depfile, depfile_target, expected_model;
  EmitOptions opt;
};

void add_options(CLI::App& app, Request& r) {
  app.add_option("MODEL", r.model_path,
                 "the model file (models/*.yaml; format: docs/model-format.md), or a URDF (robot.urdf) with --with")
      ->required();
  app.add_option("--with", r.with_path,
                 "for a URDF as MODEL: the YAML file that says what URDF cannot (docs/model-format.md, URDF import)");
  app.add_option("--out", r.out_dir, "output root; headers go to OUT/wlx/gen/ (required unless --print-model)");
  app.add_flag("--print-model", r.print_model,
               "print the model file wlx-gen reads (for a URDF: the frames, joints and bodies it maps to) and exit");
  app.add_flag("--data-at-run-time", r.opt.data_at_run_time,
               "leave the model file's numbers out of the headers (no settings.hpp, NaN parameter defaults): a plugin "
               "reads them from model.json, so that editing them compiles nothing");
  app.add_flag("--describe", r.describe,
               "derive everything, write nothing, and print model.json (the description, with the code's fingerprint "
               "code_key) on stdout");
  app.add_option("--bake", r.bake_args, "bake a parameter in as a constant: NAME=VALUE (repeatable)");
  app.add_flag("--bake-defaults", r.bake_defaults, "bake every geometry parameter (kinds length, offset, angle) in at its default");
  app.add_option("--namespace", r.opt.name_space,
                 "C++ namespace of the emitted code (default: wlx::<model>::gen, <model> inline)");
  app.add_option("--depfile", r.depfile,
                 "also write a Makefile-style depfile: the files the headers were derived from (the model file and "
                 "the URDF it names), so that a build system reruns wlx-gen when any of them changes");
  app.add_option("--depfile-target", r.depfile_target, "the depfile's target (default: OUT/wlx/gen/all.hpp)");
  app.add_option("--expect-model", r.expected_model,
                 "the model's name the build was told (CMake's wlx_generate): a model file whose `model:` differs is an error");
  app.add_flag("--quiet", r.quiet, "print nothing on success");
  app.add_flag("--stats", r.stats_only, "print the operation-count table (always printed unless --quiet)");
  app.set_version_flag("--version", WLX_VERSION, "print the version and exit");
}

// The exit code when the command line is all that is done (--help, --version, a bad command line).
std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    const int code = app.exit(e);
    std::cout.flush();
    if (!std::cout || std::fflush(stdout) != 0 || std::ferror(stdout)) {
      wlx::diagnose("wlx-gen: error: stdout: {}\n", std::strerror(errno));
      return 74;
    }
    return code;
  } catch (const CLI::ParseError& e) {
    // Like every bad input: the option and the reason, exit code 2.
    wlx::diagnose("wlx-gen: error: {}\n", e.what());
    return 2;
  }
  return std::nullopt;
}

void check_namespace(const std::string& name_space) {
  // A qualified C++ identifier, nothing else: the name is pasted into every header.
  // (Checked by hand, not by std::regex, which costs this file a third of its compile.)
  const auto identifier = [](std::string_view part) {
    const auto letter = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; };
    return !part.empty() && letter(part[0]) &&
           std::all_of(part.begin(), part.end(), [&](char c) { return letter(c) || (c >= '0' && c <= '9'); });
  };
  std::vector<std::string> parts;
  for (std::size_t begin = 0; begin <= name_space.size();) {
    const std::size_t end = std::min(name_space.find("::", begin), name_space.size());
    parts.push_back(name_space.substr(begin, end - begin));
    begin = end + 2;
  }
  if (!std::all_of(parts.begin(), parts.end(), identifier))
    throw ModelFileError(fmt::format("--namespace: '{}' is not a C++ qualified name such as wlx::mine", name_space.substr(0, 60)));
  // Each part is pasted in as a name: no keyword, macro, std or Eigen (the model file's rule).
  for (const std::string& part : parts)
    if (const std::string why = cpp_name_problem(part); !why.empty())
      throw ModelFileError(fmt::format("--namespace: '{}' cannot be used: {}", part, why));
}

// `wlx-gen robot.urdf --with robot.yaml`: the YAML file is the model, the URDF its robot. Returns
// the URDF's path (empty when MODEL is a model file).
std::string urdf_from_command_line(std::string& model_path, const std::string& with_path) {
  std::string urdf_path;
  const bool urdf_given = model_path.size() >= 5 && model_path.compare(model_path.size() - 5, 5, ".urdf") == 0;
  if (urdf_given) {
    if (with_path.empty())
      throw ModelFileError(fmt::format("{}: a URDF needs --with robot.yaml, the file that names the base's inputs, the "
                                       "wheels, limbs and dynamics (docs/model-format.md, URDF import)",
                                       model_path.substr(0, 200)));
    urdf_path = model_path;
    model_path = with_path;
  } else if (!with_path.empty()) {
    throw ModelFileError("--with: only a URDF as MODEL takes --with (a model file names its URDF with `urdf:`)");
  }
  return urdf_path;
}

// The options that exclude or need each other.
void check_option_combinations(const Request& r) {
  if (r.describe && !r.out_dir.empty()) throw ModelFileError("--describe writes nothing: give --out or --describe, not both");
  if (r.out_dir.empty() && !r.describe) throw ModelFileError("--out is required (the output root; headers go to OUT/wlx/gen/)");
  if (r.opt.data_at_run_time && (r.bake_defaults || !r.bake_args.empty()))
    throw ModelFileError("--data-at-run-time reads every parameter's value at run time: it cannot bake any (--bake, --bake-defaults)");
  if (!r.depfile.empty() && r.out_dir.empty()) throw ModelFileError("--depfile lists what --out's headers depend on: give --out");
}

// One --bake NAME=VALUE; `baked_by` maps each NAME to its --bake argument: a second one would
// silently win.
void bake_argument(const std::string& arg, const Model& model, std::map<std::string, std::string>& baked_by,
                   std::map<std::string, double>& baked) {
  const auto eq = arg.find('=');
  const std::string shown = arg.substr(0, 60);
  if (eq == std::string::npos) throw ModelFileError(fmt::format("--bake {}: expected NAME=VALUE", shown));
  const std::string name = arg.substr(0, eq);
  if (const auto [first, added] = baked_by.emplace(name, shown); !added)
    throw ModelFileError(fmt::format("--bake {}: '{}' is given twice (first as --bake {})", shown, name.substr(0, 60), first->second));
  std::vector<std::string> names;
  std::size_t index = model.parameters.size();
  for (std::size_t k = 0; k < model.parameters.size(); ++k) {
    names.push_back(model.parameters[k].name);
    if (model.parameters[k].name == name) index = k;
  }
  if (index == model.parameters.size())
    throw ModelFileError(fmt::format("--bake {}: the model has no parameter '{}'{}", shown, name.substr(0, 60),
                                     did_you_mean(name, names)));
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(arg.substr(eq + 1), &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != arg.size() - eq - 1 || !std::isfinite(value))
    throw ModelFileError(fmt::format("--bake {}: the value of '{}' is not a finite number", shown, name));
  // Baked values obey the rules of the parameter's kind, as the model file's values do.
  const ParameterKind kind = model.parameter_kinds[index];
  if (const std::string why = parameter_value_problem(kind, value); !why.empty())
    throw ModelFileError(fmt::format("--bake {}: '{}' is {}, which {}", shown, name,
                                     kind == ParameterKind::gravity ? std::string("gravity") : fmt::format("a {}", kind_name(kind)), why));
  baked[name] = value;
}

// --bake-defaults (every geometry parameter at its default), then each --bake.
void bake_parameters(const Model& model, bool bake_defaults, const std::vector<std::string>& bake_args,
                     std::map<std::string, double>& baked) {
  if (bake_defaults)
    for (std::size_t k = 0; k < model.parameters.size(); ++k) {
      const ParameterKind kind = model.parameter_kinds[k];
      if (kind == ParameterKind::length || kind == ParameterKind::offset || kind == ParameterKind::angle)
        baked[model.parameters[k].name] = model.parameters[k].default_value;
    }
  std::map<std::string, std::string> baked_by;
  for (const auto& arg : bake_args) bake_argument(arg, model, baked_by, baked);
}

// The headers of a model, with what the report says of them.
struct Emitted {
  std::vector<EmittedFile> files;  // the description (model.json) last
  std::vector<FunctionStats> stats;
  std::vector<std::string> ik_report;
  std::chrono::steady_clock::time_point model_built;  // before the derivations
};

Emitted derive_and_emit(const Model& model, const EmitOptions& opt) {
  Emitted out;
  std::vector<EmittedFile>& files = out.files;
  files = emit_model_headers(model, opt);
  files.push_back(emit_trig_header(model, opt));
  files.push_back(emit_structure_header(model, opt));
  if (!opt.data_at_run_time) files.push_back(emit_settings_header(model, opt));
  out.model_built = std::chrono::steady_clock::now();
  std::vector<FunctionSpec> fns;
  for (const Derivation& derivation : derivations(model)) {
    const auto d0 = std::chrono::steady_clock::now();
    fns.push_back(derivation.derive(model));
    const double derive_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - d0).count();
    FunctionStats s;
    files.push_back(emit_function(model, fns.back(), opt, s));
    s.seconds += derive_s;
    out.stats.push_back(s);
  }
  files.push_back(emit_ik_header(model, opt, out.ik_report));
  files.push_back(emit_umbrella(model, fns, out.stats, opt));
  files.push_back(emit_description(model, opt, files));
  return out;
}

// The operation-count table and the summary line.
std::string stats_report(const Emitted& emitted, double model_seconds, double total_seconds, const std::string& out_dir, int changed,
                         int removed) {
  std::string report;
  const auto out = std::back_inserter(report);
  fmt::format_to(out, "{:<14} {:>8} {:>12} {:>11} {:>9}\n", "function", "temps", "ops before", "ops after", "seconds");
  long b = 0, a = 0;
  for (const auto& s : emitted.stats) {
    fmt::format_to(out, "{:<14} {:>8} {:>12} {:>11} {:>9.3f}\n", s.name, s.intermediates, s.before_cse.total(),
               s.after_cse.total(), s.seconds);
    b += s.before_cse.total();
    a += s.after_cse.total();
  }
  fmt::format_to(out, "{:<14} {:>8} {:>12} {:>11} {:>9.3f}\n", "total", "", b, a, total_seconds);
  for (const auto& line : emitted.ik_report) fmt::format_to(out, "closed-form IK, {}\n", line);
  fmt::format_to(out, "model built in {:.3f} s; {} files written to {} ({} changed{})\n", model_seconds, emitted.files.size(),
             out_dir, changed, removed ? fmt::format(", {} stale removed", removed) : "");
  return report;
}

// Everything after the command line is parsed; returns the exit code, throws what main reports.
int run(Request& r) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!r.opt.name_space.empty()) check_namespace(r.opt.name_space);
  const std::string urdf_path = urdf_from_command_line(r.model_path, r.with_path);
  if (r.print_model) {
    write_stdout(print_model_file(r.model_path, urdf_path));
    return 0;
  }
  check_option_combinations(r);
  const Model model = load_model_file(r.model_path, urdf_path);
  if (!r.expected_model.empty() && r.expected_model != model.name)
    throw ModelFileError(fmt::format("{}: `model: {}`, where the build expects the model '{}' (wlx_generate's NAME, else the "
                                     "file's name without .yaml): rename the model or the file, or give NAME",
                                     r.model_path.substr(0, 200), model.name, r.expected_model.substr(0, 60)));
  r.opt.model_name = model.name;
  bake_parameters(model, r.bake_defaults, r.bake_args, r.opt.baked);

  const Emitted emitted = derive_and_emit(model, r.opt);
  if (r.describe) {
    write_stdout(emitted.files.back().text);
    return 0;
  }
  writing = 1;  // from here a signal is polled (stop_if_signalled), so that the writing can undo itself
  const int changed = write_header_set(r.out_dir, emitted.files);
  const int removed = remove_stale(r.out_dir, emitted.files);
  writing = 0;
  if (const int signal = received_signal) throw Interrupted{signal};  // the new set is whole; still stop as asked
  if (!r.depfile.empty())
    write_depfile(r.depfile, r.depfile_target.empty() ? (fs::path(r.out_dir) / "wlx" / "gen" / "all.hpp").string() : r.depfile_target,
                  model.input_files);
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!r.quiet || r.stats_only)
    write_stdout(stats_report(emitted, std::chrono::duration<double>(emitted.model_built - t0).count(), total, r.out_dir, changed, removed));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"wlx-gen: derive a model's kinematics and dynamics symbolically and emit C++ headers"};
  Request request;
  request.opt.generator_version = WLX_VERSION;
  add_options(app, request);
  install_signal_handlers();
  if (const std::optional<int> code = parse_command_line(app, argc, argv)) return *code;

  try {
    return run(request);
  } catch (const Interrupted& e) {
    // The shell's convention: 128 + the signal (130 SIGINT, 143 SIGTERM, 129 SIGHUP).
    wlx::diagnose("{}", signal_message(e.signal));
    return 128 + e.signal;
  } catch (const ModelFileError& e) {
    wlx::diagnose("wlx-gen: error: {}\n", e.what());
    return 2;
  } catch (const wlx::OutputError& e) {
    // As wlx: 74 (EX_IOERR) when an output cannot be written; the previous headers are intact.
    wlx::diagnose("wlx-gen: error: {}: {}\n", e.field(), e.reason());
    return 74;
  } catch (const fs::filesystem_error& e) {
    wlx::diagnose("wlx-gen: error: {}: {}\n", e.path1().string(), e.code().message());
    return 74;
  } catch (const std::exception& e) {
    wlx::diagnose("wlx-gen: error: {}\n", e.what());
    return 1;
  }
}
