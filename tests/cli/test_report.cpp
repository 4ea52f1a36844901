// `wlx report` end to end: every run, every figure, a checks table without failures, valid HTML.
#include "../helpers/csv.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;

namespace {

// A folder of this test process's own: other builds on the machine run these tests at the same time.
fs::path temp_dir(const std::string& name) {
  return fs::temp_directory_path() / (name + "_" + std::to_string(static_cast<long>(::getpid())));
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Well-formedness of the XHTML-style markup the report writes: every element closed, properly
// nested; returns the first problem or an empty string.
std::string markup_problem(const std::string& html) {
  std::vector<std::string> open;
  std::size_t pos = 0;
  while ((pos = html.find('<', pos)) != std::string::npos) {
    const std::size_t end = html.find('>', pos);
    if (end == std::string::npos) return "unterminated tag at " + std::to_string(pos);
    const std::string tag = html.substr(pos + 1, end - pos - 1);
    pos = end + 1;
    if (tag.empty()) return "empty tag";
    if (tag[0] == '!') continue;  // <!DOCTYPE html>
    if (tag.back() == '/') continue;  // <img ... />
    const bool closing = tag[0] == '/';
    const std::string name = tag.substr(closing ? 1 : 0, tag.find_first_of(" \t\n", closing ? 1 : 0) - (closing ? 1 : 0));
    if (!closing) {
      open.push_back(name);
    } else {
      if (open.empty() || open.back() != name) return "</" + name + "> closes " + (open.empty() ? "nothing" : "<" + open.back() + ">");
      open.pop_back();
    }
  }
  return open.empty() ? "" : "<" + open.back() + "> never closed";
}

// The index of a column in a CSV file's header, or -1.
int csv_column(const fs::path& path, const std::string& name) {
  std::istringstream in(slurp(path));
  std::string header, cell;
  std::getline(in, header);
  std::istringstream cells(header);
  for (int k = 0; std::getline(cells, cell, ','); ++k)
    if (cell == name) return k;
  return -1;
}

}  // namespace

// Sanitized, the quick report (the same code on fewer runs: the full one took 47 s of CI's there);
// the normal tree runs the full one.
#ifdef WLX_SANITIZED
constexpr bool kFullReport = false;
#else
constexpr bool kFullReport = true;
#endif

TEST_CASE("report: the full report runs, every image exists, every check passes, the HTML is well formed, its gnuplot scripts run from their own folder") {
  const fs::path dir = temp_dir("wlx_report_test"), cwd = temp_dir("wlx_report_cwd");
  fs::remove_all(dir);
  fs::remove_all(cwd);
  fs::create_directories(cwd);
  // Run from a folder of its own, which must stay empty: nothing is written outside --out (MuJoCo,
  // left to itself, appends its warnings to MUJOCO_LOG.TXT in the current folder).
  const std::string cmd = "cd " + cwd.string() + " && " + std::string(WLX_BINARY) + " report " + (kFullReport ? "" : "--quick ") +
                          "--out " + dir.string() + " > " + (dir.string() + ".log") + " 2>&1";
  const int status = std::system(cmd.c_str());
  INFO(slurp(dir.string() + ".log"));
  REQUIRE(WEXITSTATUS(status) == 0);
  for (const auto& stray : fs::directory_iterator(cwd)) FAIL_CHECK("written outside --out: " << stray.path());
  fs::remove_all(cwd);
  const std::string html = slurp(dir / "index.html");
  REQUIRE(!html.empty());
  CHECK(markup_problem(html).empty());
  INFO(markup_problem(html));
  CHECK(html.find("class=\"fail\"") == std::string::npos);
  CHECK(html.find("class=\"pass\"") != std::string::npos);
  // Every referenced file exists and is not empty.
  const std::regex ref("(src|href)=\"([^\"#?]+)[^\"]*\"");
  int images = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), ref); it != std::sregex_iterator(); ++it) {
    const fs::path file = dir / (*it)[2].str();
    CAPTURE(file);
    REQUIRE(fs::exists(file));
    CHECK(fs::file_size(file) > 100);
    images += file.extension() == ".png";
  }
  CHECK(images >= (kFullReport ? 50 : 14));
  // The CSV files behind the figures never hold NaN or Inf.
  for (const auto& e : fs::directory_iterator(dir / "data")) {
    const std::string text = slurp(e.path());
    CHECK(text.find("nan") == std::string::npos);
    CHECK(text.find("inf") == std::string::npos);
  }
