// Issue 14: bad inputs and faults, run as a user would (wlx started with posix_spawn and an
// argument vector, never through a shell). Each case asserts the exit code, the field named in
// the message, a bounded message, and that no output file is left incomplete without saying so.
#include "../helpers/run_wlx.hpp"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <spawn.h>
#include <sstream>
#include <string>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

extern char** environ;

// Io is filled with designated initializers naming only what a test sets; the rest keep their
// defaults on purpose.
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

using namespace wlx_test;

namespace {

// Problems with the files under `dir`: a temporary left behind, or a CSV that is cut (no final
// newline, or a row with another number of columns than its header). Empty when all is well.
std::string incomplete_files(const fs::path& dir) {
  if (!fs::exists(dir)) return {};
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > 4 && name.substr(name.size() - 4) == ".tmp") return "temporary left: " + entry.path().string();
    if (entry.is_regular_file() && entry.path().extension() == ".csv") {
      const std::string text = slurp(entry.path());
      if (text.empty() || text.back() != '\n') return "cut CSV: " + entry.path().string();
      std::istringstream lines(text);
      std::string line;
      std::getline(lines, line);
      const auto columns = std::count(line.begin(), line.end(), ',');
      while (std::getline(lines, line))
        if (std::count(line.begin(), line.end(), ',') != columns) return "ragged CSV: " + entry.path().string();
    }
  }
  return {};
}

std::string repeat(const std::string& s, std::size_t n) {
  std::string out;
  out.reserve(s.size() * n);
  for (std::size_t k = 0; k < n; ++k) out += s;
  return out;
}

// `depth` nested arrays around 1.
std::string nested(std::size_t depth) { return repeat("[", depth) + "1" + repeat("]", depth); }

// One bad input or fault: how wlx is called, what it must answer.
struct Case {
  std::string what;               // the class and the case, for the report on failure
  std::vector<std::string> args;  // "{dir}": the case's output folder, "{file}": the scenario file, "{existing}": a file
  std::string input;              // stdin
  std::string file;               // the scenario file's content
  int code;                       // expected exit code
  std::string field;              // the message names it: "wlx: error: <field>: " (or "line N: " in batch mode)
  std::string reason;             // and says this (a word or phrase of the reason)
};

void check_case(const Case& c, int index) {
  const fs::path dir = work_dir() / ("case-" + std::to_string(index));
  fs::create_directories(dir);
  const fs::path file = dir / "scenario.json", existing = dir / "existing-file";
  write(existing, "not a folder");
  if (!c.file.empty()) write(file, c.file);
  std::vector<std::string> args;
  for (std::string a : c.args) {
    for (const auto& [key, value] : std::map<std::string, std::string>{
             {"{dir}", (dir / "out").string()}, {"{file}", file.string()}, {"{existing}", existing.string()}})
      if (const auto at = a.find(key); at != std::string::npos) a.replace(at, key.size(), value);
    args.push_back(a);
  }
  const Result r = run(args, {.input = c.input});
  CAPTURE(c.what);
  CAPTURE(r.err.substr(0, 2000));
  CHECK(r.signal == 0);
  CHECK(r.code == c.code);
  if (!c.field.empty()) CHECK(r.err.find(c.field) != std::string::npos);
  if (!c.reason.empty()) CHECK(r.err.find(c.reason) != std::string::npos);
  // Bounded messages: whatever the input, a short excerpt of it at most.
  CHECK(r.err.size() <= 1500);
  CHECK(r.out.size() <= 1 << 16);
  // Nothing cut or temporary in the output folder; a trajectory written by a failed run is said so.
  CHECK(incomplete_files(dir / "out").empty());
  if (c.code != 0 && fs::exists(dir / "out" / "trajectory.csv")) CHECK(r.err.find("samples computed before") != std::string::npos);
  fs::remove_all(dir);
}

const std::string kOk = R"("dependent": ["y_C", "yaw"], "duration": 0.01)";
const std::string kBig(500'000, 'k');  // half a megabyte: within the 1 MiB input cap, far beyond a message

std::string e(const std::string& field) { return "wlx: error: " + field + ": "; }

}  // namespace

