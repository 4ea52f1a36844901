// cli/viewer_export: the run files the viewer reads, the index, and their errors.
#include <doctest/doctest.h>

#include "viewer_export.hpp"

#include "../helpers/run_wlx.hpp"

#include <nlohmann/json.hpp>
#include <wlx/error.hpp>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

namespace fs = std::filesystem;
using wlx::cli::ViewerRun;
using wlx::cli::write_viewer_run;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The object a run file passes to wlxViewer.registerRun(...).
nlohmann::json registered(const fs::path& file, std::string_view call) {
  const std::string text = slurp(file);
  const auto open = text.find(call);
  REQUIRE(open != std::string::npos);
  const auto start = open + call.size();
  const auto end = text.rfind(");");
  REQUIRE(end != std::string::npos);
  return nlohmann::json::parse(text.substr(start, end - start));
}

constexpr std::array<std::string_view, 2> kNames{"a", "b_deg"};

fs::path fresh(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("wlx-viewer-export-" + name);
  fs::remove_all(dir);
  return dir;
}

ViewerRun run_with(std::string csv) {
  ViewerRun run;
  run.id = "R-1+";
  run.model = "toy";
  run.description = "a \"quoted\" run";
  run.trajectory_csv = std::move(csv);
  return run;
}

}  // namespace

TEST_CASE("viewer run: columns by name, the varying rates plotted, thinned to max_samples with the last kept") {
  const fs::path dir = fresh("basic");
  std::string csv = "t,a,b_deg,a_dot,b_deg_dot,extra\n";
  for (int i = 0; i <= 100; ++i) csv += std::to_string(i * 0.01) + "," + std::to_string(i) + ",0.5,1," + std::to_string(i) + ",7\n";
  write_viewer_run(dir, run_with(csv), kNames, 11);
  const auto run = registered(dir / "runs" / "R-1+.js", "wlxViewer.registerRun(");
  CHECK(run["format"] == "wlx-viewer-run 1");
  CHECK(run["id"] == "R-1+");
  CHECK(run["model"] == "toy");
  CHECK(run["description"] == "a \"quoted\" run");
  CHECK(run["samples"] == 11);
  // a_dot is constant (commanded), b_deg_dot varies (dependent): only the latter is plotted.
  CHECK(run["plot"]["columns"] == nlohmann::json::array({"b_deg_dot"}));
  CHECK(run["plot"]["title"] == "dependent rates");
  CHECK(run["columns"]["t"].size() == 11);
  CHECK(run["columns"]["a"].front() == 0.0);
  CHECK(run["columns"]["a"].back() == 100.0);  // the last sample is kept
  CHECK(run["columns"]["a"][5] == 50.0);      // evenly thinned
  CHECK_FALSE(run["columns"].contains("extra"));
  const auto index = registered(dir / "runs" / "index.js", "wlxViewer.registerIndex(");
  REQUIRE(index.size() == 1);
  CHECK(index[0]["id"] == "R-1+");

  // Torques are plotted when present; a second run is added to the index, a rewrite replaces.
  ViewerRun dynamics = run_with("t,a,b_deg,tau_x,tau_y\n0,1,2,3,4\n1,1,2,5,6\n");
  dynamics.id = "D";
  write_viewer_run(dir, dynamics, kNames);
  const auto d = registered(dir / "runs" / "D.js", "wlxViewer.registerRun(");
  CHECK(d["plot"]["columns"] == nlohmann::json::array({"tau_x", "tau_y"}));
  CHECK(d["plot"]["unit"] == "N m");
  write_viewer_run(dir, run_with(csv), kNames);
  const auto index2 = registered(dir / "runs" / "index.js", "wlxViewer.registerIndex(");
  REQUIRE(index2.size() == 2);
  CHECK(index2[0]["id"] == "R-1+");
  CHECK(index2[1]["id"] == "D");
  // No temporary left behind.
  for (const auto& e : fs::directory_iterator(dir / "runs")) CHECK(e.path().extension() == ".js");
  fs::remove_all(dir);
}

