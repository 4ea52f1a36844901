// `wlx --model-file FILE` (cli/shell/model_plugin.hpp): a user's own model file, compiled on first
// use into a cached plugin and loaded with dlopen. The model here is a copy of the excavator's
// file with 30 cm longer thighs that keeps the built-in's name, `excavator`: the plugin's code must
// not be mistaken for wlx's own model of that name, and it must compute what the built-in
// computes when given the same parameters (--params). The plugins are compiled at -O0
// (WLX_PLUGIN_CXXFLAGS, part of the cache key): these tests check the mechanism, and -O0 halves
// their compile time; users get -O2.
#include "../helpers/csv.hpp"
#include "../helpers/run_wlx.hpp"

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

#include <sys/stat.h>
#include <unistd.h>

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
    // A umask that leaves new files group-writable (Ubuntu's default for users): the entries wlx
    // makes must be private all the same, or its own next load would refuse them.
    ::umask(002);
    ::setenv("WLX_CACHE_DIR", cache.c_str(), 1);
    ::setenv("WLX_PLUGIN_CXXFLAGS", "-O0", 1);
    ::setenv("WLX_PLUGIN_EMCCFLAGS", "-O0", 1);  // the viewer's module likewise (its IK is checked, not timed)
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

using wlx_test::read_csv;

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
  // Built by Clang, wlx precompiled the plugin's common headers for these flags (-O0:
  // plugin_prelude-O0.pch), and the compiler accepted them (its check's log is empty); GCC's build
  // has none to offer.
#ifdef __clang__
  REQUIRE(fs::exists(entries().front() / "precompiled-O0.log"));
  CHECK(slurp(entries().front() / "precompiled-O0.log").empty());
#else
  CHECK(!fs::exists(entries().front() / "precompiled-O0.log"));
#endif

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

// Replaces `from` (which must be there) by `to` in `text`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE_MESSAGE(at != std::string::npos, from);
  return text.replace(at, from.size(), to);
}

TEST_CASE("--model-file: editing only the file's numbers compiles nothing (the compiler is /bin/false), and every edit takes effect") {
  const Setup& s = setup();
  REQUIRE(run({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose}).code == 0);  // compiled (the first case)
  const std::size_t entries_before = entries().size();
  // A parameter's value, the nominal state, a limb's Newton start, an IK sweep, the weights, torque
  // limits and friction: each is data (model.json), none is in the plugin's code.
  std::string text = slurp(s.model);
  text = replaced(text, "{name: thighD, value: 2.3,", "{name: thighD, value: 2.25,");
  text = replaced(text, "  z_C: 2.0\n", "  z_C: 1.9\n");
  text = replaced(text, "    joints: [psi_<side>2, psi_<side>3, psi_<side>4]\n",
                  "    joints: [psi_<side>2, psi_<side>3, psi_<side>4]\n    start: {psi_<side>3: -0.3}\n");
  text = replaced(text, "from: 1.80, to: 4.30", "from: 2.00, to: 4.30");
  text = replaced(text, "  weights: [0.01, 100, 1, 0.01, 100, 1, 0.01, 0.01]\n",
                  "  weights: [0.02, 100, 1, 0.01, 100, 1, 0.01, 0.01]\n  torque_limits: [1e6, 1e6, 1e6, 1e6, 1e6, 1e6, 1e6, 1e6]\n");
  text += "\ncontacts:\n  friction: {feet: 0.6, wheels: 0.8}\n";
  const fs::path edited = wlx_test::work_dir() / "edited_numbers.yaml";
  write(edited, text);
  ::setenv("CXX", "/bin/false", 1);  // would fail any compile; it is not part of a plugin's key only if never run
  const auto fk = run({"--model-file", edited.string(), "fk", "--json"}, {.input = "{}"});
  const auto sweep = run({"--model-file", edited.string(), "verify", "ik", "--sweep", "IK-L1", "--out",
                          (wlx_test::work_dir() / "verify-edited").string()});
  ::unsetenv("CXX");
  INFO(fk.err);
  REQUIRE(fk.code == 0);
  CHECK(fk.err.empty());  // nothing compiled, nothing to say
  CHECK(entries().size() == entries_before);
  // The nominal state and the thighs are the edited ones: the built-in model at those numbers agrees.
  const nlohmann::json own = nlohmann::json::parse(fk.out);
  CHECK(own["coordinates"]["z_C"].get<double>() == 1.9);
  const fs::path params = wlx_test::work_dir() / "edited_numbers.json";
  write(params, R"({"thighD": 2.25})");
  const auto builtin = run({"--params", params.string(), "fk", "--json"}, {.input = R"({"z_C": 1.9})"});
  REQUIRE(builtin.code == 0);
  const nlohmann::json reference = nlohmann::json::parse(builtin.out);
  for (const auto& item : reference["coordinates"].items()) {
    CAPTURE(item.key());
    CHECK(own["coordinates"][item.key()].get<double>() == doctest::Approx(item.value().get<double>()).epsilon(1e-12));
  }
  // The sweep starts at its new end.
  INFO(sweep.err);
  REQUIRE(sweep.code == 0);
  const auto [header, rows] = read_csv(wlx_test::work_dir() / "verify-edited" / "IK-L1.csv");
  REQUIRE(!rows.empty());
  CHECK(rows.front().front() == doctest::Approx(2.0).epsilon(1e-12));
  CHECK(rows.size() == 231);  // (4.30 - 2.00) / 0.01 + 1

  // A change of structure is code: the same compiler now has to run, and fails.
  const fs::path restructured = wlx_test::work_dir() / "restructured.yaml";
  write(restructured, replaced(text, "{name: cyd, value: 3.0, unit: m, kind: length,", "{name: cyd, value: 3.0, unit: m, kind: offset,"));
  ::setenv("CXX", "/bin/false", 1);
  const auto code = run({"--model-file", restructured.string(), "fk", "--json"}, {.input = "{}"});
  ::unsetenv("CXX");
  CHECK(code.code == 1);
  CHECK(code.err.find("wlx: compiling model excavator for first use") != std::string::npos);
}