TEST_CASE("faults: the command line: every parse error exits 2 naming the option, with did-you-mean") {
  const std::vector<Case> cases = {
      {"no subcommand", {}, "", "", 2, e("subcommand"), "fk, ik, verify, simulate, report, viewer, export or sweep"},
      {"unknown subcommand", {"simulat", "NH-1"}, "", "", 2, e("simulat"), "did you mean 'simulate'?"},
      {"unknown subcommand 2", {"reprot"}, "", "", 2, e("reprot"), "did you mean 'report'?"},
      {"unknown subcommand, no near name", {"zzzzzzzz"}, "", "", 2, e("zzzzzzzz"), "the subcommands are"},
      {"verify without subcommand", {"verify"}, "", "", 2, e("verify"), "ik or nonholonomic"},
      {"verify, unknown subcommand", {"verify", "ikk"}, "", "", 2, e("ikk"), "did you mean 'ik'?"},
      {"verify, unknown subcommand 2", {"verify", "nonholonomc"}, "", "", 2, e("nonholonomc"), "did you mean 'nonholonomic'?"},
      {"fk, unknown option", {"fk", "--jsn"}, "", "", 2, e("--jsn"), "did you mean '--json'?"},
      {"ik, unknown option", {"ik", "--bach"}, "", "", 2, e("--bach"), "did you mean '--batch'?"},
      {"ik, unknown short option", {"ik", "-x"}, "", "", 2, e("-x"), "unknown option"},
      {"simulate, unknown option", {"simulate", "NH-1", "--outt", "{dir}"}, "", "", 2, e("--outt"), "did you mean '--out'?"},
      {"simulate, unknown option 2", {"simulate", "NH-1", "--dtt", "0.001"}, "", "", 2, e("--dtt"), "did you mean '--dt'?"},
      {"simulate, unknown option 3", {"simulate", "NH-1", "--integratr", "rk4"}, "", "", 2, e("--integratr"), "did you mean '--integrator'?"},
      {"report, unknown option", {"report", "--quik"}, "", "", 2, e("--quik"), "did you mean '--quick'?"},
      {"verify ik, unknown option", {"verify", "ik", "--swep", "IK-L1"}, "", "", 2, e("--swep"), "did you mean '--sweep'?"},
      {"not a number", {"simulate", "NH-1", "--dt", "abc", "--out", "{dir}"}, "", "", 2, e("--dt"), "'abc' is not a valid value"},
      {"not a number 2", {"simulate", "NH-1", "--tolerance", "1e-8x", "--out", "{dir}"}, "", "", 2, e("--tolerance"), "not a valid value"},
      {"empty number", {"simulate", "NH-1", "--dt", "", "--out", "{dir}"}, "", "", 2, e("--dt"), "empty value"},
      {"option twice", {"simulate", "NH-1", "--dt", "0.001", "--dt", "0.002", "--out", "{dir}"}, "", "", 2, e("--dt"), "given 2 times"},
      {"--out twice", {"simulate", "NH-1", "--out", "{dir}", "--out", "{dir}"}, "", "", 2, e("--out"), "given 2 times"},
      {"--integrator twice", {"simulate", "NH-1", "--integrator", "rk4", "--integrator", "euler"}, "", "", 2, e("--integrator"), "given 2 times"},
      {"flag twice", {"fk", "--json", "--json"}, "", "", 2, e("--json"), "given 2 times"},
      {"flag twice 2", {"ik", "--batch", "--batch"}, "{}", "", 2, e("--batch"), "given 2 times"},
      {"flag twice 3", {"simulate", "--list", "--list"}, "", "", 2, e("--list"), "given 2 times"},
      {"flag twice 4", {"report", "--quick", "--quick", "--out", "{dir}"}, "", "", 2, e("--quick"), "given 2 times"},
      {"extra argument", {"simulate", "NH-1", "NH-2", "--out", "{dir}"}, "", "", 2, e("NH-2"), "unexpected argument"},
      {"extra argument 2", {"fk", "extra"}, "", "", 2, e("extra"), "unexpected argument"},
      {"empty --out", {"simulate", "NH-1", "--out", ""}, "", "", 2, e("--out"), "empty"},
      {"--out -", {"simulate", "NH-1", "--out", "-"}, "", "", 2, e("--out"), "'-' would be a folder named '-'"},
      {"--out -, report", {"report", "--quick", "--out", "-"}, "", "", 2, e("--out"), "'-'"},
      {"--out existing file, simulate", {"simulate", "NH-1", "--out", "{existing}"}, "", "", 2, e("--out"), "exists and is not a folder"},
      {"--out existing file, report", {"report", "--quick", "--out", "{existing}"}, "", "", 2, e("--out"), "exists and is not a folder"},
      {"--out existing file, verify ik", {"verify", "ik", "--sweep", "IK-L1", "--out", "{existing}"}, "", "", 2, e("--out"), "not a folder"},
      {"--out existing file, verify nh", {"verify", "nonholonomic", "--out", "{existing}"}, "", "", 2, e("--out"), "not a folder"},
      {"empty --out, verify ik", {"verify", "ik", "--out", ""}, "", "", 2, e("--out"), "empty"},
      {"--out below a file", {"simulate", "NH-1", "--out", "{existing}/sub"}, "", "", 74, "existing-file/sub: cannot create the folder", "Not a directory"},
      {"scenario id misspelt", {"simulate", "NH-9", "--out", "{dir}"}, "", "", 2, e("SCENARIO"), "did you mean"},
      {"huge scenario argument", {"simulate", kBig.substr(0, 100000), "--out", "{dir}"}, "", "", 2, e("SCENARIO"), "bytes in all"},
      {"bad dt override", {"simulate", "NH-1", "--dt", "1e-300", "--out", "{dir}"}, "", "", 2, e("dt"), "more than the limit of 1e8"},
      {"bad tolerance override", {"simulate", "NH-1", "--integrator", "dopri5", "--tolerance", "1", "--out", "{dir}"}, "", "", 2,
       e("tolerance"), "between 1e-14"},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) check_case(cases[k], static_cast<int>(k));
  MESSAGE(cases.size() << " command-line cases");
}

TEST_CASE("faults: wlx --version and --help exit 0 with their text") {
  Result r = run({"--version"});
  CHECK(r.code == 0);
  CHECK(r.out.find_first_of("0123456789") != std::string::npos);
  CHECK(r.out.find('.') != std::string::npos);
  CHECK(r.err.empty());
  r = run({"simulate", "--help"});
  CHECK(r.code == 0);
  CHECK(r.out.find("--integrator") != std::string::npos);
}

