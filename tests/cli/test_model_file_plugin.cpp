// `wlx --model-file FILE` (cli/shell/model_plugin.hpp): a user's own model file, compiled on first
// use into a cached plugin and loaded with dlopen. The model here is a copy of the excavator's
// file with 30 cm longer thighs that keeps the built-in's name, `excavator`: the plugin's code must
// not be mistaken for wlx's own model of that name, and it must compute what the built-in
// computes when given the same parameters (--params). The plugins are compiled at -O0
// (WLX_PLUGIN_CXXFLAGS, part of the cache key): these tests check the mechanism, and -O0 halves
// their compile time; users get -O2.
#include "../support/run_wlx.hpp"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <thread>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using wlx_test::run;
using wlx_test::slurp;
using wlx_test::write;

// The cache and the model file, set up once for every test of this file.
struct Setup {
  fs::path cache = wlx_test::work_dir() / "cache";
  fs::path model = wlx_test::work_dir() / "longer_thighs.yaml";
  fs::path params = wlx_test::work_dir() / "longer_thighs.json";
  Setup() {
    ::setenv("WLX_CACHE_DIR", cache.c_str(), 1);
    ::setenv("WLX_PLUGIN_CXXFLAGS", "-O0", 1);
    ::unsetenv("CXX");
    std::string text = slurp(fs::path(WLX_SOURCE_DIR) / "models" / "excavator.yaml");
    const std::string from = "{name: thighD, value: 2.0,";
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    text.replace(at, from.size(), "{name: thighD, value: 2.3,");
    write(model, text);
    write(params, R"({"thighD": 2.3})");
  }
};
const Setup& setup() {
  static const Setup s;
  return s;
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::vector<fs::path> entries() {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(setup().cache))
    if (e.is_directory() && e.path().filename().string().rfind("excavator-", 0) == 0 &&
        e.path().filename().string().find('.') == std::string::npos)
      out.push_back(e.path());
  return out;
}

// A CSV of numbers: its header line and its rows.
std::pair<std::string, std::vector<std::vector<double>>> read_csv(const fs::path& path) {
  std::istringstream in(slurp(path));
  std::string header, line;
  std::getline(in, header);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return {header, rows};
}

const std::string kPose = R"({"z_C": 1.8, "x_Fl": 2.4})";

}  // namespace

