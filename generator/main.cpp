// wlx-gen: derives the model's equations with GiNaC and emits header-only C++ into a folder.
#include "derivations.hpp"
#include "emit.hpp"
#include "model_file.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>

#ifndef WLX_VERSION
#define WLX_VERSION "unknown"
#endif

namespace fs = std::filesystem;
using namespace wlx::codegen;

namespace {

// Writes only when the content changed, so unchanged headers keep their time stamps.
bool write_if_changed(const fs::path& path, const std::string& text) {
  if (std::ifstream in(path, std::ios::binary); in) {
    std::ostringstream old;
    old << in.rdbuf();
    if (old.str() == text) return false;
  }
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path.string());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"wlx-gen: derive a model's kinematics and dynamics symbolically and emit C++ headers"};
  std::string model_path, out_dir;
  std::vector<std::string> bake_args;
  bool bake_defaults = false, stats_only = false, quiet = false;
  EmitOptions opt;
  opt.generator_version = WLX_VERSION;
  app.add_option("MODEL", model_path, "the model file (models/*.yaml; format: docs/model-format.md)")->required();
  app.add_option("--out", out_dir, "output root; headers go to OUT/wlx/gen/")->required();
  app.add_option("--bake", bake_args, "bake a parameter in as a constant: NAME=VALUE (repeatable)");
  app.add_flag("--bake-defaults", bake_defaults, "bake every geometry parameter (kinds length, offset, angle) in at its default");
  app.add_option("--namespace", opt.name_space,
                 "C++ namespace of the emitted code (default: wlx::<model>::gen, <model> inline)");
  app.add_flag("--quiet", quiet, "print nothing on success");
  app.add_flag("--stats", stats_only, "print the operation-count table (always printed unless --quiet)");
  app.set_version_flag("--version", WLX_VERSION, "print the version and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Like every bad input: the option and the reason, exit code 2.
    fmt::print(stderr, "wlx-gen: error: {}\n", e.what());
    return 2;
  }

  try {
    const auto t0 = std::chrono::steady_clock::now();
    if (!opt.name_space.empty()) {
      // A qualified C++ identifier, nothing else: the name is pasted into every header.
      static const std::regex qualified("[A-Za-z_][A-Za-z0-9_]*(::[A-Za-z_][A-Za-z0-9_]*)*");
      if (!std::regex_match(opt.name_space, qualified))
        throw ModelFileError(fmt::format("--namespace: '{}' is not a C++ qualified name such as wlx::mine",
                                         opt.name_space.substr(0, 60)));
    }
    const Model model = load_model_file(model_path);
    opt.model_name = model.name;
    if (bake_defaults)
      for (std::size_t k = 0; k < model.parameters.size(); ++k) {
        const ParameterKind kind = model.parameter_kinds[k];
        if (kind == ParameterKind::length || kind == ParameterKind::offset || kind == ParameterKind::angle)
          opt.baked[model.parameters[k].name] = model.parameters[k].default_value;
      }
    for (const auto& arg : bake_args) {
      const auto eq = arg.find('=');
      const std::string shown = arg.substr(0, 60);
      if (eq == std::string::npos) throw ModelFileError(fmt::format("--bake {}: expected NAME=VALUE", shown));
      const std::string name = arg.substr(0, eq);
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
      // Baked values obey the rules of the parameter's kind, as values given at run time do.
      const ParameterKind kind = model.parameter_kinds[index];
      if ((kind == ParameterKind::length || kind == ParameterKind::mass || kind == ParameterKind::inertia) && !(value > 0))
        throw ModelFileError(fmt::format("--bake {}: '{}' is a {}, which must be positive", shown, name, kind_name(kind)));
      if (kind == ParameterKind::gravity && !(value >= 0))
        throw ModelFileError(fmt::format("--bake {}: '{}' is gravity, which must be non-negative", shown, name));
      opt.baked[name] = value;
    }

    std::vector<EmittedFile> files = emit_model_headers(model, opt);
    files.push_back(emit_trig_header(model, opt));
    files.push_back(emit_structure_header(model, opt));
    const auto t1 = std::chrono::steady_clock::now();
    std::vector<FunctionSpec> fns;
    std::vector<FunctionStats> stats;
    for (const Derivation& derivation : derivations(model)) {
      const auto d0 = std::chrono::steady_clock::now();
      fns.push_back(derivation.derive(model));
      const double derive_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - d0).count();
      FunctionStats s;
      files.push_back(emit_function(model, fns.back(), opt, s));
      s.seconds += derive_s;
      stats.push_back(s);
    }
    std::vector<std::string> ik_report;
    files.push_back(emit_ik_header(model, opt, ik_report));
    files.push_back(emit_umbrella(model, fns, stats, opt));
    int changed = 0;
    for (const auto& f : files) changed += write_if_changed(fs::path(out_dir) / f.path, f.text);
    const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!quiet || stats_only) {
      fmt::print("{:<14} {:>8} {:>12} {:>11} {:>9}\n", "function", "temps", "ops before", "ops after", "seconds");
      long b = 0, a = 0;
      for (const auto& s : stats) {
        fmt::print("{:<14} {:>8} {:>12} {:>11} {:>9.3f}\n", s.name, s.intermediates, s.before_cse.total(),
                   s.after_cse.total(), s.seconds);
        b += s.before_cse.total();
        a += s.after_cse.total();
      }
      fmt::print("{:<14} {:>8} {:>12} {:>11} {:>9.3f}\n", "total", "", b, a, total);
      for (const auto& line : ik_report) fmt::print("closed-form IK, {}\n", line);
      fmt::print("model built in {:.3f} s; {} files written to {} ({} changed)\n",
                 std::chrono::duration<double>(t1 - t0).count(), files.size(), out_dir, changed);
    }
  } catch (const ModelFileError& e) {
    fmt::print(stderr, "wlx-gen: error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "wlx-gen: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