TEST_CASE("faults: JSON requests to wlx ik: bounded depth, bounded messages, integer ranges, physical bounds") {
  const std::vector<Case> cases = {
      {"10^5 nested arrays", {"ik"}, nested(100000), "", 2, e("stdin"), "nested deeper than 64 levels"},
      {"10^5 nested objects", {"ik"}, repeat("{\"a\":", 100000) + "1" + repeat("}", 100000), "", 2, e("stdin"), "deeper than 64"},
      {"65 levels", {"ik"}, "{\"x_C\": " + nested(64) + "}", "", 2, e("stdin"), "deeper than 64"},
      {"64 levels: parsed, then refused as a value", {"ik"}, "{\"x_C\": " + nested(63) + "}", "", 2, e("x_C"), "must be a number, got array"},
      {"a half-megabyte key", {"ik"}, "{\"" + kBig + "\": 1}", "", 2, "bytes in all): unknown key", "kkkkkkkk"},
      {"a key NUL", {"ik"}, R"({"\u0000": 1})", "", 2, e("\\u0000"), "unknown key"},
      {"a key with a newline", {"ik"}, R"({"a\nb": 1})", "", 2, e("a\\nb"), "unknown key"},
      {"a key with a terminal escape", {"ik"}, R"({"\u001b[31mred": 1})", "", 2, e("\\u001b[31mred"), "unknown key"},
      {"a half-megabyte string value", {"ik"}, "{\"x_C\": \"" + kBig + "\"}", "", 2, e("x_C"), "bytes in all"},
      {"a half-megabyte method", {"ik"}, "{\"method\": \"" + kBig + "\"}", "", 2, e("method"), "bytes in all"},
      {"a half-megabyte start key", {"ik"}, "{\"start\": {\"" + kBig + "\": 1}}", "", 2, "wlx: error: start.kkk", "unknown key"},
      {"a NUL params key", {"ik"}, R"({"params": {"\u0000": 1}})", "", 2, e("params.\\u0000"), "unknown key"},
      {"stdin beyond 1 MiB", {"ik"}, "{\"x_C\": 1}" + std::string(1100000, ' '), "", 2, e("stdin"), "longer than 1048576 bytes"},
      {"a half-megabyte invalid token", {"ik"}, std::string(500000, 't'), "", 2, e("stdin"), "not valid JSON"},
      {"empty stdin", {"ik"}, "", "", 2, e("stdin"), "not valid JSON"},
      {"branch 2^32 + 1 (was branch 1)", {"ik"}, R"({"branch": 4294967297})", "", 2, e("branch"), "has branches 0 to 3, got 4294967297"},
      {"branch 2^32", {"ik"}, R"({"branch": {"wheel_l": 4294967296}})", "", 2, e("branch.wheel_l"), "has branches 0 to 7"},
      {"branch -1", {"ik"}, R"({"branch": -1})", "", 2, e("branch"), "has branches 0 to 3, got -1"},
      {"branch 2^64 - 1", {"ik"}, R"({"branch": 18446744073709551615})", "", 2, e("branch"), "got 18446744073709551615"},
      {"branch -2^63", {"ik"}, R"({"branch": -9223372036854775808})", "", 2, e("branch"), "has branches"},
      {"branch 1e20", {"ik"}, R"({"branch": 1e20})", "", 2, e("branch"), "must be an integer"},
      {"branch as text", {"ik"}, R"({"branch": "1"})", "", 2, e("branch"), "must be an integer"},
      {"branch 2.5", {"ik"}, R"({"branch": {"leg_l": 2.5}})", "", 2, e("branch.leg_l"), "must be an integer"},
      {"mass 1e308", {"ik"}, R"({"params": {"m_M1": 1e308}})", "", 2, e("params.m_M1"), "beyond the bound of 1e+06 kg"},
      {"mass just above the bound", {"ik"}, R"({"params": {"m_M1": 1000001}})", "", 2, e("params.m_M1"), "beyond the bound"},
      {"mass at the bound", {"ik"}, R"({"params": {"m_M1": 1000000}})", "", 0, "", ""},
      {"gravity 1e304", {"ik"}, R"({"params": {"g": 1e304}})", "", 2, e("params.g"), "beyond the bound of 100 m/s^2"},
      {"a 1 km cabin", {"ik"}, R"({"params": {"cxd": 1000}})", "", 2, e("params.cxd"), "beyond the bound of 100 m"},
      {"inertia 1e20", {"ik"}, R"({"params": {"Ixx_M1": 1e20}})", "", 2, e("params.Ixx_M1"), "beyond the bound"},
      {"inertia 1e300", {"ik"}, R"({"params": {"Izz_M7": 1e300}})", "", 2, e("params.Izz_M7"), "beyond the bound"},
      {"position 1e300", {"ik"}, R"({"x_C": 1e300})", "", 2, e("x_C"), "beyond the bound of 10000 m"},
      {"angle 1e6", {"ik"}, R"({"yaw": 1e6})", "", 2, e("yaw"), "beyond the bound of 100 rad"},
      {"angle -1e5", {"ik"}, R"({"theta_l5": -1e5})", "", 2, e("theta_l5"), "beyond the bound"},
      {"foot 1e5 away", {"ik"}, R"({"x_Fl": 1e5})", "", 2, e("x_Fl"), "beyond the bound"},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) check_case(cases[k], static_cast<int>(100 + k));
  MESSAGE(cases.size() << " JSON request cases");
}

TEST_CASE("faults: wlx ik --batch: capped lines named by number; the lines after a bad one still answered") {
  struct BatchCase {
    std::string what, input;
    std::string message;  // on stderr, after "wlx ik: line 1: "
  };
  const std::vector<BatchCase> cases = {
      {"a 2 MiB line", std::string(2u << 20, 'x') + "\n{}\n", "longer than 1048576 bytes"},
      {"10^5 nested arrays", nested(100000) + "\n{}\n", "JSON nested deeper than 64 levels"},
      {"a NUL key", "{\"\\u0000\": 1}\n{}\n", "\\u0000: unknown key"},
      {"a half-megabyte key", "{\"" + kBig + "\": 1}\n{}\n", kBig.substr(0, 60) + "... (500000 bytes in all): unknown key"},
      {"a half-megabyte invalid token", std::string(500000, 't') + "\n{}\n", "not valid JSON"},
      {"branch 2^32 + 1", "{\"branch\": 4294967297}\n{}\n", "branch: left leg has branches 0 to 3"},
      // Ill-formed UTF-8 quoted by the parser's message: shown as \xNN, and the error line is
      // still valid JSON (it once ended the whole batch).
      {"an ill-formed UTF-8 key", "{\"\xff\": 1}\n{}\n", "last read: '\"\\xff'"},
      {"a cut UTF-8 character", "{\"a\xc3\": 1}\n{}\n", "last read: '\"a\\xc3\"'"},
      {"a surrogate in UTF-8", "{\"\xed\xa0\x80\": 1}\n{}\n", "\\xed"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.what);
    const Result r = run({"ik", "--batch"}, {.input = c.input});
    CAPTURE(r.err.substr(0, 2000));
    CHECK(r.code == 2);
    CHECK(r.err.find("wlx ik: line 1: ") == 0);
    CHECK(r.err.find(c.message) != std::string::npos);
    CHECK(r.err.size() <= 1500);
    CHECK(r.out.size() <= 4000);
    // Line 2 answered after line 1's error.
    const auto newline = r.out.find('\n');
    REQUIRE(newline != std::string::npos);
    CHECK(r.out.find("\"line\":1") < newline);
    CHECK(r.out.find("closure_residual", newline) != std::string::npos);
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) CHECK(nlohmann::json::accept(line));
  }
  // A line that never ends (3 MiB without a newline): refused with its number, memory bounded.
  const Result r = run({"ik", "--batch"}, {.input = "{}\n" + std::string(3u << 20, ' ')});
  CHECK(r.code == 2);
  CHECK(r.err.find("wlx ik: line 2: longer than 1048576 bytes") != std::string::npos);
  // Its memory is measured in test_streaming_memory.cpp, a program small enough to measure a child.
}