TEST_CASE("--model-file: compiled on first use, then loaded from the cache; it computes what the built-in model computes with the same parameters") {
  const Setup& s = setup();
  auto first = run({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose});
  INFO(first.err);
  REQUIRE(first.code == 0);
  // Progress on stderr only: stdout is the command's JSON.
  CHECK(first.err.find("wlx: compiling model excavator for first use") != std::string::npos);
  CHECK(std::regex_search(first.err, std::regex(R"(wlx: compiled model excavator in [0-9.]+ s)")));
  const nlohmann::json own = nlohmann::json::parse(first.out);
  REQUIRE(entries().size() == 1);
  CHECK(fs::file_size(entries().front() / "plugin.so") > 100000);

  // The built-in excavator with the same thighs: the same numbers (the same generated code from
  // the same file, with one parameter moved from the file to --params).
  const auto builtin = run({"--params", s.params.string(), "fk", "--json"}, {.input = kPose});
  REQUIRE(builtin.code == 0);
  const nlohmann::json reference = nlohmann::json::parse(builtin.out);
  REQUIRE(own["coordinates"].size() == reference["coordinates"].size());
  for (const auto& item : reference["coordinates"].items()) {
    const std::string coordinate = item.key();
    CAPTURE(coordinate);
    CHECK(own["coordinates"][coordinate].get<double>() == doctest::Approx(item.value().get<double>()).epsilon(1e-12));
  }
  // ... and not the built-in's default thighs: the plugin's code is its own, though its model
  // has the built-in's name.
  const auto defaults = run({"fk", "--json"}, {.input = kPose});
  REQUIRE(defaults.code == 0);
  CHECK(std::abs(nlohmann::json::parse(defaults.out)["coordinates"]["psi_l4"].get<double>() -
                 own["coordinates"]["psi_l4"].get<double>()) > 0.01);

  // Second use: loaded, not compiled; nothing on stderr; the same answer.
  const auto second = run({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose});
  CHECK(second.code == 0);
  CHECK(second.err.empty());
  CHECK(second.out == first.out);

  // Every command takes it: simulate (a scenario file: a model file embeds none), verify ik, report.
  const fs::path scenario = wlx_test::work_dir() / "nh1.json";
  write(scenario, slurp(fs::path(WLX_SOURCE_DIR) / "scenarios" / "excavator" / "NH-1.json"));
  const fs::path own_out = wlx_test::work_dir() / "sim-own", builtin_out = wlx_test::work_dir() / "sim-builtin";
  const auto sim = run({"--model-file", s.model.string(), "simulate", scenario.string(), "--out", own_out.string()});
  INFO(sim.err);
  REQUIRE(sim.code == 0);
  REQUIRE(run({"--params", s.params.string(), "simulate", scenario.string(), "--out", builtin_out.string()}).code == 0);
  // The same to rounding: the plugin at -O0 and wlx at -O2 (with FMA where the machine has it)
  // round differently, by ~1e-16 per operation; over NH-1's 2000 steps that stays far below 1e-9.
  const auto [own_header, own_rows] = read_csv(own_out / "trajectory.csv");
  const auto [builtin_header, builtin_rows] = read_csv(builtin_out / "trajectory.csv");
  CHECK(own_header == builtin_header);
  REQUIRE(own_rows.size() == builtin_rows.size());
  CHECK(own_rows.size() > 1000);
  double worst = 0;
  for (std::size_t r = 0; r < own_rows.size(); ++r)
    for (std::size_t c = 0; c < own_rows[r].size(); ++c) worst = std::max(worst, std::abs(own_rows[r][c] - builtin_rows[r][c]));
  CHECK(worst <= 1e-9);
  const auto verify = run({"--model-file", s.model.string(), "verify", "ik", "--sweep", "IK-L3", "--out",
                           (wlx_test::work_dir() / "verify").string()});
  CHECK(verify.code == 0);
  CHECK(fs::exists(wlx_test::work_dir() / "verify" / "IK-L3.csv"));
  const fs::path report = wlx_test::work_dir() / "report";
  const auto rep = run({"--model-file", s.model.string(), "report", "--quick", "--out", report.string()});
  INFO(rep.out);
  CHECK(rep.code == 0);
  CHECK(slurp(report / "index.html").find("has no report file with claims") != std::string::npos);
}

TEST_CASE("--model-file: a corrupt cache entry is never loaded but rebuilt, and two processes that find it so compile once") {
  const Setup& s = setup();
  REQUIRE(run({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose}).code == 0);  // built (by the case above)
  REQUIRE(entries().size() == 1);
  const fs::path plugin = entries().front() / "plugin.so";
  const std::string expected = run({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose}).out;
  {  // the same size, other bytes: only the checksum can tell
    std::string bytes = slurp(plugin);
    for (std::size_t k = bytes.size() / 2; k < bytes.size() / 2 + 64; ++k) bytes[k] = static_cast<char>(~bytes[k]);
    write(plugin, bytes);
  }
  auto a = wlx_test::start({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose});
  auto b = wlx_test::start({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose});
  const auto ra = wlx_test::finish(a), rb = wlx_test::finish(b);
  INFO(ra.err);
  INFO(rb.err);
  CHECK(ra.code == 0);
  CHECK(rb.code == 0);
  CHECK(ra.out == expected);
  CHECK(rb.out == expected);
  CHECK(count(ra.err + rb.err, "wlx: compiled model excavator") == 1);  // one compiled, the other waited or found it built
  CHECK(count(ra.err + rb.err, "cannot be used (plugin.so is missing or does not match its manifest") == 1);
  CHECK(entries().size() == 1);
  // (A plugin of another key in an entry's place: the last case.)
}

TEST_CASE("--model-file: a mistake in the model file is reported as wlx-gen reports it, before any compiling (exit 2)") {
  const Setup& s = setup();
  const fs::path bad = wlx_test::work_dir() / "bad.yaml";
  write(bad, "model: bad\nframes: 3\n");
  auto r = run({"--model-file", bad.string(), "fk"}, {.input = "{}"});
  CHECK(r.code == 2);
  CHECK(r.err == "wlx: error: bad.yaml:1:1: missing field 'parameters'\n");
  r = run({"--model-file", (wlx_test::work_dir() / "missing.yaml").string(), "fk"}, {.input = "{}"});
  CHECK(r.code == 2);
  CHECK(r.err.find("wlx: error: --model-file: ") == 0);
  CHECK(r.err.find("No such file") != std::string::npos);
  r = run({"--model", "walker", "--model-file", s.model.string(), "fk"}, {.input = "{}"});
  CHECK(r.code == 2);
  CHECK(r.err.find("give --model (a built-in model) or --model-file (your own), not both") != std::string::npos);
}