// The SHA-256 of a file by coreutils' sha256sum: an implementation other than wlx's.
std::string sha256sum(const fs::path& file) {
  const auto r = run({file.string()}, {.program = "/usr/bin/sha256sum"});
  REQUIRE(r.code == 0);
  return r.out.substr(0, 64);
}

TEST_CASE("--model-file: a corrupt or replaced cache entry is never loaded but rebuilt, and two processes that find it so compile once") {
  const Setup& s = setup();
  REQUIRE(run({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose}).code == 0);  // built (by the case above)
  REQUIRE(entries().size() == 1);
  const fs::path entry = entries().front(), plugin = entry / "plugin.so";
  const std::string expected = run({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose}).out;
  const std::string good_plugin = slurp(plugin), good_manifest = slurp(entry / "manifest");
  // The manifest and the cache's index hold the plugin's SHA-256, as sha256sum computes it.
  CHECK(good_manifest.find("checksum " + sha256sum(plugin) + "\n") != std::string::npos);
  CHECK(slurp(s.cache / "index").find(entry.filename().string() + " " + sha256sum(plugin) + "\n") != std::string::npos);
  std::string spoilt = good_plugin;  // the same size, other bytes: only a digest can tell
  for (std::size_t k = spoilt.size() / 2; k < spoilt.size() / 2 + 64; ++k) spoilt[k] = static_cast<char>(~spoilt[k]);

  // Corrupt: the bytes no longer match the manifest. Found before dlopen; the rebuild that follows
  // fails here at once (CXX=/bin/false), which shows it was not loaded.
  write(plugin, spoilt);
  ::setenv("CXX", "/bin/false", 1);
  const auto corrupt = run({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose});
  ::unsetenv("CXX");
  CHECK(corrupt.code == 1);
  CHECK(corrupt.err.find("cannot be used (plugin.so is missing or does not match its manifest") != std::string::npos);

  // Replaced with a manifest to match: only the index, which the entry cannot rewrite, can tell.
  // (Made as wlx makes its entries, the user's alone: what others may write is refused before this.)
  fs::create_directories(entry);
  fs::permissions(entry, fs::perms::owner_all);
  write(plugin, spoilt);
  fs::permissions(plugin, fs::perms::owner_read | fs::perms::owner_write);
  const fs::path spoilt_copy = wlx_test::work_dir() / "spoilt.so";
  write(spoilt_copy, spoilt);
  std::string manifest = good_manifest;
  const auto at = manifest.find("checksum ");
  REQUIRE(at != std::string::npos);
  manifest.replace(at + 9, 64, sha256sum(spoilt_copy));
  write(entry / "manifest", manifest);
  fs::permissions(entry / "manifest", fs::perms::owner_read | fs::perms::owner_write);
  // The build folder a killed first use left behind (its pid runs no more): removed when building.
  const fs::path abandoned = s.cache / (entry.filename().string() + ".build-2147483000");
  fs::create_directories(abandoned / "generated");
  // This rebuild finds a precompiled header it must not use: built by Clang, the build's own
  // commands' header (-O0) without the archive that holds its code (-fpch-codegen: a plugin that
  // loaded it would link, then fail to load); otherwise one the compiler refuses (not one at all).
  // Either way it compiles without it.
  const fs::path refused_pch = wlx_test::work_dir() / "refused-pch";
  fs::create_directories(refused_pch);
  const fs::path built_pch = fs::path(WLX_BINARY).parent_path() / "plugin_prelude" / "plugin_prelude-O0.pch";
  const bool without_archive = fs::exists(built_pch) && fs::exists(fs::path(built_pch).replace_extension(".a"));
  if (without_archive) fs::copy_file(built_pch, refused_pch / "plugin_prelude-O0.pch", fs::copy_options::overwrite_existing);
  else write(refused_pch / "plugin_prelude-O0.pch", "not a precompiled header\n");
  ::setenv("WLX_PLUGIN_PRECOMPILED_DIR", refused_pch.c_str(), 1);
  auto a = wlx_test::start({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose});
  auto b = wlx_test::start({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose});
  const auto ra = wlx_test::finish(a), rb = wlx_test::finish(b);
  ::unsetenv("WLX_PLUGIN_PRECOMPILED_DIR");
#ifdef __clang__
  if (without_archive) CHECK(slurp(entry / "precompiled-O0.log").find("plugin_prelude-O0.a is missing: not used") != std::string::npos);
  else CHECK(slurp(entry / "precompiled-O0.log").find("error") != std::string::npos);  // the compiler's refusal
#endif
  INFO(ra.err);
  INFO(rb.err);
  CHECK(ra.code == 0);
  CHECK(rb.code == 0);
  CHECK(ra.out == expected);
  CHECK(rb.out == expected);
  CHECK(count(ra.err + rb.err, "wlx: compiled model excavator") == 1);  // one compiled, the other waited or found it built
  CHECK(count(ra.err + rb.err, "cannot be used (plugin.so is not one this cache built (its SHA-256 is not the one") == 1);
  CHECK(entries().size() == 1);
  CHECK(!fs::exists(abandoned));
  CHECK(slurp(s.cache / "index").find(entry.filename().string() + " " + sha256sum(plugin) + "\n") != std::string::npos);
  // (A plugin of another key in an entry's place: the last case.)
}