TEST_CASE("faults: scenario files: physical bounds, depth, sizes, excerpts, weights, branches") {
  const std::string big_file = "{" + kOk + ", \"description\": \"" + std::string(17u << 20, 'd') + "\"}";
  const std::vector<Case> cases = {
      {"rate 1e200", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "rates": {"z_C": 1e200}})", 2, e("rates.z_C"),
       "beyond the bound of 100 m/s"},
      {"rate 1e3 rad/s", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "rates": {"roll": 1e3}})", 2, e("rates.roll"),
       "beyond the bound of 100 rad/s"},
      {"rate in deg/s", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "rates": {"pitch": {"deg/s": 1e10}}})", 2,
       e("rates.pitch"), "beyond the bound"},
      {"initial 1e300", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "initial": {"x_C": 1e300}})", 2, e("initial.x_C"),
       "beyond the bound"},
      {"initial in deg", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "initial": {"yaw": {"deg": 1e9}}})", 2,
       e("initial.yaw"), "beyond the bound"},
      {"gravity 1e304", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "params": {"g": 1e304}})", 2, e("params.g"),
       "beyond the bound"},
      {"mass 1e308", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "params": {"m_M3": 1e308}})", 2, e("params.m_M3"),
       "beyond the bound"},
      {"thigh 100 km", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "params": {"thighD": 1e5}})", 2,
       e("params.thighD"), "beyond the bound"},
      {"10^5 nested arrays", {"simulate", "{file}", "--out", "{dir}"}, "", nested(100000), 2, "scenario.json: JSON nested deeper than 64",
       ""},
      {"a 17 MiB file", {"simulate", "{file}", "--out", "{dir}"}, "", big_file, 2, "scenario.json: longer than 16777216 bytes", ""},
      {"a 10 MB key", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + ", \"" + std::string(10'000'000, 'q') + "\": 1}", 2,
       "bytes in all): unknown key", "qqqq"},
      {"a NUL key", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "\u0000": 1})", 2, e("\\u0000"), "unknown key"},
      {"a NUL key in rates", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "rates": {"\u0000": 1}})", 2,
       e("rates.\\u0000"), "unknown key"},
      {"weights 1e308: a uniform scale, valid", {"simulate", "{file}", "--out", "{dir}"}, "",
       "{" + kOk + R"(, "rates": {"z_C": 0.01}, "weighting": {"diag": [1e308, 1e308, 1e308, 1e308, 1e308, 1e308, 1e308, 1e308]}})",
       0, "", ""},
      {"weights spanning 1e13", {"simulate", "{file}", "--out", "{dir}"}, "",
       "{" + kOk + R"(, "weighting": {"diag": [1e13, 1, 1, 1, 1, 1, 1, 1]}})", 2, e("weighting.diag"), "times the smallest"},
      {"a half-megabyte weight", {"simulate", "{file}", "--out", "{dir}"}, "",
       "{" + kOk + ", \"weighting\": {\"diag\": [\"" + kBig + "\", 1, 1, 1, 1, 1, 1, 1]}}", 2, e("weighting.diag[0]"), "bytes in all"},
      {"a half-megabyte weighting", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + ", \"weighting\": \"" + kBig + "\"}", 2,
       e("weighting"), "bytes in all"},
      {"branch 2^32 + 1", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "branch": 4294967297})", 2, e("branch"),
       "has branches 0 to 3"},
      {"a half-megabyte dependent name", {"simulate", "{file}", "--out", "{dir}"}, "",
       "{\"dependent\": [\"" + kBig + "\", \"yaw\"], \"duration\": 1}", 2, e("dependent"), "bytes in all"},
      {"a half-megabyte integrator", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + ", \"integrator\": \"" + kBig + "\"}", 2,
       e("integrator"), "bytes in all"},
      {"a long array as description", {"simulate", "{file}", "--out", "{dir}"}, "",
       "{" + kOk + ", \"description\": [" + repeat("12345,", 100000) + "0]}", 2, e("description"), "bytes in all"},
      {"duration as text", {"simulate", "{file}", "--out", "{dir}"}, "", R"({"dependent": ["y_C", "yaw"], "duration": "1"})", 2,
       e("duration"), "must be a number"},
      {"tolerance below rounding", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "integrator": "dopri5", "tolerance": 1e-20})",
       2, e("tolerance"), "between 1e-14"},
      // A tolerance on a fixed-step integrator was ignored without a word (issue 26).
      {"tolerance with rk4", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "tolerance": 1e-8})", 2, e("tolerance"),
       "applies to the adaptive integrator only; this run integrates with rk4"},
      {"tolerance with euler", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "integrator": "euler", "tolerance": 1e-8})",
       2, e("tolerance"), "integrates with euler"},
      {"tolerance, the file's rk4 replaced by --integrator dopri5", {"simulate", "{file}", "--out", "{dir}", "--integrator", "dopri5"}, "",
       "{" + kOk + R"(, "tolerance": 1e-8})", 0, "", ""},
      {"tolerance, the file's dopri5 replaced by --integrator rk4", {"simulate", "{file}", "--out", "{dir}", "--integrator", "rk4"}, "",
       "{" + kOk + R"(, "integrator": "dopri5", "tolerance": 1e-8})", 2, e("tolerance"), "integrates with rk4"},
      // Duplicate keys: nlohmann::json kept the last one without a word (issue 26).
      {"a key twice", {"simulate", "{file}", "--out", "{dir}"}, "", R"({"dependent": ["y_C", "yaw"], "duration": 0.01, "duration": 5})", 2,
       "scenario.json: duration: given twice in one object", ""},
      {"a nested key twice", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "rates": {"z_C": 0.01, "z_C": 0.02}})", 2,
       "scenario.json: z_C: given twice in one object", ""},
      {"the same key in two objects: valid", {"simulate", "{file}", "--out", "{dir}"}, "",
       "{" + kOk + R"(, "initial": {"z_C": 1.8}, "rates": {"z_C": 0.01}})", 0, "", ""},
      {"10^12 steps", {"simulate", "{file}", "--out", "{dir}"}, "", R"({"dependent": ["y_C", "yaw"], "duration": 1, "dt": 1e-12})", 2,
       e("dt"), "more than the limit of 1e8"},
      {"initial not an object", {"simulate", "{file}", "--out", "{dir}"}, "", "{" + kOk + R"(, "initial": [1, 2]})", 2, e("initial"),
       "must be an object"},
      {"not JSON, long token", {"simulate", "{file}", "--out", "{dir}"}, "", std::string(500000, 'n'), 2, "scenario.json: not valid JSON",
       ""},
      {"number overflow", {"simulate", "{file}", "--out", "{dir}"}, "", R"({"dependent": ["y_C", "yaw"], "duration": 1e999})", 2,
       "scenario.json: not valid JSON", "overflow"},
      {"a run failing midway keeps its rows", {"simulate", "{file}", "--out", "{dir}"}, "",
       R"({"rates": {"z_C": 3}, "dependent": ["y_C", "yaw"], "duration": 1})", 2, "wlx: error: stopped at t = ", "leg: F_l out of reach"},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) check_case(cases[k], static_cast<int>(200 + k));
  MESSAGE(cases.size() << " scenario-file cases");
}