TEST_CASE("viewer run: errors name the run, the column or row, and the reason") {
  const fs::path dir = fresh("errors");
  const auto message = [&](ViewerRun run) {
    try {
      write_viewer_run(dir, run, kNames);
    } catch (const wlx::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(message(run_with("t,a\n0,1\n")) == "run R-1+: the trajectory CSV has no column 'b_deg'");
  CHECK(message(run_with("t,a,b_dg\n0,1,2\n")) == "run R-1+: the trajectory CSV has no column 'b_deg' (did you mean 'b_dg'?)");
  CHECK(message(run_with("t,a,b_deg\n0,1,nan\n")) ==
        "run R-1+: row 2, column 'b_deg' of the trajectory CSV: 'nan' is not a finite number");
  CHECK(message(run_with("t,a,b_deg\n0,1\n")) == "run R-1+: row 2 of the trajectory CSV has 2 values for 3 columns");
  CHECK(message(run_with("t,a,b_deg\n")) == "run R-1+: the trajectory CSV has no samples");
  ViewerRun bad_id = run_with("t,a,b_deg\n0,1,2\n");
  bad_id.id = "../x";
  CHECK(message(bad_id).starts_with("run id: '../x' must be 1 to 64 of"));
  ViewerRun bad_plot = run_with("t,a,b_deg\n0,1,2\n");
  bad_plot.plot_columns = {"tau_z"};
  CHECK(message(bad_plot) == "run R-1+: the trajectory CSV has no column 'tau_z'");
  CHECK_FALSE(fs::exists(dir / "runs" / "R-1+.js"));  // nothing written for a bad run
  fs::remove_all(dir);
}

TEST_CASE("copy_viewer_files: a missing build says how to get one") {
  const fs::path source = fresh("source");
  fs::create_directories(source);
  std::ofstream(source / "viewer.html") << "<html></html>";
  try {
    wlx::cli::copy_viewer_files(fresh("copy"), source);
    FAIL("no error");
  } catch (const wlx::Error& e) {
    CHECK(std::string(e.what()).find("viewer.js is missing") != std::string::npos);
    CHECK(std::string(e.what()).find("WLX_VIEWER_DIR") != std::string::npos);
  }
  std::ofstream(source / "viewer.js") << "//";
  fs::create_directories(source / "wasm");
  std::ofstream(source / "wasm" / "wlx_toy.js") << "//";
  const fs::path copy = fresh("copy");
  wlx::cli::copy_viewer_files(copy, source);
  CHECK(slurp(copy / "viewer.html") == "<html></html>");
  CHECK(fs::exists(copy / "wasm" / "wlx_toy.js"));
  CHECK(registered(copy / "runs" / "index.js", "wlxViewer.registerIndex(").empty());
  fs::remove_all(source);
  fs::remove_all(copy);
}

TEST_CASE("wlx viewer: bad requests exit 2 naming the option or run") {
  const fs::path out = wlx_test::work_dir() / "viewer";
  auto r = wlx_test::run({"viewer", "--out", out.string(), "NH-9"});
  CHECK(r.code == 2);
  CHECK(r.err.find("did you mean 'NH-1'") != std::string::npos);
  wlx_test::write(wlx_test::work_dir() / "params.json", R"({"legD": 1.6})");
  r = wlx_test::run({"viewer", "--out", out.string(), "--params", (wlx_test::work_dir() / "params.json").string()});
  CHECK(r.code == 2);
  CHECK(r.err.find("wlx: error: --params: the viewer draws the model with its default parameters") == 0);
  // A viewer that was not built: the message says where it looked and how to build it.
  ::setenv("WLX_VIEWER_DIR", (wlx_test::work_dir() / "no-viewer").c_str(), 1);
  r = wlx_test::run({"viewer", "--out", out.string()});
  ::unsetenv("WLX_VIEWER_DIR");
  CHECK(r.code == 2);
  CHECK(r.err.find("viewer.html is missing") != std::string::npos);
  CHECK(r.err.find("WLX_BUILD_VIEWER") != std::string::npos);
}

TEST_CASE("viewer run: hostile descriptions and column names stay inside their JavaScript strings") {
  const fs::path dir = fresh("hostile");
  ViewerRun run = run_with("t,a,b_deg,x\"y</script>\n0,1,2,3\n1,1,2,3\n");
  run.description = "</script><script>alert(1)</script> \" \\ \n \xe2\x80\xa8 \xff";
  run.plot_columns = {"x\"y</script>"};
  write_viewer_run(dir, run, kNames);
  for (const fs::path& file : {dir / "runs" / "R-1+.js", dir / "runs" / "index.js"}) {
    const std::string text = slurp(file);
    CAPTURE(file);
    // Nothing a browser could take for markup or a line end inside a literal; all ASCII.
    CHECK(text.find("</script") == std::string::npos);
    CHECK(text.find("<script") == std::string::npos);
    for (const char c : text) CHECK(static_cast<unsigned char>(c) < 0x80);
  }
  // And the data still reads back as written (the ill-formed byte as U+FFFD).
  const nlohmann::json head = registered(dir / "runs" / "R-1+.js", "wlxViewer.registerRun(");
  CHECK(head["description"] == "</script><script>alert(1)</script> \" \\ \n \xe2\x80\xa8 \xef\xbf\xbd");
  CHECK(head["columns"].contains("x\"y</script>"));
  fs::remove_all(dir);
}

TEST_CASE("viewer run: a run index that is not a regular file (a link to /dev/zero) is refused, not read without end") {
  const fs::path dir = fresh("zero-index");
  fs::create_directories(dir / "runs");
  fs::create_symlink("/dev/zero", dir / "runs" / "index.js");
  CHECK_THROWS_WITH_AS(write_viewer_run(dir, run_with("t,a,b_deg\n0,1,2\n1,1,2\n"), kNames), doctest::Contains("is a device, not a regular file"),
                       wlx::Error);
  fs::remove_all(dir);
}

TEST_CASE("wlx viewer: a run driven by torques is played like any other, its torques plotted") {
  const fs::path out = wlx_test::work_dir() / "viewer-torques";
  const fs::path scenario = wlx_test::work_dir() / "fd.json";
  wlx_test::write(scenario, R"({"id": "FD-T", "description": "ID-1's torques fed back", "rates": {"x_C": 3.0},
                               "duration": 0.05, "torques": {"run": "ID-1"}})");
  // A stand-in viewer folder: the run's file is what is checked here, and it must be written in
  // every build, also one without the viewer (the sanitized tree).
  const fs::path source = fresh("stand-in-viewer");
  fs::create_directories(source / "wasm");
  std::ofstream(source / "viewer.html") << "<html></html>";
  std::ofstream(source / "viewer.js") << "//";
  std::ofstream(source / "wasm" / "wlx_excavator.js") << "//";
  ::setenv("WLX_VIEWER_DIR", source.c_str(), 1);
  const auto r = wlx_test::run({"viewer", "--out", out.string(), scenario.string()});
  ::unsetenv("WLX_VIEWER_DIR");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto run = registered(out / "runs" / "FD-T.js", "wlxViewer.registerRun(");
  CHECK(run["samples"] == 51);
  CHECK(run["plot"]["title"] == "joint torques");
  CHECK(run["plot"]["columns"].size() == 8);
  CHECK(run["columns"]["x_C"].size() == 51);
  CHECK(run["columns"]["x_C"].back().get<double>() > run["columns"]["x_C"].front().get<double>() + 0.1);  // it drove
}