#ifdef WLX_PYTHON
TEST_CASE("wlx.load in Python: the plugin `wlx --model-file` built, from the same cache entry; its model is its own beside the built-in of the same name") {
  const Setup& s = setup();
  REQUIRE(run({"--model-file", s.model.string(), "fk", "--json"}, {.input = kPose}).code == 0);  // built (by the cases above)
  const std::vector<fs::path> before = entries();
  REQUIRE(before.size() == 1);
  ::setenv("PYTHONPATH", WLX_PYTHON_DIR, 1);
  // The loaded model keeps the built-in's name (excavator) with thighs of 2.3 m: Python holds both,
  // and each must compute its own (the module is made global for the plugin; the plugin binds to
  // itself). With the built-in given thighD = 2.3, the two agree to rounding.
  const std::string script = R"py(
import sys, numpy as np, wlx
mine, builtin = wlx.load(sys.argv[1]), wlx.model("excavator")
# Two threads loading two sets of numbers of this code at once, five times over: each load gets
# its own description (no shared scratch file) and keeps its own numbers.
import threading
thighs = {}
def load(path, key):
    thighs.setdefault(key, []).append(wlx.load(path).params["thighD"])
for _ in range(5):
    threads = [threading.Thread(target=load, args=(sys.argv[1], "mine")), threading.Thread(target=load, args=(sys.argv[3], "variant"))]
    for t in threads: t.start()
    for t in threads: t.join()
assert thighs == {"mine": [2.3] * 5, "variant": [2.4] * 5}, thighs
assert repr(mine) == f"wlx.load({sys.argv[1]!r})" and mine.name == "excavator" and mine.params["thighD"] == 2.3, mine.params
assert builtin.params["thighD"] == 2.0
pose = {"z_C": 1.8, "x_Fl": 2.4}
s_mine, s_default = mine.ik(pose)["s"], builtin.ik(pose)["s"]
s_same = builtin.ik(pose, params={"thighD": 2.3})["s"]
assert np.max(np.abs(s_mine - s_default)) > 1e-3, "the loaded model computed the built-in's geometry"
assert np.max(np.abs(s_mine - s_same)) <= 1e-12, np.max(np.abs(s_mine - s_same))
u, u_dot = [0.0, 0.3, 0.0, 0.0], [0.1, 0.0, 0.0, 0.2]
a = mine.inverse_dynamics(s_mine, u, u_dot)
b = builtin.inverse_dynamics(s_same, u, u_dot, params={"thighD": 2.3})
assert np.max(np.abs(a["tau"] - b["tau"])) <= 1e-9 * np.max(np.abs(b["tau"])), (a["tau"], b["tau"])
run = {"id": "T", "initial": pose, "rates": {"x_C": 0.2}, "dependent": ["y_C", "yaw"], "duration": 0.2, "dt": 0.01}
r_mine = mine.simulate(run)
r_same = builtin.simulate({**run, "params": {"thighD": 2.3}})
assert r_mine["complete"] and len(r_mine["t"]) == 21, r_mine["stopped"]
assert np.max(np.abs(r_mine["psi_l2"] - r_same["psi_l2"])) <= 1e-12
# A sweep over the model file on a local Dask cluster: its worker process loads the model from the
# same cache entry (the env's WLX_CACHE_DIR; no second build, checked below) and computes its geometry.
from distributed import Client, LocalCluster
# Weighting 1 pulls a wheel at these geometries (a contact lost stops a run by default): the
# sweep's mechanics are checked here, so the run goes on as the thesis' bilateral contacts do.
dynamics = {**run, "weighting": 1, "on_contact_loss": "continue"}
with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
    table = wlx.sweep(mine, {"list": [{"legD": 1.4}, {"legD": 1.6}]}, [dynamics], ["peak_tau"], client=client, progress=False)
assert table["complete"] == [True, True], table["stopped"]
peak = lambda r: max(np.abs(r[c]).max() for c in r if c.startswith("tau_"))
assert table["peak_tau"] == [peak(mine.simulate(dynamics, params={"legD": v})) for v in (1.4, 1.6)]
theirs = [peak(builtin.simulate(dynamics, params={"legD": v})) for v in (1.4, 1.6)]
assert all(abs(a - b) > 1e-6 * abs(b) for a, b in zip(table["peak_tau"], theirs)), (table["peak_tau"], theirs)
for bad, message in ((sys.argv[2], "bad.yaml:1:1: missing field 'parameters'"), (sys.argv[2] + ".missing", "load: ")):
    try:
        wlx.load(bad)
    except wlx.Error as e:
        assert message in str(e), str(e)
    else:
        raise AssertionError("loaded " + bad)
print("ok")
)py";
  const fs::path bad = wlx_test::work_dir() / "bad.yaml";
  write(bad, "model: broken\n");
  const fs::path variant = wlx_test::work_dir() / "variant_thighs.yaml";
  write(variant, replaced(slurp(s.model), "{name: thighD, value: 2.3,", "{name: thighD, value: 2.4,"));
  const auto r = run({"-c", script, s.model.string(), bad.string(), variant.string()}, {.program = WLX_PYTHON});
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(r.out == "ok\n");
  CHECK(r.err.find("compiling") == std::string::npos);  // the CLI's entry, not a second build
  CHECK(entries() == before);
}
#endif