TEST_CASE("faults: a run that fails at step 0 prints no sentinel values, only what was computed") {
  const fs::path dir = work_dir() / "step0";
  fs::create_directories(dir);
  // The cabin 5 m up: no leg reaches the ground at t = 0.
  write(dir / "s.json", R"({"initial": {"z_C": 5}, "dependent": ["y_C", "yaw"], "duration": 1})");
  const Result r = run({"simulate", (dir / "s.json").string(), "--out", (dir / "out").string()});
  CAPTURE(r.out);
  CAPTURE(r.err);
  CHECK(r.code == 2);
  CHECK(r.out.find("0 samples") != std::string::npos);
  CHECK(r.out.find("no sample was computed") != std::string::npos);
  CHECK(r.out.find("clearance") == std::string::npos);
  CHECK(r.out.find("cond(J_beta)") == std::string::npos);
  CHECK(r.out.find("e+") == std::string::npos);  // no 1e300-style sentinel in any form
  CHECK(r.err.find("stopped at t = 0.0000 s") != std::string::npos);
  CHECK(r.err.find("the 0 samples computed before") != std::string::npos);
  // The file holds the header only: complete, and said to be so.
  CHECK(incomplete_files(dir / "out").empty());
  const std::string csv = slurp(dir / "out" / "trajectory.csv");
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 1);
}

TEST_CASE("faults: stdout that fails (/dev/full, a closed pipe) is an error with a message, never exit 0") {
  const fs::path dir = work_dir() / "stdout";
  const std::vector<std::pair<std::vector<std::string>, std::string>> commands = {
      {{"fk"}, ""},
      {{"fk", "--json"}, ""},
      {{"ik"}, "{}"},
      {{"ik", "--batch"}, "{}\n{}\n{}\n"},
      {{"simulate", "--list"}, ""},
      {{"verify", "ik", "--sweep", "IK-L1", "--out", (dir / "v").string()}, ""},
      {{"simulate", "NH-2", "--out", (dir / "s").string()}, ""},
  };
  for (const auto& [args, input] : commands) {
    const auto shown = args[0] + (args.size() > 1 ? " " + args[1] : "");  // a copy: clang 14 cannot capture a structured binding
    CAPTURE(shown);
    const Result full = run(args, {.input = input, .stdout_path = "/dev/full"});
    CHECK(full.code == 74);
    CHECK(full.err.find("stdout: writ") != std::string::npos);
    CHECK(full.err.find("No space left on device") != std::string::npos);
    // Closed pipe: with a short output the kernel may accept it all before the reader is gone,
    // so the pipe is closed before wlx starts; the write must then fail, not kill wlx silently.
    const Result pipe = run(args, {.input = input, .stdout_closed_pipe = true});
    CHECK(pipe.signal == 0);
    CHECK(pipe.code == 74);
    CHECK(pipe.err.find("stdout: writ") != std::string::npos);
    CHECK(pipe.err.find("Broken pipe") != std::string::npos);
  }
  // ik --batch stops reading when nobody receives its answers: a long input ends early.
  const Result batch = run({"ik", "--batch"}, {.input = repeat("{}\n", 20000), .stdout_closed_pipe = true});
  CHECK(batch.code == 74);
  CHECK(batch.err.find("at input line") != std::string::npos);
  CHECK(incomplete_files(dir).empty());
}

TEST_CASE("faults: stderr that cannot be written loses the message, not the exit code (never abort)") {
  // fmt::print(stderr) threw on a full stderr, which in main's error handler ended wlx with abort
  // (134); a stdout failure reported on a failing stderr still exits 74.
  const std::vector<std::pair<std::vector<std::string>, int>> commands = {
      {{"models"}, 0},
      {{"--model", "no_such_model", "fk"}, 2},
      {{"fk", "--no-such-option"}, 2},
      {{"ik"}, 2},  // stdin "[]": not a request
  };
  for (const auto& [args, code] : commands) {
    const auto shown = args[0] + (args.size() > 1 ? " " + args[1] : "");
    CAPTURE(shown);
    const Result r = run(args, {.input = "[]", .stderr_path = "/dev/full"});
    CHECK(r.signal == 0);
    CHECK(r.code == code);
  }
  const Result both = run({"fk"}, {.stdout_path = "/dev/full", .stderr_path = "/dev/full"});
  CHECK(both.signal == 0);
  CHECK(both.code == 74);
}