#ifdef WLX_VIEWER_BUILT
  // Every run links its animation in the 3D viewer, whose data file is there and names the run.
  const std::regex animate("href=\"viewer/viewer.html\\?run=([^\"]+)\"");
  int animated = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), animate); it != std::sregex_iterator(); ++it) {
    const std::string id = std::regex_replace((*it)[1].str(), std::regex("%2B"), "+");
    const std::string data = slurp(dir / "viewer" / "runs" / (id + ".js"));
    CAPTURE(id);
    CHECK(data.find("\"id\":\"" + id + "\"") != std::string::npos);
    ++animated;
  }
  if (kFullReport) CHECK(animated >= 20);  // the 19 scenarios, inverse dynamics twice
  CHECK(fs::file_size(dir / "viewer" / "viewer.js") > 100000);
#endif
  const std::string log = slurp(dir.string() + ".log");
  // Progress was shown, and its last step is numbered as the last of all.
  CHECK(std::regex_search(log, std::regex(R"(\[(\d+)/\1\] rendering)")));
  if (kFullReport) CHECK(html.find("Integrators compared") != std::string::npos);
  // The forward-dynamics section with its checks (round trip, energy, closed loop) and figures.
  for (const char* id : {"FD-round-trip", "FD-energy", "FD-closed-loop"}) CHECK(html.find(id) != std::string::npos);
  CHECK(html.find("<img src=\"fig/forward-round-trips.png\"") != std::string::npos);
  CHECK(html.find("<img src=\"fig/forward-closed-loop.png\"") != std::string::npos);
#ifdef WLX_HAVE_MUJOCO
  // The physics engine's runs are drawn (and, where they leave their reference, said), without
  // failing the report: the exit status above is 0.
  if (kFullReport) CHECK(html.find("<img src=\"fig/engine-ID-1-w1.png\"") != std::string::npos);
#endif
  CHECK(log.find("open " + fs::absolute(dir / "index.html").string()) != std::string::npos);
  // The gnuplot scripts run from their own folder (plots/): the first and the last, their figures
  // removed, draw them again. (On this report rather than one of their own: a sanitized report is
  // 7 s of CI.)
  std::vector<fs::path> scripts;
  for (const auto& e : fs::directory_iterator(dir / "plots"))
    if (e.path().extension() == ".gp") scripts.push_back(e.path());
  REQUIRE(!scripts.empty());
  std::sort(scripts.begin(), scripts.end());
  for (const fs::path& script : {scripts.front(), scripts.back()}) {
    const std::string stem = script.stem().string();
    fs::remove(dir / "fig" / (stem + ".png"));
    fs::remove(dir / "fig" / (stem + ".svg"));
    CAPTURE(stem);
    CHECK(std::system(("cd " + (dir / "plots").string() + " && gnuplot " + stem + ".gp > " + (dir / (stem + ".log")).string() +
                       " 2>&1").c_str()) == 0);
    CHECK(fs::file_size(dir / "fig" / (stem + ".png")) > 1000);
    CHECK(fs::file_size(dir / "fig" / (stem + ".svg")) > 1000);
  }
}