TEST_CASE("--model-file: a cache that others may write, or another user's, is refused before anything in it is loaded (exit 2)") {
  const Setup& s = setup();
  const fs::path open_cache = wlx_test::work_dir() / "open-cache";
  fs::create_directories(open_cache);
  fs::permissions(open_cache, fs::perms::all);  // 0777: anyone could plant a plugin.so
  ::setenv("WLX_CACHE_DIR", open_cache.c_str(), 1);
  auto r = run({"--model-file", s.model.string(), "fk"}, {.input = "{}"});
  CHECK(r.code == 2);
  CHECK(r.err.find("the cache's folder " + open_cache.string() + " may be written by others (mode 0777)") != std::string::npos);
  CHECK(r.err.find("chmod go-w") != std::string::npos);
  // A private cache whose entry was made writable by others: that entry is refused by name.
  ::setenv("WLX_CACHE_DIR", s.cache.c_str(), 1);
  REQUIRE(run({"--model-file", s.model.string(), "fk"}, {.input = "{}"}).code == 0);
  REQUIRE(!entries().empty());
  const fs::path plugin = entries().front() / "plugin.so";
  const fs::perms before = fs::status(plugin).permissions();
  fs::permissions(plugin, fs::perms::others_write, fs::perm_options::add);
  r = run({"--model-file", s.model.string(), "fk"}, {.input = "{}"});
  fs::permissions(plugin, before);
  CHECK(r.code == 2);
  CHECK(r.err.find("the cache's plugin " + plugin.string() + " may be written by others") != std::string::npos);
  // A damaged index (here a folder) is an error naming it, and costs no good plugin.
  fs::rename(s.cache / "index", s.cache / "index.kept");
  fs::create_directory(s.cache / "index");
  fs::permissions(s.cache / "index", fs::perms::owner_all);  // the user's own: only its kind is wrong
  r = run({"--model-file", s.model.string(), "fk"}, {.input = "{}"});
  CHECK(r.code == 2);
  CHECK(r.err.find("the cache's index " + (s.cache / "index").string() + " is not a regular file") != std::string::npos);
  CHECK(fs::exists(plugin));
  fs::remove(s.cache / "index");
  fs::rename(s.cache / "index.kept", s.cache / "index");
  // An entry that is a link, even one to nothing: refused by name, never compiled over.
  const fs::path entry = plugin.parent_path(), kept = entry.string() + ".kept";
  fs::rename(entry, kept);
  fs::create_symlink("/nonexistent", entry);
  r = run({"--model-file", s.model.string(), "fk"}, {.input = "{}"});
  CHECK(r.code == 2);
  CHECK(r.err.find("the cache's entry " + entry.string() + " is a symbolic link") != std::string::npos);
  fs::remove(entry);
  fs::rename(kept, entry);
  REQUIRE(run({"--model-file", s.model.string(), "fk"}, {.input = "{}"}).code == 0);
  if (::geteuid() == 0) {  // root can give a folder away: another user's cache
    fs::permissions(open_cache, fs::perms::owner_all);
    REQUIRE(::chown(open_cache.c_str(), 65534, 65534) == 0);
    ::setenv("WLX_CACHE_DIR", open_cache.c_str(), 1);
    r = run({"--model-file", s.model.string(), "fk"}, {.input = "{}"});
    CHECK(r.code == 2);
    CHECK(r.err.find("belongs to another user (uid 65534)") != std::string::npos);
  }
  ::setenv("WLX_CACHE_DIR", s.cache.c_str(), 1);
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
  // Flags of their own: another key (the compiler is not part of it: a cached plugin is loaded
  // whichever compiler built it).
  ::setenv("WLX_PLUGIN_CXXFLAGS", "-O0 -DWLX_FAILING_COMPILER_TEST", 1);
  ::setenv("CXX", compiler.c_str(), 1);
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
  ::setenv("WLX_PLUGIN_CXXFLAGS", "-O0", 1);
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

// The processes (other than this one) whose command line holds `text`.
std::vector<int> processes_with(const std::string& text) {
  std::vector<int> out;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos || std::stoi(name) == ::getpid()) continue;
    std::string cmdline = slurp(e.path() / "cmdline");
    for (char& c : cmdline)
      if (c == '\0') c = ' ';
    if (cmdline.find(text) != std::string::npos) out.push_back(std::stoi(name));
  }
  return out;
}