namespace {

// A small tmpfs to fill up, unmounted at the end; not mounted when the test may not mount.
struct SmallDisk {
  fs::path path;
  bool mounted = false;
  explicit SmallDisk(const std::string& size) : path(work_dir() / ("tmpfs-" + size)) {
    fs::create_directories(path);
    mounted = ::mount("tmpfs", path.c_str(), "tmpfs", 0, ("size=" + size).c_str()) == 0;
    if (!mounted) MESSAGE("skipped: cannot mount a tmpfs here (" << std::strerror(errno) << "): needs root or CAP_SYS_ADMIN");
  }
  ~SmallDisk() {
    if (mounted) ::umount2(path.c_str(), MNT_DETACH);
  }
};

}  // namespace

TEST_CASE("faults: a full disk (small tmpfs): exit 74 naming the file, nothing cut left, no index.html") {
  {
    SmallDisk disk("256k");
    if (disk.mounted) {
      // ST-A1+ writes ~1.6 MB: the disk fills up mid-file.
      const Result r = run({"simulate", "ST-A1+", "--out", (disk.path / "sim").string()});
      CAPTURE(r.err);
      CHECK(r.code == 74);
      CHECK(r.err.find("trajectory.csv: write failed (No space left on device); the file was not written") != std::string::npos);
      CHECK(!fs::exists(disk.path / "sim" / "trajectory.csv"));
      CHECK(incomplete_files(disk.path).empty());
      const Result v = run({"verify", "ik", "--out", (disk.path / "verify").string()});
      CAPTURE(v.err);
      CHECK(v.code == 74);
      CHECK(v.err.find(".csv: write failed (No space left on device)") != std::string::npos);
      CHECK(incomplete_files(disk.path).empty());
    }
  }
  {
    SmallDisk disk("1m");
    if (disk.mounted) {
      const fs::path out = disk.path / "report";
      fs::create_directories(out);
      write(out / "index.html", "an earlier report");  // must not survive to claim this one complete
      const Result r = run({"report", "--quick", "--out", out.string()});
      CAPTURE(r.err);
      CHECK(r.code == 74);
      CHECK(r.err.find("No space left on device") != std::string::npos);
      CHECK(r.out.find("checks pass") == std::string::npos);
      CHECK(!fs::exists(out / "index.html"));
      CHECK(incomplete_files(disk.path).empty());
    }
  }
}

namespace {

// Waits until `ready` holds (polled), at most `limit`.
template <typename Ready>
bool wait_for(Ready ready, std::chrono::milliseconds limit = 20s) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (ready()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

// Whether process `pid` has a handler for `signal` (the SigCgt mask of /proc/PID/status).
bool catches(pid_t pid, int signal) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string key, mask;
  while (status >> key) {
    if (key == "SigCgt:") {
      status >> mask;
      return (std::stoull(mask, nullptr, 16) >> (signal - 1)) & 1;
    }
    status.ignore(4096, '\n');
  }
  return false;
}

bool has_temporary(const fs::path& dir) {
  if (!fs::exists(dir)) return false;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.path().extension() == ".tmp" && entry.file_size() > 100000) return true;
  return false;
}

// Sends `signal` to a running `wlx report --out out` and checks what an interrupted report leaves:
// the exit code, the signal named, no index.html, no file cut short. Returns the result for more.
Result interrupt_report(const Spawned& s, int signal, int code, const char* name, const fs::path& out) {
  ::kill(s.pid, signal);
  const Result r = finish(s);
  CAPTURE(r.err);
  CHECK(r.code == code);
  CHECK(r.err.find(name) != std::string::npos);
  CHECK(r.err.find("no index.html was written") != std::string::npos);
  CHECK(!fs::exists(out / "index.html"));
  CHECK(incomplete_files(out).empty());
  return r;
}

}  // namespace

TEST_CASE("faults: SIGINT, SIGTERM and SIGHUP during simulate: the samples so far kept, said partial, exit 130 / 143 / 129") {
  // 10^6 steps (about 10 s): long enough to be interrupted midway.
  const fs::path dir = work_dir() / "signals";
  fs::create_directories(dir);
  write(dir / "long.json", R"({"rates": {"roll": 0.0872664626}, "dependent": ["y_C", "yaw"], "duration": 1, "dt": 1e-6})");
  for (const auto& entry :
       {std::tuple{SIGINT, 130, "SIGINT"}, std::tuple{SIGTERM, 143, "SIGTERM"}, std::tuple{SIGHUP, 129, "SIGHUP"}}) {
    // Plain variables, not structured bindings: clang 14 cannot capture those in a lambda.
    const int signal = std::get<0>(entry), code = std::get<1>(entry);
    const char* const shown = std::get<2>(entry);
    CAPTURE(shown);
    const fs::path out = dir / shown;
    const Spawned s = start({"simulate", (dir / "long.json").string(), "--out", out.string()});
    REQUIRE(wait_for([&] { return has_temporary(out); }));
    ::kill(s.pid, signal);
    const Result r = finish(s);
    CAPTURE(r.err);
    CHECK(r.signal == 0);
    CHECK(r.code == code);
    CHECK(r.err.find(shown) != std::string::npos);
    CHECK(r.err.find("the run is partial") != std::string::npos);
    CHECK(incomplete_files(out).empty());
    // The file holds exactly the samples the message counts, each row complete, t increasing by dt.
    const std::string csv = slurp(out / "trajectory.csv");
    const long rows = std::count(csv.begin(), csv.end(), '\n') - 1;
    CHECK(rows > 100);
    CHECK(rows < 1000001);
    CHECK(r.err.find("holds the " + std::to_string(rows) + " samples computed before") != std::string::npos);
    fs::remove_all(out);
  }
}

TEST_CASE("faults: SIGKILL during simulate: no trajectory.csv appears cut; only a file named .tmp is left") {
  // Nothing can run after SIGKILL: the guarantee is that the name trajectory.csv is never given to
  // an unfinished file.
  const fs::path dir = work_dir() / "sigkill";
  fs::create_directories(dir);
  write(dir / "long.json", R"({"rates": {"roll": 0.0872664626}, "dependent": ["y_C", "yaw"], "duration": 1, "dt": 1e-6})");
  const Spawned s = start({"simulate", (dir / "long.json").string(), "--out", (dir / "out").string()});
  REQUIRE(wait_for([&] { return has_temporary(dir / "out"); }));
  ::kill(s.pid, SIGKILL);
  const Result r = finish(s);
  CHECK(r.signal == SIGKILL);
  CHECK(!fs::exists(dir / "out" / "trajectory.csv"));
  int temporaries = 0;
  for (const auto& entry : fs::directory_iterator(dir / "out")) temporaries += entry.path().extension() == ".tmp";
  CHECK(temporaries == 1);
  fs::remove_all(dir);
}