TEST_CASE("--model-file: a compiler that fails: its first error and where the log is, exit 1, nothing under a final name") {
  const Setup& s = setup();
  const fs::path compiler = wlx_test::work_dir() / "failing-c++";
  write(compiler, "#!/bin/sh\necho 'some.cpp:12:3: warning: unused'\necho 'some.cpp:14:1: error: this compiler fails'\nexit 1\n");
  fs::permissions(compiler, fs::perms::owner_all);
  const std::size_t before = entries().size();
  ::setenv("CXX", compiler.c_str(), 1);  // another compiler: another key
  const auto r = run({"--model-file", s.model.string(), "fk"}, {.input = "{}"});
  ::unsetenv("CXX");
  CHECK(r.code == 1);
  CHECK(r.err.find("some.cpp:14:1: error: this compiler fails") != std::string::npos);
  const std::smatch log = [&] {
    std::smatch m;
    std::regex_search(r.err, m, std::regex("the whole log: (\\S+)"));
    return m;
  }();
  REQUIRE(log.size() == 2);
  CHECK(slurp(log[1].str()).find("this compiler fails") != std::string::npos);
  CHECK(entries().size() == before);  // no entry of the failing compiler's key
  for (const auto& e : fs::directory_iterator(s.cache)) CHECK(e.path().filename().string().find(".build-") == std::string::npos);

  // A plugin of another key in this key's place (a working plugin, copied there): refused, not
  // loaded, and built again (here with the failing compiler, so it fails again, quickly).
  const fs::path stem = fs::path(log[1].str()).parent_path();  // <cache>/<model>-<key>.failed
  const fs::path place = stem.parent_path() / stem.stem();
  REQUIRE(!entries().empty());
  fs::copy(entries().front(), place, fs::copy_options::recursive);
  ::setenv("CXX", compiler.c_str(), 1);
  const auto again = run({"--model-file", s.model.string(), "fk"}, {.input = "{}"});
  ::unsetenv("CXX");
  CHECK(again.code == 1);
  CHECK(again.err.find("cannot be used (its manifest is missing or names another key)") != std::string::npos);
  CHECK(!fs::exists(place));
}

TEST_CASE("--model-file: SIGINT, SIGTERM or SIGHUP while compiling: stopped at once, the compilers too, exit 130 / 143 / 129, nothing left behind") {
  const Setup& s = setup();
  for (const auto& pair : {std::pair{SIGINT, 130}, std::pair{SIGTERM, 143}, std::pair{SIGHUP, 129}}) {
    const int signal = pair.first, code = pair.second;
    CAPTURE(signal);
    // Flags of their own: a key with no entry yet, so this run compiles.
    ::setenv("WLX_PLUGIN_CXXFLAGS", ("-O0 -DWLX_SIGNAL_TEST=" + std::to_string(signal)).c_str(), 1);
    const auto started = std::chrono::steady_clock::now();
    auto p = wlx_test::start({"--model-file", s.model.string(), "fk"}, {.input = "{}"});
    // Until it says it compiles (wlx-gen is done and the compilers run), at most 20 s.
    while (slurp(p.err).find("compiling model") == std::string::npos &&
           std::chrono::steady_clock::now() - started < std::chrono::seconds(20))
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the compilers well under way
    const auto sent = std::chrono::steady_clock::now();
    ::kill(p.pid, signal);
    const auto r = wlx_test::finish(p);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
    ::setenv("WLX_PLUGIN_CXXFLAGS", "-O0", 1);
    INFO(r.err);
    CHECK(r.code == code);
    CHECK(seconds < 2.0);  // the compiles take 20 s: stopped, not waited for (2 s: a loaded machine's slack)
    for (const auto& e : fs::directory_iterator(s.cache)) {
      CAPTURE(e.path());
      CHECK(e.path().filename().string().find(".build-") == std::string::npos);
    }
  }
  CHECK(entries().size() == 1);  // only the entry of the other cases
}