TEST_CASE("--model-file: kill -9 while compiling leaves no compiler running; the next first use removes its build folder") {
  const Setup& s = setup();
  ::setenv("WLX_PLUGIN_CXXFLAGS", "-O0 -DWLX_KILL_TEST", 1);  // a key with no entry yet: this run compiles
  const auto started = std::chrono::steady_clock::now();
  auto p = wlx_test::start({"--model-file", s.model.string(), "fk"}, {.input = "{}"});
  const std::string build_folder = ".build-" + std::to_string(p.pid);
  while (processes_with(build_folder).empty() && std::chrono::steady_clock::now() - started < std::chrono::seconds(30))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  REQUIRE_MESSAGE(!processes_with(build_folder).empty(), "no compiler of wlx's build folder ever ran");
  ::kill(p.pid, SIGKILL);
  const auto r = wlx_test::finish(p);
  CHECK(r.signal == SIGKILL);
  // The compilers had their parent-death signal: gone within moments (2 s: a loaded machine's slack).
  const auto killed = std::chrono::steady_clock::now();
  while (!processes_with(build_folder).empty() && std::chrono::steady_clock::now() - killed < std::chrono::seconds(2))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  CHECK(processes_with(build_folder).empty());
  bool left = false;
  for (const auto& e : fs::directory_iterator(s.cache)) left = left || e.path().filename().string().find(build_folder) != std::string::npos;
  CHECK(left);  // nothing could remove it: wlx was killed
  // The next first use of that key removes it before building (here with a compiler that fails at once).
  ::setenv("CXX", "/bin/false", 1);
  CHECK(run({"--model-file", s.model.string(), "fk"}, {.input = "{}"}).code == 1);
  ::unsetenv("CXX");
  ::setenv("WLX_PLUGIN_CXXFLAGS", "-O0", 1);
  for (const auto& e : fs::directory_iterator(s.cache)) CHECK(e.path().filename().string().find(build_folder) == std::string::npos);
}

TEST_CASE("--model-file with --scenarios: a user's runs in every command; a run written for another model is refused") {
  const Setup& s = setup();
  const fs::path runs = wlx_test::work_dir() / "my_runs";
  fs::create_directories(runs);
  // Two runs of the user's: one says whose it is, one does not (both run).
  write(runs / "drive.json", R"({"model": "excavator", "description": "forward at 0.5 m/s", "initial": {"z_C": 1.8},
    "rates": {"x_C": 0.5}, "dependent": ["y_C", "yaw"], "duration": 0.2, "dt": 0.01})");
  write(runs / "lift.json", R"({"description": "the body up at 0.1 m/s", "rates": {"z_C": 0.1}, "dependent": ["y_C", "yaw"],
    "duration": 0.1, "dt": 0.01})");
  const auto list = run({"--model-file", s.model.string(), "--scenarios", runs.string(), "simulate", "--list"});
  INFO(list.err);
  REQUIRE(list.code == 0);
  CHECK(list.out.find("drive") != std::string::npos);
  CHECK(list.out.find("forward at 0.5 m/s") != std::string::npos);
  CHECK(list.out.find("lift") != std::string::npos);
  CHECK(list.out.find("NH-1") == std::string::npos);  // the folder replaces the model's own runs
  const fs::path out = wlx_test::work_dir() / "sim-drive";
  const auto sim = run({"--model-file", s.model.string(), "--scenarios", runs.string(), "simulate", "drive", "--out", out.string()});
  INFO(sim.err);
  REQUIRE(sim.code == 0);
  const auto [header, rows] = read_csv(out / "trajectory.csv");
  CHECK(rows.size() == 21);
  // The built-in model with the same folder: the same run (its thighs given by --params).
  const fs::path builtin_out = wlx_test::work_dir() / "sim-drive-builtin";
  REQUIRE(run({"--params", s.params.string(), "--scenarios", runs.string(), "simulate", "drive", "--out", builtin_out.string()}).code == 0);
  const auto [builtin_header, builtin_rows] = read_csv(builtin_out / "trajectory.csv");
  REQUIRE(builtin_rows.size() == rows.size());
  double worst = 0;
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (std::size_t c = 0; c < rows[r].size(); ++c) worst = std::max(worst, std::abs(rows[r][c] - builtin_rows[r][c]));
  CHECK(worst <= 1e-9);

  // The report of the user's runs (no report.yaml: a report of its runs, no claims).
  const fs::path report = wlx_test::work_dir() / "report-runs";
  const auto rep = run({"--model-file", s.model.string(), "--scenarios", runs.string(), "report", "--out", report.string()});
  INFO(rep.out);
  INFO(rep.err);
  CHECK(rep.code == 0);
#ifdef WLX_VIEWER_DIST  // the report's viewer: the model's own module, compiled now (the viewer case takes it from the cache)
  CHECK(rep.err.find("wlx: compiling model excavator's viewer module with emscripten for first use") != std::string::npos);
  CHECK(fs::is_regular_file(report / "viewer" / "wasm" / "wlx_excavator.js"));
  CHECK(fs::is_regular_file(report / "viewer" / "runs" / "drive.js"));
#endif
  const std::string html = slurp(report / "index.html");
  CHECK(html.find("forward at 0.5 m/s") != std::string::npos);
  CHECK(html.find("the body up at 0.1 m/s") != std::string::npos);
  CHECK(html.find("ID-1") == std::string::npos);

  // A run written for another model, by its "model", on this one: refused, named.
  const fs::path other = wlx_test::work_dir() / "walker_run.json";
  write(other, R"({"model": "walker", "rates": {"x_C": 0.5}, "duration": 0.1})");
  const auto wrong = run({"--model-file", s.model.string(), "simulate", other.string(), "--out", out.string()});
  CHECK(wrong.code == 2);
  CHECK(wrong.err.find("model: the scenario is for model 'walker', not for 'excavator'") != std::string::npos);
  // Folder errors: not a folder, no scenario in it, a file name that is no id.
  const auto missing = run({"--scenarios", (runs / "nope").string(), "simulate", "--list"});
  CHECK(missing.code == 2);
  CHECK(missing.err.find("--scenarios: ") != std::string::npos);
  CHECK(missing.err.find("is not a folder") != std::string::npos);
  const fs::path empty = wlx_test::work_dir() / "no_runs";
  fs::create_directories(empty);
  const auto none = run({"--scenarios", empty.string(), "simulate", "--list"});
  CHECK(none.code == 2);
  CHECK(none.err.find("holds no scenario file") != std::string::npos);
  const fs::path odd = wlx_test::work_dir() / "odd_runs";
  fs::create_directories(odd);
  write(odd / "a run.json", "{}");
  const auto bad_id = run({"--scenarios", odd.string(), "simulate", "--list"});
  CHECK(bad_id.code == 2);
  CHECK(bad_id.err.find("a scenario's id is its file name") != std::string::npos);
  const fs::path renamed = wlx_test::work_dir() / "renamed_runs";
  fs::create_directories(renamed);
  write(renamed / "forward.json", R"({"id": "backward", "rates": {"x_C": 0.5}, "dependent": ["y_C", "yaw"], "duration": 0.1})");
  const auto mismatch = run({"--scenarios", renamed.string(), "simulate", "forward", "--out", out.string()});
  CHECK(mismatch.code == 2);
  CHECK(mismatch.err.find("forward: id: is \"backward\", but the run's file is named forward.json") != std::string::npos);
}