TEST_CASE("faults: SIGINT during report: exit 130, said partial, no index.html (not even an earlier one), no temporaries") {
  const fs::path out = work_dir() / "report-signal";
  fs::create_directories(out);
  write(out / "index.html", "an earlier report");
  const Spawned s = start({"report", "--out", out.string()});
  // Interrupted once the simulations have started: some data files are finished, most are not.
  REQUIRE(wait_for([&] { return slurp(s.out).find("simulating") != std::string::npos; }, 300s));  // sanitized builds are slow
  const Result r = interrupt_report(s, SIGINT, 130, "SIGINT", out);
  CHECK(r.err.find("partial: no index.html was written") != std::string::npos);
}

TEST_CASE("faults: SIGTERM while gnuplot renders: exit 143, no index.html, no temporary image left") {
  const fs::path out = work_dir() / "render-signal";
  // --quick: the same rendering after fewer runs (the full set took 40 s under the sanitizers).
  const Spawned s = start({"report", "--quick", "--out", out.string()});
  REQUIRE(wait_for([&] { return slurp(s.out).find("rendering") != std::string::npos; }, 300s));
  std::this_thread::sleep_for(200ms);  // some figures done, some under way
  interrupt_report(s, SIGTERM, 143, "SIGTERM", out);
  fs::remove_all(out);
}

TEST_CASE("faults: SIGTERM to ik --batch waiting for input: exit 143 with a message, the answers given kept") {
  const Spawned s = start({"ik", "--batch"}, {.stdin_pipe = true});
  const std::string line = "{}\n";
  // Signalled only once wlx catches SIGTERM (before that the default action would just kill it).
  REQUIRE(wait_for([&] { return catches(s.pid, SIGTERM); }));
  REQUIRE(::write(s.stdin_fd, line.data(), line.size()) == static_cast<ssize_t>(line.size()));
  std::this_thread::sleep_for(500ms);  // wlx answers the line and blocks reading the next
  ::kill(s.pid, SIGTERM);
  const Result r = finish(s);
  CAPTURE(r.err);
  CHECK(r.signal == 0);
  CHECK(r.code == 143);
  CHECK(r.err.find("SIGTERM") != std::string::npos);
  CHECK(r.out.find("closure_residual") != std::string::npos);
}

TEST_CASE("faults: paths with quotes, spaces, $, backquotes, newlines and non-ASCII work, and run nothing") {
  const fs::path base = work_dir() / "paths";
  fs::create_directories(base);
  const std::string hostile = "bob's report $(touch pwned) `touch pwned2` ;touch pwned3 \"q\" \\ new\nline \u00fc\u20ac";
  const fs::path dir = base / hostile;
  fs::create_directories(dir);
  // The report: gnuplot must find its data and write every figure.
  Result r = run({"report", "--quick", "--out", (dir / "report").string()}, {.cwd = base});
  CAPTURE(r.err);
  CHECK(r.code == 0);
  CHECK(fs::exists(dir / "report" / "index.html"));
  int images = 0;
  for (const auto& entry : fs::directory_iterator(dir / "report" / "fig")) images += entry.path().extension() == ".png";
  CHECK(images >= 10);
  CHECK(incomplete_files(dir).empty());
  // A scenario file and an output folder with the same name.
  write(dir / "scenario $x.json", R"({"rates": {"roll": 0.01}, "dependent": ["y_C", "yaw"], "duration": 0.01})");
  r = run({"simulate", (dir / "scenario $x.json").string(), "--out", (dir / "sim").string()}, {.cwd = base});
  CHECK(r.code == 0);
  CHECK(fs::exists(dir / "sim" / "trajectory.csv"));
  r = run({"verify", "ik", "--sweep", "IK-L1", "--out", (dir / "verify").string()}, {.cwd = base});
  CHECK(r.code == 0);
  CHECK(fs::exists(dir / "verify" / "IK-L1.csv"));
  // No command was run from any part of the names, here or in the report folder.
  for (const char* name : {"pwned", "pwned2", "pwned3"}) {
    CHECK(!fs::exists(base / name));
    CHECK(!fs::exists(dir / "report" / name));
    CHECK(!fs::exists(fs::current_path() / name));
  }
}


// ---- hostile report files and inputs that are not files (issue 26) ----