namespace {

// Runs `command` through the shell with its output in `log`; returns the exit code.
int run(const std::string& command, const fs::path& log) {
  const int status = std::system((command + " > " + log.string() + " 2>&1").c_str());
  return WEXITSTATUS(status);
}

void write(const fs::path& p, const std::string& text) {
  std::ofstream out(p);
  out << text;
}

// A report file with one check whose criterion the measured value meets or not.
std::string claims_with_mass_check(const std::string& criterion) {
  // quick: one sweep and one run, so that --quick draws few figures (without it, a file of claims
  // alone draws every run: 6.8 s, and 37 s under the sanitizers, for a check of the mass).
  return "quick: {sweeps: [IK-L3], scenarios: [NH-1]}\nsources: {datasheet: the maker's data sheet}\n"
         "claims:\n  - id: mass\n    kind: check\n    claim: the total mass\n    source: {datasheet: Table 6-1}\n"
         "    claimed: {datasheet: 6153.98 kg}\n    measure: {quantity: total_mass}\n    criterion: " +
         criterion + "\n    why: a test\n";
}

}  // namespace

TEST_CASE("report: a check whose measured value is outside its criterion fails the report (exit 1)") {
  const fs::path dir = temp_dir("wlx_report_failing_check");
  fs::remove_all(dir);
  fs::create_directories(dir);
  // The mass of the default parameters is several tonnes: 1 kg at most cannot hold.
  write(dir / "claims.yaml", claims_with_mass_check("{at_most: 1}"));
  const int code = run(std::string(WLX_BINARY) + " report --quick --claims " + (dir / "claims.yaml").string() + " --out " +
                           (dir / "out").string(), dir / "log");
  INFO(slurp(dir / "log"));
  CHECK(code == 1);
  const std::string html = slurp(dir / "out" / "index.html");
  CHECK(html.find("class=\"fail\"") != std::string::npos);
  CHECK(html.find("0 of 1 checks pass") != std::string::npos);
  // The file's own source is the claims' column, its value under it.
  CHECK(html.find("<th>datasheet</th>") != std::string::npos);
  CHECK(html.find("<td>6153.98 kg</td>") != std::string::npos);
  CHECK(slurp(dir / "log").find("check failed: mass") != std::string::npos);
}

TEST_CASE("report: a malformed or inapplicable report file is a bad input (exit 2) naming file, line and field") {
  const fs::path dir = temp_dir("wlx_report_bad_claims");
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string claims = (dir / "claims.yaml").string();
  const std::string command = std::string(WLX_BINARY) + " report --quick --claims " + claims + " --out " + (dir / "out").string();
  write(claims, claims_with_mass_check("{near: 6000}"));
  CHECK(run(command, dir / "log") == 2);
  CHECK(slurp(dir / "log").find(claims + ":10: claims[0].criterion: 'near' needs a 'tolerance'") != std::string::npos);
  // Well formed, but the name is not one of the model's coordinates.
  write(claims, "run_figures:\n  - {id: F, runs: [NH-1], x: rol, y: [yaw]}\n");
  CHECK(run(command, dir / "log") == 2);
  CHECK(slurp(dir / "log").find(claims + ":2: run_figures.F.x: 'rol' is not a coordinate of model excavator (did you mean 'roll'?)") !=
        std::string::npos);
  CHECK(!fs::exists(dir / "out" / "index.html"));
  write(claims, "claims: [\n");
  CHECK(run(command, dir / "log") == 2);
  CHECK(slurp(dir / "log").find(claims + ":") != std::string::npos);
}

namespace {
// `wlx --model MODEL report` into a fresh folder: the folder, once the report exited 0 with a page
// whose markup is sound and that shows no failed check.
[[maybe_unused]] fs::path model_report(const std::string& model) {
  const fs::path dir = temp_dir("wlx_report_" + model);
  fs::remove_all(dir);
  const int code = run(std::string(WLX_BINARY) + " --model " + model + " report --out " + dir.string(), dir.string() + ".log");
  INFO(slurp(dir.string() + ".log"));
  REQUIRE(code == 0);
  const std::string html = slurp(dir / "index.html");
  CHECK(markup_problem(html).empty());
  CHECK(html.find("class=\"fail\"") == std::string::npos);
  return dir;
}
}  // namespace