#ifdef WLX_VIEWER_DIST
TEST_CASE("--model-file viewer: the model file's own WebAssembly module (emscripten, on first use, cached), not the built-in's of the same name") {
  const Setup& s = setup();
  const fs::path runs = wlx_test::work_dir() / "viewer_runs";
  fs::create_directories(runs);
  write(runs / "drive.json", R"({"model": "excavator", "rates": {"x_C": 0.5}, "dependent": ["y_C", "yaw"], "duration": 0.2, "dt": 0.01})");
  const fs::path out = wlx_test::work_dir() / "viewer-own";
  const auto first = run({"--model-file", s.model.string(), "--scenarios", runs.string(), "viewer", "drive", "--out", out.string()});
  INFO(first.err);
  REQUIRE(first.code == 0);
  // The report of the case above compiled the module into the entry: taken from there.
  CHECK(first.err.find("compiling") == std::string::npos);
  REQUIRE(fs::is_regular_file(out / "wasm" / "wlx_excavator.js"));
  CHECK(fs::is_regular_file(out / "runs" / "drive.js"));
  // The built-in modules of other models come along; this model's is its own, not the built-in's.
  CHECK(fs::is_regular_file(out / "wasm" / "wlx_walker.js"));
  CHECK(slurp(out / "wasm" / "wlx_excavator.js") != slurp(fs::path(WLX_VIEWER_DIST) / "wasm" / "wlx_excavator.js"));
  // Run both modules in node: the closed-form IK at the nominal inputs. The file's module gives
  // what `wlx --model-file ... ik` gives (thighs 2.3 m); the built-in's gives other angles.
  const fs::path script = wlx_test::work_dir() / "module_ik.cjs";
  write(script, R"js(
const factory = require(process.argv[2]);
factory().then((m) => {
  const info = JSON.parse(m.UTF8ToString(m._wlx_model_info_json()));
  const n = info.coordinates.length;
  const inputs = m._malloc(8 * info.inputCount), branches = m._malloc(4 * info.limbs.length), s = m._malloc(8 * n);
  info.nominalInputs.forEach((v, k) => m.HEAPF64[inputs / 8 + k] = v);
  for (let k = 0; k < info.limbs.length; ++k) m.HEAP32[branches / 4 + k] = 0;
  if (!m._wlx_solve_ik(inputs, branches, s)) throw new Error(m.UTF8ToString(m._wlx_last_error()));
  const out = {};
  info.coordinates.forEach((c, k) => out[c.name] = m.HEAPF64[s / 8 + k]);
  console.log(JSON.stringify({inputs: Object.fromEntries(info.nominalInputs.map((v, k) => [info.coordinates[k].name, v])), s: out}));
});
)js");
  const auto own = run({script.string(), (out / "wasm" / "wlx_excavator.js").string()}, {.program = WLX_NODE});
  INFO(own.err);
  REQUIRE(own.code == 0);
  const nlohmann::json own_ik = nlohmann::json::parse(own.out);
  const auto cli = run({"--model-file", s.model.string(), "ik"}, {.input = own_ik["inputs"].dump()});
  INFO(cli.err);
  REQUIRE(cli.code == 0);
  const nlohmann::json reference = nlohmann::json::parse(cli.out);  // the dependent joints by name, and more
  int compared = 0;
  for (const auto& item : own_ik["s"].items()) {
    const std::string coordinate = item.key();
    if (!reference.contains(coordinate)) continue;  // an input: given, not solved
    CAPTURE(coordinate);
    CHECK(item.value().get<double>() == doctest::Approx(reference[coordinate].get<double>()).epsilon(1e-9));
    ++compared;
  }
  CHECK(compared >= 14);  // the legs' and the wheel levers' joints, the wheels' positions
  const auto builtin = run({script.string(), (fs::path(WLX_VIEWER_DIST) / "wasm" / "wlx_excavator.js").string()}, {.program = WLX_NODE});
  REQUIRE(builtin.code == 0);
  CHECK(std::abs(nlohmann::json::parse(builtin.out)["s"]["psi_l4"].get<double>() - reference["psi_l4"].get<double>()) > 0.01);

}
#endif