namespace {

std::string report_file_with(const std::string& from, const std::string& to) {
  std::string text = slurp(fs::path(WLX_SOURCE_DIR) / "scenarios" / "excavator" / "report.yaml");
  const auto at = text.find(from);
  REQUIRE_MESSAGE(at != std::string::npos, "anchor not in report.yaml: " << from);
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("faults: a --claims label with a line break and a system() call is refused; quotes, backquotes and </script> are quoted, nothing runs") {
  const fs::path base = work_dir() / "hostile-claims";
  fs::create_directories(base);
  const std::string anchor = "label: \"thesis (~1e-5 m, section 3.4)\"}";
  // Before: the label's line break ended the gnuplot command and system(...) ran a shell.
  write(base / "newline.yaml", report_file_with(anchor, "label: \"x\\nsystem('touch PWNED')\"}"));
  Result r = run({"report", "--quick", "--claims", (base / "newline.yaml").string(), "--out", (base / "r1").string()}, {.cwd = base});
  CAPTURE(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("newline.yaml:32: reference_lines.ik_check_error.label: has a line break at byte 1") != std::string::npos);
  CHECK(!fs::exists(base / "r1" / "index.html"));
  // Every other way out of a gnuplot string, and HTML in a claim: written as text.
  std::string text = report_file_with(anchor, "label: \"x' . system('touch PWNED') . 'y `touch PWNED2` @z \\u00fc </script>\"}");
  const std::string claim = "claim: Total mass of the default parameters";
  REQUIRE(text.find(claim) != std::string::npos);
  text.replace(text.find(claim), claim.size(), "claim: \"</td><script>alert(1)</script> Total mass\"");
  write(base / "quotes.yaml", text);
  r = run({"report", "--quick", "--claims", (base / "quotes.yaml").string(), "--out", (base / "r2").string()}, {.cwd = base});
  CAPTURE(r.err);
  REQUIRE(r.code == 0);
  for (const fs::path& where : {base, base / "r2", base / "r2" / "plots"})
    for (const char* name : {"PWNED", "PWNED2"}) CHECK(!fs::exists(where / name));
  const std::string gp = slurp(base / "r2" / "plots" / "ik-IK-L3.gp");
  CHECK(gp.find("title 'x'' . system(''touch PWNED'') . ''y `touch PWNED2` @z \u00fc </script>'") != std::string::npos);
  const std::string html = slurp(base / "r2" / "index.html");
  CHECK(html.find("<script>alert") == std::string::npos);
  CHECK(html.find("&lt;/td&gt;&lt;script&gt;alert(1)&lt;/script&gt;") != std::string::npos);
}

TEST_CASE("faults: --claims and --params that never end or are not files (/dev/zero, a FIFO without a writer, a folder) exit 2 at once") {
  const fs::path dir = work_dir() / "not-files";
  fs::create_directories(dir);
  const fs::path fifo = dir / "input.fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const std::vector<std::pair<std::string, std::string>> inputs = {
      {"/dev/zero", "is a device, not a regular file"}, {fifo.string(), "is a pipe (FIFO)"}, {dir.string(), "is a folder"}};
  for (const auto& [path, reason] : inputs) {
    const auto shown = path;  // a copy: clang 14 cannot capture a structured binding
    CAPTURE(shown);
    const auto t0 = std::chrono::steady_clock::now();
    Result r = run({"report", "--quick", "--claims", path, "--out", (dir / "out").string()});
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("--claims: ") != std::string::npos);
    CHECK(r.err.find(reason) != std::string::npos);
    r = run({"fk", "--params", path}, {.input = "{}"});
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("--params: ") != std::string::npos);
    CHECK(r.err.find(reason) != std::string::npos);
    CHECK(std::chrono::steady_clock::now() - t0 < 10s);  // no waiting for a writer or an end
  }
  // A report file beyond the bound.
  write(dir / "big.yaml", "title: big\n" + std::string(2 << 20, '#'));
  const Result big = run({"report", "--quick", "--claims", (dir / "big.yaml").string(), "--out", (dir / "out").string()});
  CHECK(big.code == 2);
  CHECK(big.err.find("more than the limit of 1048576 bytes") != std::string::npos);
}

TEST_CASE("faults: a scenario's id or description with a line break or a control character is refused, naming the field") {
  const Case cases[] = {
      {"id with a line break", {"simulate", "{file}", "--out", "{dir}"}, "", "{\"id\": \"a\\nb\", " + kOk + "}", 2, e("id"), "line break"},
      {"description with NUL", {"simulate", "{file}", "--out", "{dir}"}, "", "{\"description\": \"a\\u0000b\", " + kOk + "}", 2,
       e("description"), "control character U+0000"},
  };
  int index = 900;
  for (const Case& c : cases) check_case(c, index++);
}

TEST_CASE("faults: ik --batch on a line that never ends (/dev/zero) stops at SIGTERM, SIGINT and SIGHUP within a second") {
  // No '\n' ever comes and no read ever blocks: the signal must be asked for while reading.
  for (const auto& entry : {std::pair{SIGTERM, 143}, std::pair{SIGINT, 130}, std::pair{SIGHUP, 129}}) {
    const int signal = entry.first, code = entry.second;  // not a structured binding: clang 14 cannot capture one
    CAPTURE(signal);
    const Spawned s = start({"ik", "--batch"}, {.stdin_path = "/dev/zero"});
    REQUIRE(wait_for([&] { return catches(s.pid, signal); }));
    std::this_thread::sleep_for(200ms);  // well into the endless line
    const auto t0 = std::chrono::steady_clock::now();
    ::kill(s.pid, signal);
    const Result r = finish(s);
    CAPTURE(r.err);
    CHECK(r.signal == 0);
    CHECK(r.code == code);
    CHECK(std::chrono::steady_clock::now() - t0 < 1s);
  }
}

TEST_CASE("faults: SIGTERM and SIGHUP during wlx viewer's simulation: exit 143 / 129, no run file, no temporary") {
  // A stand-in for the built viewer (its files are copied, not run): WLX_VIEWER_DIR points at it.
  const fs::path dir = work_dir() / "viewer-signal", fake = dir / "built";
  fs::create_directories(fake / "wasm");
  write(fake / "viewer.html", "<!DOCTYPE html>");
  write(fake / "viewer.js", "// viewer");
  write(fake / "wasm" / "wlx_excavator.js", "// module");
  write(dir / "long.json", R"({"id": "long", "rates": {"roll": 0.0872664626}, "dependent": ["y_C", "yaw"], "duration": 1, "dt": 1e-6})");
  ::setenv("WLX_VIEWER_DIR", fake.c_str(), 1);
  for (const auto& entry : {std::pair{SIGTERM, 143}, std::pair{SIGHUP, 129}}) {
    const int signal = entry.first, code = entry.second;  // not a structured binding: clang 14 cannot capture one
    CAPTURE(signal);
    const fs::path out = dir / ("out-" + std::to_string(signal));
    const Spawned s = start({"viewer", (dir / "long.json").string(), "--out", out.string()});
    // The viewer's files are in place once the simulation runs.
    REQUIRE(wait_for([&] { return fs::exists(out / "runs" / "index.js") && catches(s.pid, signal); }));
    std::this_thread::sleep_for(300ms);
    const auto t0 = std::chrono::steady_clock::now();
    ::kill(s.pid, signal);
    const Result r = finish(s);
    CAPTURE(r.err);
    CHECK(r.signal == 0);
    CHECK(r.code == code);
    CHECK(std::chrono::steady_clock::now() - t0 < 1s);
    CHECK(!fs::exists(out / "runs" / "long.js"));
    CHECK(incomplete_files(out).empty());
  }
  ::unsetenv("WLX_VIEWER_DIR");
}
