// wlx-gen as a user runs it: bad options and bad values exit 2 naming the option and the reason,
// and nothing is written; the emitted namespace and baked values are validated before emission.
#include "../support/run_wlx.hpp"

#include <doctest/doctest.h>

#include <filesystem>

namespace {

struct Case {
  const char* what;
  std::vector<std::string> args;  // after the model file and --out
  const char* message;
};

}  // namespace

TEST_CASE("wlx-gen: every bad option or value exits 2 with the reason, and writes nothing") {
  const std::filesystem::path out = wlx_test::work_dir() / "gen";
  const Case cases[] = {
      {"unknown parameter to bake", {"--bake", "lgD=1.6"}, "no parameter 'lgD' (did you mean 'legD'?)"},
      {"negative length baked", {"--bake", "legD=-1"}, "'legD' is a length, which must be positive"},
      {"zero mass baked", {"--bake", "m_M1=0"}, "'m_M1' is a mass, which must be positive"},
      {"negative gravity baked", {"--bake", "g=-9.81"}, "'g' is gravity, which must be non-negative"},
      {"not a number", {"--bake", "legD=abc"}, "the value of 'legD' is not a finite number"},
      {"infinite", {"--bake", "legD=inf"}, "the value of 'legD' is not a finite number"},
      {"no value", {"--bake", "legD"}, "expected NAME=VALUE"},
      {"code in the namespace", {"--namespace", "x { } int evil(){return 1;} namespace y"}, "is not a C++ qualified name"},
      {"namespace starting with a digit", {"--namespace", "1bad"}, "is not a C++ qualified name"},
      {"unknown option", {"--bogus"}, "--bogus"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.what);
    std::filesystem::remove_all(out);
    std::vector<std::string> args = {WLX_MODEL_FILE, "--out", out.string(), "--quiet"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const auto r = wlx_test::run(args);
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.rfind("wlx-gen: error: ", 0) == 0);
    CHECK(r.err.find(c.message) != std::string::npos);
    CHECK(!std::filesystem::exists(out));
  }
  const auto missing = wlx_test::run({"/nonexistent/model.yaml", "--out", out.string()});
  CHECK(missing.code == 2);
  CHECK(missing.err.find("cannot open the model file") != std::string::npos);
  const auto version = wlx_test::run({"--version"});
  CHECK(version.code == 0);
  CHECK(version.out.find('.') != std::string::npos);
}

TEST_CASE("wlx-gen: a baked parameter's field in params.hpp holds the baked value") {
  const std::filesystem::path out = wlx_test::work_dir() / "baked";
  const auto r = wlx_test::run({WLX_MODEL_FILE, "--out", out.string(), "--quiet", "--bake", "legD=1.75"});
  REQUIRE(r.code == 0);
  const std::string params = wlx_test::slurp(out / "wlx" / "gen" / "params.hpp");
  CHECK(params.find("double legD = 1.75;  // m: knee-to-foot length of a leg (baked:") != std::string::npos);
  CHECK(params.find("double legD = 1.5;") == std::string::npos);
}

TEST_CASE("wlx-gen: a header an earlier wlx-gen wrote and this one no longer produces is removed; others stay") {
  const std::filesystem::path out = wlx_test::work_dir() / "stale";
  std::filesystem::remove_all(out);
  REQUIRE(wlx_test::run({WLX_MODEL_FILE, "--out", out.string(), "--quiet"}).code == 0);
  const std::filesystem::path dir = out / "wlx" / "gen";
  const std::string kinematics = wlx_test::slurp(dir / "kinematics.hpp");
  // A dropped function's header: the banner of a real one under another name.
  wlx_test::write(dir / "dropped_function.hpp", kinematics);
  wlx_test::write(dir / "users_own.hpp", "// mine\n//\n// not generated\n");
  const auto r = wlx_test::run({WLX_MODEL_FILE, "--out", out.string()});
  REQUIRE(r.code == 0);
  CHECK(r.out.find("1 stale removed") != std::string::npos);
  CHECK(!std::filesystem::exists(dir / "dropped_function.hpp"));
  CHECK(std::filesystem::exists(dir / "users_own.hpp"));
  CHECK(wlx_test::slurp(dir / "kinematics.hpp") == kinematics);
}