// Issue 43, item 5: a model file without `clearance` (the test model newton_leg: one leg, one
// wheel, no clearance box). Its runs have no clearance to write (the runtime's is +infinity), so
// the trajectory has no clearance column, and every command that writes or reads one copes.
TEST_CASE("--model-file without a clearance box: simulate, report and the viewer's runs have no clearance column") {
  setup();
  const fs::path model = fs::path(WLX_SOURCE_DIR) / "tests" / "models" / "newton_leg.yaml";
  REQUIRE(slurp(model).find("\nclearance:") == std::string::npos);  // the premise
  const fs::path runs = wlx_test::work_dir() / "newton_leg_runs";
  fs::create_directories(runs);
  write(runs / "roll.json", R"({"description": "the base forward at 0.2 m/s, the wheel rolling", "rates": {"x_B": 0.2},
    "dependent": ["y_B"], "duration": 0.2, "dt": 0.01})");

  const fs::path out = wlx_test::work_dir() / "newton_leg_sim";
  const auto sim = run({"--model-file", model.string(), "--scenarios", runs.string(), "simulate", "roll", "--out", out.string()});
  INFO(sim.out);
  INFO(sim.err);
  REQUIRE(sim.code == 0);
  const auto [header, rows] = read_csv(out / "trajectory.csv");
  CHECK(rows.size() == 21);
  CHECK(header.find("cond_J_beta") != std::string::npos);
  CHECK(header.find("clearance") == std::string::npos);
  CHECK(slurp(out / "trajectory.csv").find("inf") == std::string::npos);
  CHECK(sim.out.find("no clearance box") != std::string::npos);
  CHECK(sim.out.find("min clearance") == std::string::npos);

  // The report (--params with the defaults: the report then leaves out the 3D viewer, whose module
  // this model would compile first, 20 s of CI for a run file the CSV's columns also make).
  const fs::path defaults = wlx_test::work_dir() / "newton_leg_clearance_defaults.json";
  write(defaults, "{}");
  const fs::path report = wlx_test::work_dir() / "newton_leg_report";
  const auto rep = run({"--model-file", model.string(), "--params", defaults.string(), "--scenarios", runs.string(), "report",
                        "--out", report.string()});
  INFO(rep.out);
  INFO(rep.err);
  CHECK(rep.code == 0);
  const std::string html = slurp(report / "index.html");
  CHECK(html.find("the base forward at 0.2 m/s") != std::string::npos);
  CHECK(html.find("min clearance") == std::string::npos);
  CHECK(html.find("<img src=\"fig/pose-roll.png\"") != std::string::npos);
  const std::string data = slurp(report / "data" / "roll.csv");
  CHECK(!data.empty());
  CHECK(data.find("clearance") == std::string::npos);
  CHECK(data.find("inf") == std::string::npos);

  // A claim measured from the clearance box is a bad input for this model: named, exit 2, no report.
  write(runs / "report.yaml", "sources: {spec: a test's}\n"
                              "claims:\n  - {id: touch, kind: check, claim: the body touches down, source: {spec: a test}, claimed: {spec: 1 s}, "
                              "measure: {quantity: ground_contact_time, run: roll}, criterion: {at_least: 0}, why: a test}\n");
  const fs::path bad = wlx_test::work_dir() / "newton_leg_bad_report";
  const auto refused = run({"--model-file", model.string(), "--scenarios", runs.string(), "report", "--out", bad.string()});
  CHECK(refused.code == 2);
  CHECK(refused.err.find("report.yaml:3: claims.touch.measure.quantity: ground_contact_time needs a clearance box, and model "
                         "newton_leg has none") != std::string::npos);
  CHECK(!fs::exists(bad / "index.html"));
}