#ifdef WLX_BUILT_MODEL_walker  // the sanitized tree builds the excavator only
TEST_CASE("report: a model without a report file still gets a report of its runs") {
  const fs::path dir = model_report("walker");
  const std::string html = slurp(dir / "index.html");
  CHECK(html.find("has no report file with claims") != std::string::npos);
  CHECK(html.find("<img src=\"fig/pose-") != std::string::npos);
  CHECK(html.find("<img src=\"fig/id-") != std::string::npos);
}
#endif

#ifdef WLX_BUILT_MODEL_wheeled_quadruped  // not in the sanitized tree
TEST_CASE("report: the wheeled quadruped (four wheels, sixteen actuators) gets a report of its runs that passes") {
  const fs::path dir = model_report("wheeled_quadruped");
  const std::string html = slurp(dir / "index.html");
  // The torque figures plot every actuator: the wheel drives by their URDF joints' names.
  bool drives = false;
  for (const auto& entry : fs::directory_iterator(dir / "plots"))
    if (entry.path().extension() == ".gp" && slurp(entry.path()).find("tau_wheel_joint_rh") != std::string::npos) drives = true;
  CHECK(drives);
  CHECK(html.find("<img src=\"fig/id-") != std::string::npos);
  // Its forward dynamics, read from the CSV files (the model has no report file, so no checks):
  // every round trip within the issue's 1e-8, every closed loop's error in its second half
  // within 5 mm (what is left of a 10% heavier plant: about 2.5 mm).
  int trips = 0, loops = 0;
  for (const auto& entry : fs::directory_iterator(dir / "data")) {
    const std::string name = entry.path().filename().string();
    const bool trip = name.ends_with("-forward.csv"), loop = name.ends_with("-closed-loop.csv");
    if (!trip && !loop) continue;
    std::istringstream in(slurp(entry.path()));
    std::string line;
    std::getline(in, line);
    std::vector<std::pair<double, double>> rows;  // t, the deviation or the tracking error
    while (std::getline(in, line)) {
      const auto comma = line.find(',');
      rows.emplace_back(std::stod(line.substr(0, comma)), std::stod(line.substr(comma + 1)));
    }
    CAPTURE(name);
    REQUIRE(rows.size() == 1001);  // 1 s at 1 ms: the loop ran to the end
    for (const auto& [t, value] : rows) {
      if (trip) CHECK(value <= 1e-8);
      if (loop && t >= 0.5) CHECK(value <= 5e-3);
    }
    if (loop) CHECK(rows.front().second == doctest::Approx(0.02).epsilon(1e-9));  // the perturbed start
    trips += trip, loops += loop;
  }
  CHECK(trips == 4);  // ID-Q1 and ID-Q2, each with both weightings
  CHECK(loops == 4);
#ifdef WLX_HAVE_MUJOCO
  // In a physics engine: the model's controller drives MuJoCo's machine along each run under
  // weighting 1 to its end. Bounds about twice what was measured when this was written (0.22 mm
  // and 0.30 deg of tracking error, mean slip 28 mm/s, normal forces within 0.22% of the load):
  // an export, a state mapping or a controller that breaks misses them by orders of magnitude.
  CHECK(html.find("In a physics engine") != std::string::npos);
  int engine_runs = 0;
  for (const char* run : {"ID-Q1-w1", "ID-Q2-w1"}) {
    const fs::path csv = dir / "data" / (std::string(run) + "-mujoco.csv");
    CAPTURE(csv);
    REQUIRE(fs::exists(csv));
    CHECK(html.find("<img src=\"fig/engine-" + std::string(run) + ".png\"") != std::string::npos);
    std::istringstream in(slurp(csv));
    std::string line;
    std::getline(in, line);
    const int length = csv_column(csv, "tracking_error_m"), angle = csv_column(csv, "tracking_error_rad");
    std::vector<int> slip, mujoco, model;
    for (const char* c : {"contactlf", "contactrf", "contactlh", "contactrh"}) {
      slip.push_back(csv_column(csv, std::string("slip_") + c));
      mujoco.push_back(csv_column(csv, std::string("normal_mujoco_") + c));
      model.push_back(csv_column(csv, std::string("normal_wlx_") + c));
    }
    double slip_sum = 0;
    long rows = 0, settled = 0;
    while (std::getline(in, line)) {
      std::vector<double> v;
      std::istringstream cells(line);
      for (std::string cell; std::getline(cells, cell, ',');) v.push_back(std::stod(cell));
      ++rows;
      CHECK(v[static_cast<std::size_t>(length)] <= 5e-4);
      CHECK(v[static_cast<std::size_t>(angle)] <= 0.0105);
      if (v[0] < 0.05) continue;  // the contacts press in
      double load = 0;
      for (int m : model) load += v[static_cast<std::size_t>(m)];
      for (std::size_t c = 0; c < slip.size(); ++c) {
        slip_sum += v[static_cast<std::size_t>(slip[c])];
        ++settled;
        CHECK(std::abs(v[static_cast<std::size_t>(mujoco[c])] - v[static_cast<std::size_t>(model[c])]) <= 0.005 * load);
      }
    }
    CHECK(rows == 1001);  // 1 s at MuJoCo's 1 ms: the run reached its end
    CHECK(slip_sum / static_cast<double>(settled) <= 0.065);
    ++engine_runs;
  }
  CHECK(engine_runs == 2);
#else
  CHECK(html.find("Not run: wlx was built without MuJoCo") != std::string::npos);
#endif
}
#endif


// Issue 43, item 4: runs of a user's folder that stop, each in its own way, in one report. UP
// raises the body at 1 m/s until a leg cannot reach its foot (it stops part way); OUT starts with
// the body too high to reach at all (its three inverse-dynamics runs stop before their first
// sample, so neither forward simulation runs); HIGH starts just below the reach and moves down,
// so its runs complete, but the closed loop's plant, started 2 cm higher, is out of reach at once
// (an empty closed loop, which made gnuplot fail with "x range is invalid").
TEST_CASE("report: runs that stop are rows of the report, which is written all the same and exits 1 listing them") {
  const fs::path dir = temp_dir("wlx_report_stopped_runs");
  fs::remove_all(dir);
  fs::create_directories(dir / "runs");
  write(dir / "runs" / "UP.json", R"({"description": "the body raised until a leg cannot reach", "rates": {"z_C": 1.0},
    "dependent": ["y_C", "yaw"], "duration": 3, "dt": 0.01})");
  write(dir / "runs" / "OUT.json", R"({"description": "inverse dynamics from a start out of reach", "initial": {"z_C": 3.2},
    "rates": {"z_C": -0.5}, "dependent": ["y_C", "yaw"], "duration": 0.1, "dt": 0.001, "weighting": 1})");
  write(dir / "runs" / "HIGH.json", R"({"description": "inverse dynamics down from just below the reach", "initial": {"z_C": 2.87},
    "rates": {"z_C": -0.5}, "dependent": ["y_C", "yaw"], "duration": 0.2, "dt": 0.001, "weighting": 1})");
  // Checks on each kind of stop, one on none (the mass) and one on a round trip that completes.
  const auto check = [](const std::string& id, const std::string& measure, const std::string& criterion) {
    return "  - {id: " + id + ", kind: check, claim: " + id + ", source: {spec: a test}, claimed: {spec: the test's}, measure: " + measure + ", criterion: " +
           criterion + ", why: a test}\n";
  };
  write(dir / "runs" / "report.yaml",
        "quick: {sweeps: [IK-L3], scenarios: [UP, OUT, HIGH]}\n"
        "integrator_comparison: {scenarios: [UP], coordinates: [y_C]}\n"
        "sources: {spec: the test's specification}\n"
        "claims:\n" +
            check("mass", "{quantity: total_mass}", "{at_least: 1}") +
            check("up-end", "{quantity: end_value, run: UP, coordinate: z_C}", "{at_least: 2.5}") +
            check("out-trip", "{quantity: round_trip_deviation, runs: [OUT-w1]}", "{at_most: 1.0e-8}") +
            // Near the legs' reach the round trip is looser than the built-in runs' 1e-8 (2e-5 m here).
            check("high-trip", "{quantity: round_trip_deviation, runs: [HIGH-w1]}", "{at_most: 1.0e-3}") +
            check("high-loop", "{quantity: closed_loop_error, runs: [HIGH-w1]}", "{at_most: 0.01}") +
            check("up-euler", "{quantity: integrator_deviation, integrator: euler, runs: [UP]}", "{at_most: 1}"));
  for (const bool quick : {true, false}) {
    CAPTURE(quick);
    const fs::path out = dir / (quick ? "quick" : "full");
    const int code = run(std::string(WLX_BINARY) + " --scenarios " + (dir / "runs").string() + " report " + (quick ? "--quick " : "") +
                             "--out " + out.string(),
                         dir / "log");
    const std::string log = slurp(dir / "log");
    INFO(log);
    CHECK(code == 1);
    const std::string html = slurp(out / "index.html");
    REQUIRE(!html.empty());
    CHECK(markup_problem(html).empty());
    // Every file the page names is there: no figure of a stopped run is referenced without its image.
    const std::regex ref("(src|href)=\"([^\"#?]+)[^\"]*\"");
    for (auto it = std::sregex_iterator(html.begin(), html.end(), ref); it != std::sregex_iterator(); ++it) {
      CAPTURE((*it)[2].str());
      CHECK(fs::exists(out / (*it)[2].str()));
    }
    for (const auto& e : fs::directory_iterator(out / "data")) {
      const std::string text = slurp(e.path());
      CHECK(text.find("nan") == std::string::npos);
      CHECK(text.find("inf") == std::string::npos);
    }

    // UP: its samples up to where it stopped, in its CSV and its row, with the time and the reason;
    // its pose figure is drawn from them.
    const auto up = wlx_test::read_csv(out / "data" / "UP.csv").second;
    REQUIRE(up.size() >= 2);
    CHECK(up.size() < 301);  // 3 s at 0.01 s: it did not finish
    const int z_C = csv_column(out / "data" / "UP.csv", "z_C");
    REQUIRE(z_C > 0);
    CHECK(up.back()[static_cast<std::size_t>(z_C)] == doctest::Approx(2.0 + up.back()[0]).epsilon(1e-9));  // it rose as asked
    // It stopped in the step from its last sample: the time the report gives is that sample's.
    char up_time_text[32];
    std::snprintf(up_time_text, sizeof up_time_text, "%.4f", up.back()[0]);
    const std::string up_time = up_time_text;
    const std::string up_stop = "stopped at t = " + up_time + " s: left leg: F_l out of reach";
    CHECK(html.find("<td>UP</td><td>the body raised until a leg cannot reach</td><td>" + std::to_string(up.size()) + "</td><td>" +
                    up_stop) != std::string::npos);
    CHECK(log.find("wlx: run stopped: UP at t = " + up_time + " s: left leg: F_l out of reach") != std::string::npos);
    CHECK(html.find("<img src=\"fig/pose-UP.png\"") != std::string::npos);

    // OUT: no sample at all; said in words, no figure, no forward simulation; its row has no maxima.
    for (const char* id : {"OUT-w1", "OUT-w2", "OUT-w3"}) {
      CAPTURE(id);
      CHECK(wlx_test::read_csv(out / "data" / (std::string(id) + ".csv")).second.empty());
      CHECK(log.find(std::string("wlx: run stopped: ") + id + " at t = 0.0000 s: ") != std::string::npos);
      CHECK(html.find(std::string("<td>") + id + "</td><td>inverse dynamics from a start out of reach</td><td>0</td><td>stopped at t = "
                      "0.0000 s: ") != std::string::npos);
      CHECK(html.find(std::string("id=\"fig-id-") + id + "\" class=\"omitted\">No figure of the torques of " + id + ": " + id +
                      " stopped at t = 0.0000 s before its first sample") != std::string::npos);
      CHECK(!fs::exists(out / "fig" / ("id-" + std::string(id) + ".png")));
    }
    CHECK(html.find("id=\"fig-pose-OUT\" class=\"omitted\"") != std::string::npos);
    CHECK(html.find("<td>OUT-w1</td><td>not run: OUT-w1 stopped at t = 0.0000 s: ") != std::string::npos);
    CHECK(!fs::exists(out / "data" / "OUT-w1-forward.csv"));

    // HIGH: the runs and their round trips complete (drawn); the closed loop never left its start:
    // an empty CSV, a sentence instead of its figure.
    CHECK(wlx_test::read_csv(out / "data" / "HIGH-w1.csv").second.size() == 201);
    CHECK(wlx_test::read_csv(out / "data" / "HIGH-w1-forward.csv").second.size() == 201);
    CHECK(wlx_test::read_csv(out / "data" / "HIGH-w1-closed-loop.csv").second.empty());
    CHECK(log.find("wlx: run stopped: HIGH-w1 (closed loop) at t = 0.0000 s: ") != std::string::npos);
    CHECK(log.find("wlx: run stopped: HIGH-w1 at") == std::string::npos);
    CHECK(html.find("<img src=\"fig/forward-round-trips.png\"") != std::string::npos);
    CHECK(html.find("fig/forward-closed-loop.png") == std::string::npos);
    CHECK(html.find("No figure of the closed loops&#39; tracking errors: the closed loop of HIGH-w1 stopped at t = 0.0000 s before its "
                    "first sample (it never left its start)") != std::string::npos);
    CHECK(html.find("id=\"stopped\">Stopped runs</h2>") != std::string::npos);

    // Checks on a stopped run fail with its reason; the others are measured as usual.
    CHECK(log.find("check failed: up-end") != std::string::npos);
    CHECK(log.find("check failed: out-trip") != std::string::npos);
    CHECK(log.find("check failed: high-loop") != std::string::npos);
    CHECK(log.find("check failed: mass") == std::string::npos);
    CHECK(log.find("check failed: high-trip") == std::string::npos);
    CHECK(html.find("not measured: UP " + up_stop) != std::string::npos);
    CHECK(html.find("not measured: HIGH-w1 (closed loop) stopped at t = 0.0000 s: ") != std::string::npos);
    CHECK(html.find("not measured: OUT-w1 stopped at t = 0.0000 s: ") != std::string::npos);
    CHECK(std::regex_search(html, std::regex("claim-high-trip\">.*<td class=\"wlx\">[0-9.e+-]+ m or rad</td>.*class=\"pass\"")));
    // The integrators are compared in the full report only; UP stopped, so its deviation is not known.
    if (quick) {
      CHECK(log.find("check failed: up-euler") == std::string::npos);
      CHECK(html.find("<tr id=\"claim-up-euler\">") == std::string::npos);
    } else {
      CHECK(log.find("check failed: up-euler") != std::string::npos);
    }
  }

  // Bad input stays bad input: a name that is not a run of the folder, exit 2 and no report.
  write(dir / "claims.yaml", "sources: {spec: the test's specification}\nclaims:\n" +
                                 check("x", "{quantity: end_value, run: UPP, coordinate: z_C}", "{at_least: 1}"));
  const fs::path out = dir / "bad";
  CHECK(run(std::string(WLX_BINARY) + " --scenarios " + (dir / "runs").string() + " report --quick --claims " +
                (dir / "claims.yaml").string() + " --out " + out.string(),
            dir / "log") == 2);
  CHECK(slurp(dir / "log").find("'UPP' is not a run of model excavator (did you mean 'UP'?)") != std::string::npos);
  CHECK(!fs::exists(out / "index.html"));
}