// Issue 43: the labels say what ran. tests/models/newton_leg.yaml is a model whose limbs no
// closed-form pattern solves (its generated ik.hpp, read from the plugin's cache entry, is checked
// first): every command must say Newton's method solved them, and nothing may claim, check or
// compare a closed form. (tests/cli/test_cli.cpp checks the excavator, whose limbs all have one.)
TEST_CASE(
    "--model-file: a model whose limbs have no closed form: ik, fk, verify ik and report say Newton's method, never "
    "the closed form") {
  setup();
  const fs::path model = fs::path(WLX_SOURCE_DIR) / "tests" / "models" / "newton_leg.yaml";
  const auto ik = run({"--model-file", model.string(), "ik"}, {.input = "{}"});
  INFO(ik.err);
  REQUIRE(ik.code == 0);
  // What wlx-gen emitted for the model: no closed form for either limb (kClosedForm's solve nullptr).
  std::string emitted;
  for (const auto& e : fs::directory_iterator(setup().cache))
    if (e.is_directory() && e.path().filename().string().rfind("newton_leg-", 0) == 0 &&
        e.path().filename().string().find('.') == std::string::npos)
      emitted = slurp(e.path() / "generated" / "wlx" / "gen" / "ik.hpp");
  REQUIRE(!emitted.empty());
  REQUIRE(count(emitted, "{nullptr, 0, \"none\", {}, {}},  // leg:") == 1);
  REQUIRE(count(emitted, "{nullptr, 0, \"none\", {}, {}},  // wheel_arm:") == 1);

  // wlx ik, the closed form asked for (the default) and Newton's method asked for: Newton's both times.
  for (const std::string request : {"{}", R"({"method": "closed-form", "foot_x": 0.6})", R"({"method": "newton"})"}) {
    CAPTURE(request);
    const auto r = run({"--model-file", model.string(), "ik"}, {.input = request});
    REQUIRE(r.code == 0);
    const nlohmann::json j = nlohmann::json::parse(r.out);
    CHECK(j["method"] == "newton");
    CHECK(j["limb_methods"] == nlohmann::json({{"leg", "newton"}, {"wheel_arm", "newton"}}));
    CHECK(j["iterations"].size() == 2);
    CHECK(j["closure_residual"].get<double>() <= 1e-12);
  }
  // From the nominal dependent joints (the model's start values), Newton's method took steps.
  CHECK(nlohmann::json::parse(ik.out)["iterations_total"].get<int>() > 0);
  // A start for the limbs Newton's method solves is taken without "method": "newton" (the knee
  // bent the other way: the leg's other solution). In a batch, each line's Newton limbs continue
  // from the previous answer: the lines after it stay on that solution, where each on its own goes
  // back to the model's start values' one.
  const double knee_default = nlohmann::json::parse(ik.out)["knee"].get<double>();
  const auto other = run({"--model-file", model.string(), "ik"}, {.input = R"({"start": {"knee": 0.6}})"});
  INFO(other.err);
  REQUIRE(other.code == 0);
  const double knee_other = nlohmann::json::parse(other.out)["knee"].get<double>();
  REQUIRE(knee_default * knee_other < 0);
  const auto batch = run({"--model-file", model.string(), "ik", "--batch"},
                         {.input = "{\"start\": {\"knee\": 0.6}}\n{\"foot_x\": 0.56}\n{\"foot_x\": 0.57}\n"});
  REQUIRE(batch.code == 0);
  std::istringstream lines(batch.out);
  int answers = 0;
  for (std::string line; std::getline(lines, line); ++answers) {
    CAPTURE(line);
    const nlohmann::json a = nlohmann::json::parse(line);
    CHECK(a["knee"].get<double>() * knee_other > 0);
    CHECK(a["closure_residual"].get<double>() <= 1e-12);
  }
  CHECK(answers == 3);
  const auto alone = run({"--model-file", model.string(), "ik"}, {.input = R"({"foot_x": 0.56})"});
  REQUIRE(alone.code == 0);
  CHECK(nlohmann::json::parse(alone.out)["knee"].get<double>() * knee_default > 0);

  // wlx fk: the table's heading, the JSON's limb_methods, the message for a partial pose.
  const auto fk = run({"--model-file", model.string(), "fk"}, {.input = "{}"});
  REQUIRE(fk.code == 0);
  CHECK(fk.out.rfind(
            "newton_leg pose, dependent joints by Newton's method (wlx-gen derived no closed form for any limb):\n",
            0) == 0);
  CHECK(fk.out.find("closed-form IK") == std::string::npos);
  const auto fk_json = run({"--model-file", model.string(), "fk", "--json"}, {.input = "{}"});
  REQUIRE(fk_json.code == 0);
  CHECK(nlohmann::json::parse(fk_json.out)["limb_methods"] ==
        nlohmann::json({{"leg", "newton"}, {"wheel_arm", "newton"}}));
  const auto partial = run({"--model-file", model.string(), "fk"}, {.input = R"({"knee": -1.2})"});
  CHECK(partial.code == 2);
  CHECK(partial.err ==
        "wlx: error: stdin: give all 4 dependent joints or none, 1 given; with none, fk solves them by Newton's method "
        "(wlx-gen "
        "derived no closed form for any limb)\n");

  // wlx verify ik: no closed-form column, no comparison; the words instead; CSVs without them.
  const fs::path out = wlx_test::work_dir() / "verify-newton-leg";
  const auto verify = run({"--model-file", model.string(), "verify", "ik", "--out", out.string()});
  INFO(verify.out);
  CHECK(verify.code == 0);
  CHECK(verify.out.find("CF") == std::string::npos);
  CHECK(verify.out.find("check N (m)") != std::string::npos);
  CHECK(verify.out.find("No closed form for leg (N-foot-x), wheel arm (N-ground): wlx-gen derived none.\n") !=
        std::string::npos);
  CHECK(verify.out.find("all sweeps pass") != std::string::npos);
  for (const char* sweep : {"N-foot-x", "N-ground"}) {
    const auto csv = read_csv(out / (std::string(sweep) + ".csv"));
    const std::string& header = csv.first;
    CAPTURE(header);
    CHECK(header.find("closed_form") == std::string::npos);
    CHECK(header.find(",check_error_newton,level_error_newton,newton_iterations,") != std::string::npos);
    CHECK(csv.second.size() > 10);
  }
  // Only one of the two limbs swept: the other is not named.
  const auto one = run({"--model-file", model.string(), "verify", "ik", "--sweep", "N-ground", "--out", out.string()});
  CHECK(one.code == 0);
  CHECK(one.out.find("No closed form for wheel arm (N-ground): wlx-gen derived none.\n") != std::string::npos);

  // wlx report: the sweeps' table and figures say so too (--params with the defaults: the report
  // then leaves out the 3D viewer, whose module this model would compile first).
  const fs::path defaults = wlx_test::work_dir() / "newton_leg_defaults.json";
  write(defaults, "{}");
  const fs::path report = wlx_test::work_dir() / "report-newton-leg";
  const auto rep = run(
      {"--model-file", model.string(), "--params", defaults.string(), "report", "--quick", "--out", report.string()});
  INFO(rep.err);
  REQUIRE(rep.code == 0);
  const std::string page = slurp(report / "index.html");
  CHECK(count(page, "<td>no closed form</td>") == 4);  // two sweeps: the check and the difference each
  CHECK(page.find("N-foot-x: foot_x swept; Newton&#39;s method (the limb has no closed form)") != std::string::npos);
  CHECK(page.find("closed form and Newton") == std::string::npos);
}
