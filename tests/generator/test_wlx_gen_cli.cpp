// wlx-gen as a user runs it: bad options and bad values exit 2 naming the option and the reason,
// and nothing is written; the emitted namespace and baked values are validated before emission.
#include "../helpers/run_wlx.hpp"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <fstream>
#include <thread>
#include <cerrno>
#include <cstring>
#include <map>
#include <sstream>

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
      {"the same parameter baked twice", {"--bake", "legD=1.6", "--bake", "legD=1.7"}, "--bake legD=1.7: 'legD' is given twice (first as --bake legD=1.6)"},
      {"code in the namespace", {"--namespace", "x { } int evil(){return 1;} namespace y"}, "is not a C++ qualified name"},
      {"namespace starting with a digit", {"--namespace", "1bad"}, "is not a C++ qualified name"},
      {"namespace ending in ::", {"--namespace", "wlx::"}, "is not a C++ qualified name"},
      {"namespace starting with ::", {"--namespace", "::wlx"}, "is not a C++ qualified name"},
      {"namespace with an empty part", {"--namespace", "wlx::::mine"}, "is not a C++ qualified name"},
      {"namespace with a single colon", {"--namespace", "wlx:mine"}, "is not a C++ qualified name"},
      {"namespace with a digit after ::", {"--namespace", "wlx::2nd"}, "is not a C++ qualified name"},
      {"unknown option", {"--bogus"}, "--bogus"},
      {"another model's name expected (wlx_generate's NAME, or the file's name)", {"--expect-model", "digger"},
       "excavator.yaml: `model: excavator`, where the build expects the model 'digger'"},
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

TEST_CASE("wlx-gen --data-at-run-time: files that differ only in numbers give byte-identical headers and one code key; model.json holds the numbers") {
  const std::filesystem::path dir = wlx_test::work_dir() / "data-at-run-time";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::string text = wlx_test::slurp(WLX_MODEL_FILE);
  const auto replace = [](std::string t, const std::string& from, const std::string& to) {
    const auto at = t.find(from);
    REQUIRE_MESSAGE(at != std::string::npos, from);
    return t.replace(at, from.size(), to);
  };
  wlx_test::write(dir / "a.yaml", text);
  // Every kind of number: a parameter's value, the nominal state, a limb's start, a sweep, the
  // weights, torque limits and friction.
  text = replace(text, "{name: legD, value: 1.5,", "{name: legD, value: 1.6,");
  text = replace(text, "  z_C: 2.0\n", "  z_C: 1.95\n");
  text = replace(text, "    joints: [psi_<side>2, psi_<side>3, psi_<side>4]\n",
                 "    joints: [psi_<side>2, psi_<side>3, psi_<side>4]\n    start: {psi_<side>3: -0.3}\n");
  text = replace(text, "from: -0.50, to: 3.50, step: 0.01", "from: -0.40, to: 3.40, step: 0.02");
  text = replace(text, "  weights: [0.01, 100, 1,", "  torque_limits: [9, 9, 9, 9, 9, 9, 9, 9]\n  weights: [0.03, 100, 1,");
  text += "contacts:\n  friction: {feet: 0.9, wheels: 0.7}\n";
  wlx_test::write(dir / "b.yaml", text);
  for (const char* name : {"a", "b"}) {
    const auto r = wlx_test::run({(dir / (std::string(name) + ".yaml")).string(), "--data-at-run-time", "--out",
                                  (dir / name).string(), "--quiet"});
    CAPTURE(r.err);
    REQUIRE(r.code == 0);
  }
  int compared = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "a" / "wlx" / "gen")) {
    if (entry.path().filename() == "model.json") continue;
    CAPTURE(entry.path().filename().string());
    CHECK(wlx_test::slurp(entry.path()) == wlx_test::slurp(dir / "b" / "wlx" / "gen" / entry.path().filename()));
    ++compared;
  }
  CHECK(compared >= 10);
  CHECK(!std::filesystem::exists(dir / "a" / "wlx" / "gen" / "settings.hpp"));  // the numbers are not compiled in
  const std::string params = wlx_test::slurp(dir / "a" / "wlx" / "gen" / "params.hpp");
  CHECK(params.find("double legD = detail::param_defaults()[3];") != std::string::npos);
  const nlohmann::json a = nlohmann::json::parse(wlx_test::slurp(dir / "a" / "wlx" / "gen" / "model.json"));
  const nlohmann::json b = nlohmann::json::parse(wlx_test::slurp(dir / "b" / "wlx" / "gen" / "model.json"));
  CHECK(a["code_key"] == b["code_key"]);
  CHECK(a["data_at_run_time"] == true);
  // The numbers are in the description, as given.
  const auto value_of = [](const nlohmann::json& d, const std::string& parameter) {
    for (const auto& p : d["parameters"])
      if (p["name"] == parameter) return p["value"].get<double>();
    return -1.0;
  };
  CHECK(value_of(a, "legD") == 1.5);
  CHECK(value_of(b, "legD") == 1.6);
  CHECK(b["settings"]["nominal"]["z_C"] == 1.95);
  CHECK(b["settings"]["dependent_start"]["psi_l3"] == -0.3);
  CHECK(b["settings"]["dependent_start"]["psi_r3"] == -0.3);
  CHECK(a["settings"]["dependent_start"]["psi_l3"] == 0.0);
  CHECK(b["settings"]["torque_limits"] == nlohmann::json::array({9, 9, 9, 9, 9, 9, 9, 9}));
  CHECK(a["settings"]["torque_limits"].is_null());
  CHECK(b["settings"]["weights"][0] == 0.03);
  for (const auto& sweep : b["settings"]["ik_sweeps"])
    if (sweep["id"] == "IK-L3") CHECK((sweep["from"] == -0.4 && sweep["step"] == 0.02));
  for (std::size_t c = 0; c < b["contacts"].size(); ++c)
    CHECK(b["settings"]["friction"][c] == (b["contacts"][c]["kind"] == "wheel" ? 0.7 : 0.9));
  // Without the option the numbers are compiled in: settings.hpp, and another code key.
  const auto compiled = wlx_test::run({(dir / "b.yaml").string(), "--out", (dir / "b-compiled").string(), "--quiet"});
  REQUIRE(compiled.code == 0);
  CHECK(wlx_test::slurp(dir / "b-compiled" / "wlx" / "gen" / "settings.hpp").find("kTorqueLimits{{9.0, 9.0,") != std::string::npos);
  CHECK(nlohmann::json::parse(wlx_test::slurp(dir / "b-compiled" / "wlx" / "gen" / "model.json"))["code_key"] != b["code_key"]);
  // A change of structure is another code key: a parameter's kind.
  wlx_test::write(dir / "c.yaml", replace(text, "{name: cyd, value: 3.0, unit: m, kind: length,", "{name: cyd, value: 3.0, unit: m, kind: offset,"));
  const auto c = wlx_test::run({(dir / "c.yaml").string(), "--data-at-run-time", "--describe"});
  REQUIRE(c.code == 0);
  CHECK(nlohmann::json::parse(c.out)["code_key"] != b["code_key"]);
  // --describe prints what --out writes as model.json, and writes nothing.
  const auto described = wlx_test::run({(dir / "b.yaml").string(), "--data-at-run-time", "--describe"});
  REQUIRE(described.code == 0);
  CHECK(described.out == wlx_test::slurp(dir / "b" / "wlx" / "gen" / "model.json"));
  const auto both = wlx_test::run({(dir / "b.yaml").string(), "--describe", "--out", (dir / "d").string()});
  CHECK(both.code == 2);
  CHECK(both.err.find("--describe writes nothing") != std::string::npos);
  CHECK(!std::filesystem::exists(dir / "d"));
  const auto baked = wlx_test::run({(dir / "b.yaml").string(), "--data-at-run-time", "--bake-defaults", "--out", (dir / "e").string()});
  CHECK(baked.code == 2);
  CHECK(baked.err.find("--data-at-run-time reads every parameter's value at run time") != std::string::npos);
}

#ifdef WLX_HAVE_URDF_TESTS
TEST_CASE("wlx-gen --describe: quoted keys and a URDF's geometry are what wlx-gen parsed: the name as written, and a moved knee is another description") {
  // A model file whose keys are quoted (`"model": ...`, `urdf: "..."`): whatever reads the
  // description (the plugin cache's key) gets the name and the URDF that wlx-gen read.
  const std::filesystem::path dir = wlx_test::work_dir() / "quoted-keys";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::string yaml = wlx_test::slurp(WLX_SOURCE_DIR "/models/wheeled_quadruped.yaml");
  const auto replace = [](std::string t, const std::string& from, const std::string& to) {
    const auto at = t.find(from);
    REQUIRE_MESSAGE(at != std::string::npos, from);
    return t.replace(at, from.size(), to);
  };
  yaml = replace(yaml, "\nmodel: wheeled_quadruped\n", "\n\"model\": \"my_quadruped\"\n");
  yaml = replace(yaml, "\nurdf: wheeled_quadruped.urdf\n", "\nurdf: \"robot.urdf\"\n");
  wlx_test::write(dir / "robot.yaml", yaml);
  const std::string urdf = wlx_test::slurp(WLX_SOURCE_DIR "/models/wheeled_quadruped.urdf");
  wlx_test::write(dir / "robot.urdf", urdf);
  const auto before = wlx_test::run({(dir / "robot.yaml").string(), "--data-at-run-time", "--describe"});
  CAPTURE(before.err);
  REQUIRE(before.code == 0);
  const nlohmann::json a = nlohmann::json::parse(before.out);
  CHECK(a["model"] == "my_quadruped");
  // The left front knee 10 cm further down its thigh. The URDF's offsets are imported as parameters,
  // so the move is data: the same code (one plugin), and the description carries the new length,
  // which the loaded plugin computes with (never the old geometry from a stale cache).
  wlx_test::write(dir / "robot.urdf", replace(urdf, "<origin xyz=\"0 0.1 -0.285\" rpy=\"0 0 0\"/>", "<origin xyz=\"0 0.1 -0.385\" rpy=\"0 0 0\"/>"));
  const auto after = wlx_test::run({(dir / "robot.yaml").string(), "--data-at-run-time", "--describe"});
  REQUIRE(after.code == 0);
  const nlohmann::json b = nlohmann::json::parse(after.out);
  CHECK(b["model"] == "my_quadruped");
  CHECK(a["code_key"] == b["code_key"]);
  int moved = 0;
  REQUIRE(a["parameters"].size() == b["parameters"].size());
  for (std::size_t k = 0; k < a["parameters"].size(); ++k)
    if (a["parameters"][k]["value"] != b["parameters"][k]["value"]) {
      CAPTURE(a["parameters"][k]["name"].get<std::string>());
      CHECK(a["parameters"][k]["value"] == -0.285);
      CHECK(b["parameters"][k]["value"] == -0.385);
      ++moved;
    }
  CHECK(moved >= 1);
}
TEST_CASE("wlx-gen: joint limits from the URDF and a `limits` section, field by field; a default branch; both are data, in model.json") {
  const std::filesystem::path dir = wlx_test::work_dir() / "limits";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string yaml = wlx_test::slurp(WLX_SOURCE_DIR "/models/wheeled_quadruped.yaml");
  wlx_test::write(dir / "wheeled_quadruped.urdf", wlx_test::slurp(WLX_SOURCE_DIR "/models/wheeled_quadruped.urdf"));
  wlx_test::write(dir / "robot.yaml", yaml);
  const auto plain = wlx_test::run({(dir / "robot.yaml").string(), "--data-at-run-time", "--describe"});
  REQUIRE(plain.code == 0);
  const nlohmann::json a = nlohmann::json::parse(plain.out);
  // The URDF's <limit>s: ranges and speeds of the revolute joints (the wheels' continuous joints are
  // spins, no coordinates), and every actuator's effort as its torque limit (dynamics gives none).
  std::map<std::string, nlohmann::json> limits;
  for (const auto& l : a["settings"]["limits"]) limits[l["coordinate"].get<std::string>()] = l;
  REQUIRE(limits.size() == 12);
  CHECK(limits["haa_rf"]["lower"] == -0.72);
  CHECK(limits["haa_rf"]["upper"] == 0.49);
  CHECK(limits["kfe_lh"]["lower"] == -2.8);
  CHECK(limits["kfe_lh"]["upper"] == -0.4);
  CHECK(limits["kfe_lh"]["velocity"] == 7.5);
  CHECK(limits["kfe_lh"]["effort"] == 80.0);
  const std::vector<double> efforts{80, 80, 80, 80, 80, 80, 80, 80, 80, 80, 80, 80, 40, 40, 40, 40};
  CHECK(a["settings"]["torque_limits"].get<std::vector<double>>() == efforts);
  CHECK(a["settings"]["branches"].empty());
  // The file's own `limits` replace the URDF's field by field (the knees' range; their effort and
  // speed stay), and a limb's default branch: data both, so the code key stays.
  std::string edited = yaml;
  const std::string start = "    start: {haa_<leg>: 0, hfe_<leg>: 0.5, kfe_<leg>: -1.0}\n";
  REQUIRE(edited.find(start) != std::string::npos);
  edited.replace(edited.find(start), start.size(), start + "    branch: 2\n");
  edited += "\nlimits:\n  - for: leg\n    items:\n      - {joint: kfe_<leg>, lower: -2.5, upper: -0.5}\n";
  const std::string x_sweep = "step: 0.005, limb: leg_<leg>}";
  REQUIRE(edited.find(x_sweep) != std::string::npos);
  edited.replace(edited.find(x_sweep), x_sweep.size(), "step: 0.005, limb: leg_<leg>, branch: 1}");
  wlx_test::write(dir / "robot.yaml", edited);
  const auto limited = wlx_test::run({(dir / "robot.yaml").string(), "--data-at-run-time", "--describe"});
  CAPTURE(limited.err);
  REQUIRE(limited.code == 0);
  const nlohmann::json b = nlohmann::json::parse(limited.out);
  CHECK(a["code_key"] == b["code_key"]);
  limits.clear();
  for (const auto& l : b["settings"]["limits"]) limits[l["coordinate"].get<std::string>()] = l;
  CHECK(limits["kfe_rf"]["lower"] == -2.5);
  CHECK(limits["kfe_rf"]["upper"] == -0.5);
  CHECK(limits["kfe_rf"]["effort"] == 80.0);
  CHECK(limits["hfe_rf"]["lower"] == -9.42);
  CHECK(b["settings"]["branches"]["leg_rh"] == 2);
  for (const auto& sweep : b["settings"]["ik_sweeps"]) {
    CAPTURE(sweep.dump());
    const bool along_x = sweep["id"].get<std::string>().find("-x") != std::string::npos;
    CHECK(sweep["branch"] == (along_x ? nlohmann::json(1) : nlohmann::json(nullptr)));
  }
  // Mistakes, named where they are: a branch the limb's closed form does not have, an empty range,
  // half a range, an effort that is no effort, a joint given twice, a name that is no coordinate.
  const std::pair<std::string, std::string> cases[] = {
      {"    branch: 4\n", "has 4 branches (0 to 3), not 4"},
      {"    branch: 1.5\n", "a branch is a whole number from 0, got 1.5"},
  };
  for (const auto& c : cases) {
    const std::string& line = c.first;
    const std::string& message = c.second;
    std::string bad = yaml;
    bad.replace(bad.find(start), start.size(), start + line);
    wlx_test::write(dir / "robot.yaml", bad);
    const auto r = wlx_test::run({(dir / "robot.yaml").string(), "--describe"});
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("robot.yaml:") != std::string::npos);
    CHECK(r.err.find(message) != std::string::npos);
  }
  const std::pair<std::string, std::string> entries[] = {
      {"{joint: kfe_lf, lower: -0.4, upper: -0.4}", "lower (-0.4) must be below upper (-0.4)"},
      {"{joint: kfe_lf, lower: -0.4}", "a range needs both `lower` and `upper`"},
      {"{joint: kfe_lf, effort: -3}", "must be in (0, 1e9], got -3"},
      {"{joint: kfe_lf, lower: -1e7, upper: 0}", "must be within [-1e6, 1e6], got -10000000"},
      {"{joint: kfe_lf, velocity: 2}\n  - {joint: kfe_lf, effort: 2}", "'kfe_lf' has limits already: give them once"},
      {"{joint: knee_lf, velocity: 2}", "knee_lf"},
  };
  for (const auto& e : entries) {
    // Not a structured binding: clang 14 cannot capture one in CAPTURE's lambda.
    const std::string& entry = e.first;
    const std::string& message = e.second;
    wlx_test::write(dir / "robot.yaml", yaml + "\nlimits:\n  - " + entry + "\n");
    const auto r = wlx_test::run({(dir / "robot.yaml").string(), "--describe"});
    CAPTURE(entry);
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("robot.yaml:") != std::string::npos);
    CHECK(r.err.find("limits") != std::string::npos);
    CHECK(r.err.find(message) != std::string::npos);
  }
  // A URDF range upside down is the URDF's mistake, named at its line.
  const std::string urdf = wlx_test::slurp(WLX_SOURCE_DIR "/models/wheeled_quadruped.urdf");
  const std::string range = "<limit lower=\"-0.72\" upper=\"0.49\"";
  REQUIRE(urdf.find(range) != std::string::npos);
  wlx_test::write(dir / "wheeled_quadruped.urdf", std::string(urdf).replace(urdf.find(range), range.size(), "<limit lower=\"0.72\" upper=\"0.49\""));
  wlx_test::write(dir / "robot.yaml", yaml);
  const auto r = wlx_test::run({(dir / "robot.yaml").string(), "--describe"});
  CHECK(r.code == 2);
  CHECK(r.err.find("wheeled_quadruped.urdf:84: joint 'haa_lf' limit: lower=\"0.72\" is above upper=\"0.49\"") != std::string::npos);
}

#endif

TEST_CASE("wlx-gen: a baked value that makes an output infinite at the nominal state exits 2 naming the function and output") {
  const std::filesystem::path dir = wlx_test::work_dir() / "baked-pole", out = dir / "out";
  std::filesystem::create_directories(dir);
  wlx_test::write(dir / "pole.yaml", "model: pole\n"
                                     "parameters:\n"
                                     "  - {name: a, value: 1, unit: m, kind: length, meaning: a length}\n"
                                     "  - {name: b, value: 2, unit: m, kind: length, meaning: another}\n"
                                     "coordinates:\n  inputs:\n    - {name: q, unit: rad, meaning: a joint}\n"
                                     "frames:\n  - {name: base, parent: K0, chain: [rz: q, translate: [1/(a-b), 0, 0]]}\n");
  REQUIRE(wlx_test::run({(dir / "pole.yaml").string(), "--out", out.string(), "--quiet"}).code == 0);  // a - b = -1
  std::filesystem::remove_all(out);
  // b = 1 = a: the generated kinematics would divide by zero in every call at these parameters.
  const auto r = wlx_test::run({(dir / "pole.yaml").string(), "--out", out.string(), "--quiet", "--bake", "b=1"});
  CAPTURE(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.rfind("wlx-gen: error: kinematics(): ", 0) == 0);
  CHECK(r.err.find(" at the default and baked parameters and the nominal state (division by zero: 1/(") != std::string::npos);
  CHECK(!std::filesystem::exists(out));
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

// ---- hostile model files (issue 26) ----

namespace {

std::string arm_text() { return wlx_test::slurp(WLX_ARM_MODEL_FILE); }

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE_MESSAGE(at != std::string::npos, "anchor not in arm.yaml: " << from);
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("wlx-gen: text from the model file cannot add code to the headers: they compile and hold the text as written") {
  // A body meaning that closes its string and the array, a parameter meaning that ends a block
  // comment and forms a trigraph, a description with quotes, and a file name with a line break
  // and a #define (it is in every banner).
  const std::string meaning = R"(x", "y"}}; int injected = 1; //)";
  const std::string param_meaning = R"(*/ #define evil 1 /* ??/)";
  std::string text = replaced(arm_text(), "{name: upper, frame: upper,", "{name: upper, meaning: '" + meaning + "', frame: upper,");
  text = replaced(text, "meaning: upper arm length}", "meaning: '" + param_meaning + "'}");
  text = replaced(text, "description: a fixed arm of three revolute and one prismatic joint (no closure, no wheels)", R"(description: 'say "hi" \ there')");
  const std::filesystem::path dir = wlx_test::work_dir() / "hostile-text";
  std::filesystem::create_directories(dir);
  const std::filesystem::path model = dir / "arm\n#define upper 0\n.yaml";
  wlx_test::write(model, text);
  const std::filesystem::path out = dir / "out";
  const auto r = wlx_test::run({model.string(), "--out", out.string(), "--quiet"});
  CAPTURE(r.err);
  REQUIRE(r.code == 2);  // the backslash in the description: text is one plain line
  CHECK(r.err.find("description: 'say \"hi\" \\ there' has a backslash") != std::string::npos);
  // The message shows the file name's line breaks escaped: one line on the terminal.
  CHECK(r.err.find("error: arm\\x0a#define upper 0\\x0a.yaml:4:14: description") != std::string::npos);
  text = replaced(text, R"(description: 'say "hi" \ there')", R"(description: 'say "hi" there')");
  wlx_test::write(model, text);
  const auto ok = wlx_test::run({model.string(), "--out", out.string(), "--quiet"});
  CAPTURE(ok.err);
  REQUIRE(ok.code == 0);
  const std::string types = wlx_test::slurp(out / "wlx" / "gen" / "types.hpp");
  CHECK(types.find("from model \"arm\" (arm\\x0a#define upper 0\\x0a.yaml, fingerprint") != std::string::npos);
  // The compiler is the judge: the headers compile (with trigraphs on too), nothing was defined,
  // and the strings are the file's text byte for byte.
  const std::filesystem::path check = dir / "check.cpp";
  wlx_test::write(check, "#include <wlx/gen/types.hpp>\n#include <wlx/gen/params.hpp>\n"
                         "#ifdef evil\n#error a comment let a #define through\n#endif\n"
                         "using namespace wlx::arm::gen;\n"
                         "static_assert(kBodyMeanings[body::upper] == std::string_view(R\"~(" + meaning + ")~\"));\n"
                         "static_assert(kParamInfo[1].meaning == std::string_view(R\"~(" + param_meaning + ")~\"));\n"
                         "static_assert(kModelDescription == std::string_view(R\"~(say \"hi\" there)~\"));\n"
                         "int main() { return 0; }\n");
  for (const char* standard : {"-std=c++17 -trigraphs", "-std=c++17"}) {
    const std::string compile = std::string(WLX_TEST_CXX) + " " + standard + " -fsyntax-only -Wall -Werror -isystem " + WLX_EIGEN_INCLUDE +
                                " -I'" + out.string() + "' '" + check.string() + "' 2>&1";
    INFO(compile);
    CHECK(std::system(compile.c_str()) == 0);
  }
}

TEST_CASE("wlx-gen: names that are keywords or macros of the compiler or the headers exit 2 before anything is written") {
  const std::filesystem::path dir = wlx_test::work_dir() / "reserved";
  std::filesystem::create_directories(dir);
  const std::filesystem::path model = dir / "arm.yaml", out = dir / "out";
  // Each would compile into a header that does not compile (unix and linux are 1 under GNU
  // modes; M_PI, EOF, errno are macros of <cmath> and the C library).
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"model: arm", "model: unix"},
      {"{name: column, parent: K0", "{name: linux, parent: K0"},
      {"{name: upper, frame: upper,", "{name: M_PI, frame: upper,"},
      {"{name: tip, parent: fore", "{name: EOF, parent: fore"},
      {"{name: turn, unit: rad", "{name: errno, unit: rad"},
      {"{name: forearm, value", "{name: std, value"},
      {"{name: fore, frame: fore", "{name: Eigen, frame: fore"},
      {"model: arm", "model: gen"},
      // The generated functions' own names: the template parameter, an output, a sum's prefix.
      {"{name: forearm, value", "{name: Scalar, value"},
      {"{name: elbow_y, value", "{name: Q_gravity, value"},
      {"{name: turn, unit: rad", "{name: kane_R_0_1_1, unit: rad"},
      {"{name: lift, unit: rad", "{name: ik_residual, unit: rad"},
  };
  for (const auto& [from, to] : cases) {
    const auto shown = to;  // a copy: clang 14 cannot capture a structured binding
    CAPTURE(shown);
    std::filesystem::remove_all(out);
    wlx_test::write(model, replaced(arm_text(), from, to));
    const auto r = wlx_test::run({model.string(), "--out", out.string(), "--quiet"});
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("cannot be") != std::string::npos);
    CHECK(r.err.rfind("wlx-gen: error: arm.yaml:", 0) == 0);
    CHECK(!std::filesystem::exists(out));
  }
  for (const char* ns : {"std", "mine::unix", "Eigen::x", "M_PI", "a::int"}) {
    CAPTURE(ns);
    const auto r = wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet", "--namespace", ns});
    CHECK(r.code == 2);
    CHECK(r.err.find("--namespace: '") != std::string::npos);
    CHECK(r.err.find("cannot be used") != std::string::npos);
  }
  CHECK(wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet", "--namespace", "mine::robot"}).code == 0);
}

TEST_CASE("wlx-gen: a model file that never ends or is not a file exits 2 at once, naming it") {
  const std::filesystem::path dir = wlx_test::work_dir() / "not-a-file";
  std::filesystem::create_directories(dir);
  const std::filesystem::path fifo = dir / "model.fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"/dev/zero", "is a device, not a regular file"},
      {fifo.string(), "is a pipe (FIFO), not a regular file"},  // no writer: must not wait for one
      {dir.string(), "is a folder"},
  };
  for (const auto& [path, reason] : cases) {
    const auto shown = path;  // a copy: clang 14 cannot capture a structured binding
    CAPTURE(shown);
    const auto r = wlx_test::run({path, "--out", (dir / "out").string(), "--quiet"});
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(reason) != std::string::npos);
  }
  // 10^5 frames in a cycle (the file that overflowed the stack) is beyond the size bound.
  std::string frames;
  for (int k = 0; k < 100000; ++k) frames += "  - {name: f" + std::to_string(k) + ", parent: f" + std::to_string((k + 1) % 100000) + ", chain: []}\n";
  wlx_test::write(dir / "cycle.yaml", replaced(arm_text(), "frames:\n", "frames:\n" + frames));
  const auto r = wlx_test::run({(dir / "cycle.yaml").string(), "--out", (dir / "out").string(), "--quiet"});
  CHECK(r.signal == 0);
  CHECK(r.code == 2);
  CHECK(r.err.find("more than the limit of 1048576 bytes") != std::string::npos);
}

// ---- wlx-gen's writes (issue 26) ----

namespace {

// The files under `dir` (relative path -> content).
std::map<std::string, std::string> tree(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.is_regular_file() || e.is_symlink()) files[std::filesystem::relative(e.path(), dir).string()] = wlx_test::slurp(e.path());
  return files;
}

}  // namespace

TEST_CASE("wlx-gen: a planted symlink is never written through; a link under a header's name is replaced, its target untouched") {
  const std::filesystem::path dir = wlx_test::work_dir() / "symlinks", out = dir / "out", gen = out / "wlx" / "gen";
  std::filesystem::create_directories(gen);
  wlx_test::write(dir / "victim", "precious");
  wlx_test::write(dir / "victim2", "precious too");
  // The fixed temporary name an earlier wlx-gen used, and a header's own name.
  std::filesystem::create_symlink(dir / "victim", gen / "types.hpp.tmp");
  std::filesystem::create_symlink(dir / "victim2", gen / "params.hpp");
  const auto r = wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet"});
  CAPTURE(r.err);
  REQUIRE(r.code == 0);
  CHECK(wlx_test::slurp(dir / "victim") == "precious");
  CHECK(wlx_test::slurp(dir / "victim2") == "precious too");
  CHECK(!std::filesystem::is_symlink(gen / "params.hpp"));
  CHECK(wlx_test::slurp(gen / "params.hpp").find("struct Params") != std::string::npos);
  for (const auto& e : std::filesystem::directory_iterator(gen))
    if (e.path().filename() != "types.hpp.tmp" && e.path().filename() != "model.json")
      CHECK(e.path().extension() == ".hpp");  // no temporary of this run left
}

TEST_CASE("wlx-gen: a full disk exits 74 naming the header; the previous header set stays whole, no temporary left") {
  const std::filesystem::path disk = wlx_test::work_dir() / "small-disk";
  std::filesystem::create_directories(disk);
  if (::mount("tmpfs", disk.c_str(), "tmpfs", 0, "size=512k") != 0) {
    MESSAGE("skipped: cannot mount a tmpfs here (" << std::strerror(errno) << "): needs root or CAP_SYS_ADMIN");
    return;
  }
  const std::filesystem::path out = disk / "out", model = wlx_test::work_dir() / "arm-changed.yaml";
  REQUIRE(wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet"}).code == 0);
  const auto before = tree(out);
  REQUIRE(before.size() > 5);
  // Another model text: every header changes (its banner's fingerprint). Then the disk is filled
  // to within 32 KiB, less than the set needs.
  wlx_test::write(model, replaced(arm_text(), "value: 0.6, unit: m", "value: 0.61, unit: m"));
  struct statvfs fs {};
  REQUIRE(::statvfs(disk.c_str(), &fs) == 0);
  const std::size_t free_bytes = fs.f_bavail * fs.f_frsize;
  REQUIRE(free_bytes > 32768);
  wlx_test::write(disk / "filler", std::string(free_bytes - 32768, 'x'));
  const auto r = wlx_test::run({model.string(), "--out", out.string(), "--quiet"});
  CAPTURE(r.err);
  CHECK(r.code == 74);
  CHECK(r.err.find(".hpp: ") != std::string::npos);
  CHECK(r.err.find("No space left on device") != std::string::npos);
  CHECK(tree(out) == before);  // byte for byte the earlier set, nothing added
  ::umount2(disk.c_str(), MNT_DETACH);
}

TEST_CASE("wlx-gen: a rename that fails midway leaves the previous header set whole, no temporary or backup left") {
  const std::filesystem::path dir = wlx_test::work_dir() / "rename-fails", out = dir / "out", gen = out / "wlx" / "gen";
  std::filesystem::create_directories(dir);
  REQUIRE(wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet"}).code == 0);
  // all.hpp is renamed last: a folder under its name makes that rename fail after the others
  // were renamed, so they have to be put back.
  std::filesystem::remove(gen / "all.hpp");
  std::filesystem::create_directories(gen / "all.hpp");
  wlx_test::write(gen / "all.hpp" / "keep", "x");
  const auto before = tree(out);
  REQUIRE(before.size() > 5);
  const std::filesystem::path model = dir / "arm-changed.yaml";
  wlx_test::write(model, replaced(arm_text(), "value: 0.6, unit: m", "value: 0.61, unit: m"));  // every header changes
  const auto r = wlx_test::run({model.string(), "--out", out.string(), "--quiet"});
  CAPTURE(r.err);
  CHECK(r.code == 74);
  CHECK(r.err.find("all.hpp: rename into place failed") != std::string::npos);
  CHECK(tree(out) == before);  // byte for byte the earlier set, nothing added
}

namespace {

// A fixed-base arm of n links, each with a body: its dynamics take wlx-gen about a second for
// n = 60, long enough to be interrupted while deriving.
std::string long_arm(int n) {
  std::string t = "model: long_arm\nparameters:\n"
                  "  - {name: l, value: 0.3, unit: m, kind: length, meaning: link length}\n"
                  "  - {name: m, value: 1, unit: kg, kind: mass, meaning: link mass}\n"
                  "  - {name: Ia, value: 0.004, unit: kg*m^2, kind: inertia, meaning: along}\n"
                  "  - {name: Ib, value: 0.09, unit: kg*m^2, kind: inertia, meaning: across}\n"
                  "  - {name: g, value: 9.81, unit: m/s^2, kind: gravity, meaning: gravity}\n"
                  "coordinates:\n  inputs:\n";
  std::string frames = "frames:\n", bodies = "bodies:\n", joints;
  for (int k = 0; k < n; ++k) {
    const std::string q = "q" + std::to_string(k), f = "f" + std::to_string(k);
    t += "    - {name: " + q + ", unit: rad, meaning: joint}\n";
    frames += "  - {name: " + f + ", parent: " + (k == 0 ? std::string("K0") : "f" + std::to_string(k - 1)) +
              ", chain: [translate: [l, 0, 0], " + (k % 2 ? "ry: " : "rz: ") + q + "]}\n";
    bodies += "  - {name: b" + std::to_string(k) + ", frame: " + f + ", com: [l/2, 0, 0], mass: m, inertia: [Ia, Ib, Ib]}\n";
    joints += (k ? ", " : "") + q;
  }
  return t + frames + bodies + "dynamics:\n  gravity: g\n  commanded: [" + joints + "]\n  actuated: [" + joints + "]\n";
}

// Whether the process has handlers for SIGINT, SIGTERM and SIGHUP (its SigCgt mask in /proc):
// a signal sent before would find the default action and prove nothing about wlx-gen.
bool catches_signals(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("SigCgt:", 0) == 0) {
      const unsigned long long mask = std::stoull(line.substr(7), nullptr, 16);
      const auto bit = [&](int s) { return (mask >> (s - 1)) & 1ULL; };
      return bit(SIGINT) && bit(SIGTERM) && bit(SIGHUP);
    }
  return false;
}

}  // namespace

TEST_CASE("wlx-gen: SIGINT, SIGTERM and SIGHUP stop it at once with 128 + signal; the previous header set stays, no temporary") {
  const std::filesystem::path dir = wlx_test::work_dir() / "signals", out = dir / "out";
  std::filesystem::create_directories(dir);
  wlx_test::write(dir / "long_arm.yaml", long_arm(60));
  REQUIRE(wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet"}).code == 0);
  const auto before = tree(out);
  for (const auto& [signal, code] : std::vector<std::pair<int, int>>{{SIGINT, 130}, {SIGTERM, 143}, {SIGHUP, 129}}) {
    const int sent = signal;  // a copy: clang 14 cannot capture a structured binding
    CAPTURE(sent);
    const auto spawned = wlx_test::start({(dir / "long_arm.yaml").string(), "--out", out.string(), "--quiet"});
    const auto started = std::chrono::steady_clock::now();
    while (!catches_signals(spawned.pid) && std::chrono::steady_clock::now() - started < std::chrono::seconds(10))
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const auto signalled = std::chrono::steady_clock::now();
    REQUIRE(::kill(spawned.pid, signal) == 0);
    const auto r = wlx_test::finish(spawned);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
    CAPTURE(r.err);
    CHECK(r.signal == 0);
    CHECK(r.code == code);
    CHECK(r.err.find(signal == SIGINT ? "interrupted (SIGINT)" : signal == SIGTERM ? "terminated (SIGTERM)" : "hung up (SIGHUP)") !=
          std::string::npos);
    CHECK(seconds < 0.5);  // the model alone takes about a second
    CHECK(tree(out) == before);  // nothing of the long arm's set, no temporary
  }
}

TEST_CASE("wlx-gen: stdout that cannot be written exits 74 naming stdout") {
  const std::filesystem::path out = wlx_test::work_dir() / "stdout-full";
  const std::vector<std::vector<std::string>> runs = {
      {WLX_ARM_MODEL_FILE, "--print-model"}, {WLX_ARM_MODEL_FILE, "--out", out.string()}, {"--version"}};
  for (const auto& args : runs) {
    const std::string shown = args.back();
    CAPTURE(shown);
    const auto full = wlx_test::run(args, {.stdout_path = "/dev/full"});
    CAPTURE(full.err);
    CHECK(full.code == 74);
    CHECK(full.err.find("wlx-gen: error: stdout: No space left on device") != std::string::npos);
    const auto closed = wlx_test::run(args, {.stdout_closed_pipe = true});
    CAPTURE(closed.err);
    CHECK(closed.signal == 0);  // not killed by SIGPIPE
    CHECK(closed.code == 74);
    CHECK(closed.err.find("wlx-gen: error: stdout: Broken pipe") != std::string::npos);
  }
}

TEST_CASE("wlx-gen: the closed-form IK accepts a target on a one-value range ([v, v]) and refuses one beside it") {
  // A joint that does not move what it solves for (a lever whose point row does not depend on it)
  // leaves a cos x + b sin x = c with a = b = 0: reachable only at c = 0, where every x solves.
  const std::filesystem::path dir = wlx_test::work_dir() / "one-value-range";
  std::filesystem::create_directories(dir);
  REQUIRE(wlx_test::run({WLX_MODEL_FILE, "--out", (dir / "out").string(), "--quiet"}).code == 0);
  wlx_test::write(dir / "check.cpp", R"(#include <wlx/gen/ik.hpp>
#include <cmath>
using namespace wlx::excavator::gen;
int main() {
  double c = 0, s = 0;
  if (!ik_solve_cos_sin(0.0, 0.0, 0.0, false, c, s) || c != 1 || s != 0) return 1;  // x = 0, nearest zero
  if (!ik_solve_cos_sin(0.0, 0.0, 1e-14, true, c, s) || c != 1 || s != 0) return 2;  // rounding
  if (ik_solve_cos_sin(0.0, 0.0, 1e-6, false, c, s)) return 3;                       // beside the value
  if (!ik_solve_cos_sin(2.0, 0.0, 1.0, false, c, s) || std::abs(c - 0.5) > 1e-15) return 4;  // a regular range
  return 0;
}
)");
  const auto compiled = wlx_test::run({"-std=c++17", "-isystem", WLX_EIGEN_INCLUDE, "-I", (dir / "out").string(),
                                       (dir / "check.cpp").string(), "-o", (dir / "check").string()},
                                      {.program = WLX_TEST_CXX});
  CAPTURE(compiled.err);
  REQUIRE(compiled.code == 0);
  CHECK(wlx_test::run({}, {.program = (dir / "check").string()}).code == 0);
}

#ifdef WLX_HAVE_URDF_TESTS
namespace {

// One mistake put into models/wheeled_quadruped.urdf (or its YAML file): the error must name the
// file, the line where the test put the mistake (found in the edited text, not taken from
// wlx-gen), the element and the reason, and wlx-gen must exit 2.
struct UrdfMistake {
  const char* what;
  bool in_yaml;         // the mistake is in the YAML file
  const char* find;     // first occurrence in the file
  const char* replace;  // what it becomes
  const char* line_of;  // the error's line is the first line of the edited file containing this (null: not checked)
  std::vector<const char*> message;
};

int line_of(const std::string& text, const std::string& needle) {
  const auto at = text.find(needle);
  REQUIRE(at != std::string::npos);
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

}  // namespace

TEST_CASE("wlx-gen: a URDF past the limits is refused where it passes them, before anything is built from it") {
  const std::filesystem::path dir = wlx_test::work_dir() / "urdf_limits";
  std::filesystem::create_directories(dir);
  wlx_test::write(dir / "robot.yaml", "model: big\nurdf: robot.urdf\nparameters:\n  - {name: g, value: 9.81, unit: m/s^2, kind: gravity}\n"
                                      "coordinates:\n  inputs:\n    - {name: x, unit: m}\n");
  // 513 links (one more than the frames a model may have): refused at the 513th, with its line.
  std::string links = "<robot name=\"big\">\n";
  for (int k = 0; k < 513; ++k) links += "  <link name=\"l" + std::to_string(k) + "\"/>\n";
  wlx_test::write(dir / "robot.urdf", links + "</robot>\n");
  auto r = wlx_test::run({(dir / "robot.yaml").string(), "--describe"});
  CHECK(r.code == 2);
  CHECK(r.err.find("robot.urdf:514: link: more than 512 links") != std::string::npos);
  // Empty elements by the hundred thousand (small on disk, large in a parsed tree).
  std::string empty = "<robot name=\"big\">\n<link name=\"base\">\n";
  for (int k = 0; k < 70000; ++k) empty += "<visual/>";
  wlx_test::write(dir / "robot.urdf", empty + "\n</link>\n</robot>\n");
  r = wlx_test::run({(dir / "robot.yaml").string(), "--describe"});
  CHECK(r.code == 2);
  CHECK(r.err.find("robot.urdf:3: XML: more than 65536 elements") != std::string::npos);
  // A URDF's YAML file without its inputs: the field, where the file is (was yaml-cpp's "invalid node", exit 1).
  wlx_test::write(dir / "robot.yaml", "model: big\ndescription: no inputs\nurdf: robot.urdf\n");
  r = wlx_test::run({(dir / "robot.yaml").string(), "--describe"});
  CHECK(r.code == 2);
  CHECK(r.err == "wlx-gen: error: robot.yaml:1:1: missing field 'coordinates'\n");
}

TEST_CASE("wlx-gen: a bad URDF or a bad URDF model file exits 2 with file:line: element: reason") {
  const std::string urdf = wlx_test::slurp(WLX_SOURCE_DIR "/models/wheeled_quadruped.urdf");
  const std::string yaml = wlx_test::slurp(WLX_SOURCE_DIR "/models/wheeled_quadruped.yaml");
  const UrdfMistake cases[] = {
      {"mimic joint", false, "<joint name=\"kfe_lf\" type=\"revolute\">", "<joint name=\"kfe_lf\" type=\"revolute\">\n    <mimic joint=\"hfe_lf\" multiplier=\"-2\"/>",
       "<mimic", {"joint 'kfe_lf' mimic: mimic joints are not supported"}},
      {"floating joint", false, "<joint name=\"haa_lf\" type=\"revolute\">", "<joint name=\"haa_lf\" type=\"floating\">", "\"haa_lf\"",
       {"joint 'haa_lf': floating joints are not read", "base: {chain:"}},
      {"planar joint", false, "<joint name=\"haa_rf\" type=\"revolute\">", "<joint name=\"haa_rf\" type=\"planar\">", "\"haa_rf\"",
       {"joint 'haa_rf': planar joints are not supported"}},
      {"misspelt type", false, "<joint name=\"hfe_rh\" type=\"revolute\">", "<joint name=\"hfe_rh\" type=\"revolut\">", "\"hfe_rh\"",
       {"joint 'hfe_rh': unknown joint type 'revolut' (did you mean 'revolute'?)"}},
      {"child link missing", false, "<child link=\"thigh_lf\"/>", "<child link=\"thigh_lff\"/>", "<joint name=\"hfe_lf\"",
       {"joint 'hfe_lf': no link 'thigh_lff' (did you mean 'thigh_lf'?)"}},
      {"two numbers for xyz", false, "<origin xyz=\"0.3 0.1 0\"", "<origin xyz=\"0.3 0.1\"", "xyz=\"0.3 0.1\"",
       {"joint 'haa_lf' origin: xyz=\"0.3 0.1\" must be 3 numbers"}},
      {"not a number", false, "<origin xyz=\"0.06 0.08 0\"", "<origin xyz=\"0.06 O.08 0\"", "O.08",
       {"joint 'hfe_lf' origin: xyz=\"0.06 O.08 0\": 'O.08' is not a finite number"}},
      {"zero axis", false, "<axis xyz=\"1 0 0\"/>", "<axis xyz=\"0 0 0\"/>", "<axis xyz=\"0 0 0\"/>", {"joint 'haa_lf' axis: the axis is zero"}},
      {"negative mass", false, "<mass value=\"2.0\"/>", "<mass value=\"-2.0\"/>", "-2.0", {"link 'hip_lf' inertial mass: a mass cannot be negative"}},
      {"a point mass", false, "<inertia ixx=\"0.006\" ixy=\"0\" ixz=\"0\" iyy=\"0.010\" iyz=\"0\" izz=\"0.006\"/>",
       "<inertia ixx=\"0\" ixy=\"0\" ixz=\"0\" iyy=\"0\" iyz=\"0\" izz=\"0\"/>", "<link name=\"wheel_lf\"",
       {"link 'wheel_lf' inertial: the principal moments of inertia are 0, 0, 0", "every one positive"}},
      {"a second root", false, "</robot>", "  <link name=\"spare_part\"/>\n</robot>", "spare_part",
       {"link 'spare_part': a second root", "tree of 'base'"}},
      // Two heavy links on a loop of their own: each has a parent, so no second root; unreached, they
      // would vanish from frames and bodies with their 1000 kg.
      {"a loop apart from the tree", false, "</robot>",
       "  <link name=\"ring_a\"><inertial><mass value=\"500\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link>\n"
       "  <link name=\"ring_b\"><inertial><mass value=\"500\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link>\n"
       "  <joint name=\"ring_ab\" type=\"fixed\"><parent link=\"ring_a\"/><child link=\"ring_b\"/></joint>\n"
       "  <joint name=\"ring_ba\" type=\"fixed\"><parent link=\"ring_b\"/><child link=\"ring_a\"/></joint>\n</robot>",
       "<link name=\"ring_a\"", {"link 'ring_a': the root link 'base' does not reach it: 'ring_a', 'ring_b' hang on a loop of joints apart from the tree"}},
      {"a link twice", false, "</robot>", "  <link name=\"hip_lf\"/>\n</robot>", "<link name=\"hip_lf\"/>", {"link 'hip_lf': defined twice"}},
      {"a link with two parents", false, "<child link=\"thigh_lf\"/>", "<child link=\"base_inertia\"/>", "<joint name=\"hfe_lf\"",
       {"joint 'hfe_lf': link 'base_inertia' is already the child of joint 'base_to_base_inertia'", "closure conditions"}},
      {"unexpanded xacro", false, "</robot>", "  <xacro:include filename=\"legs.xacro\"/>\n</robot>", "xacro:include",
       {"<xacro:include>: this is xacro, not URDF: expand it first"}},
      {"no limit on a revolute joint", false, "<limit lower=\"-0.72\" upper=\"0.49\" effort=\"80\" velocity=\"7.5\"/>", "", "<joint name=\"haa_lf\"",
       {"joint 'haa_lf': URDF requires <limit"}},
      {"a name C++ cannot use", false, "</robot>",
       "  <joint name=\"camera_joint\" type=\"fixed\"><parent link=\"base\"/><child link=\"camera-link\"/></joint>\n"
       "  <link name=\"camera-link\"/>\n</robot>",
       "<link name=\"camera-link\"", {"link 'camera-link': 'camera-link' cannot name a frame", "rename: {\"camera-link\": camera_link}"}},
      {"an oblique wheel axle", false, "<axis xyz=\"0 1 0\"/>\n    <limit effort=\"40\"", "<axis xyz=\"0 0.6 0.8\"/>\n    <limit effort=\"40\"",
       "<joint name=\"wheel_joint_lf\"", {"joint 'wheel_joint_lf' axis: a wheel turns about an axis of its joint frame"}},
      {"not XML", false, "</robot>", "</robt>", nullptr, {"XML: "}},
      {"a wheel's axle not the URDF's", true, "axle: y", "axle: x", "axle: x",
       {"axle: the URDF's joint 'wheel_joint_lf' (wheeled_quadruped.urdf:", "turns the wheel about y of 'wheel_lf', not x"}},
      {"a hub that is no wheel's", true, "hub: wheel_<leg>", "hub: shank_<leg>", "hub: shank_<leg>",
       {"wheels[0]{leg=lf}.hub: URDF link 'shank_lf' hangs on joint 'kfe_lf', which is not continuous"}},
      {"no such URDF", true, "urdf: wheeled_quadruped.urdf", "urdf: wheeled_quadrupd.urdf", "urdf: wheeled_quadrupd",
       {"urdf: cannot open the URDF file"}},
      {"rename of nothing", true, "repeat:", "rename: {haa_lx: hip_lf_abduction}\nrepeat:", "rename:",
       {"the URDF has no link or joint 'haa_lx' (did you mean 'haa_lf'?)"}},
      {"dependent joints given", true, "# The floating base", "  dependent: []\n# The floating base", "dependent:",
       {"coordinates.dependent: with a URDF the dependent joints are the URDF's moving joints"}},
  };
  const std::filesystem::path dir = wlx_test::work_dir() / "urdf";
  std::filesystem::create_directories(dir);
  const std::filesystem::path out = wlx_test::work_dir() / "urdf_gen";
  for (const UrdfMistake& c : cases) {
    const std::string what = c.what;
    CAPTURE(what);
    std::string u = urdf, y = yaml;
    std::string& edited = c.in_yaml ? y : u;
    const auto at = edited.find(c.find);
    REQUIRE(at != std::string::npos);
    edited.replace(at, std::strlen(c.find), c.replace);
    wlx_test::write(dir / "wheeled_quadruped.urdf", u);
    wlx_test::write(dir / "wheeled_quadruped.yaml", y);
    std::filesystem::remove_all(out);
    const auto r = wlx_test::run({(dir / "wheeled_quadruped.yaml").string(), "--out", out.string(), "--quiet"});
    CAPTURE(r.err);
    CHECK(r.code == 2);
    const std::string file = c.in_yaml ? "wheeled_quadruped.yaml:" : "wheeled_quadruped.urdf:";
    CHECK(r.err.rfind("wlx-gen: error: " + file, 0) == 0);
    if (c.line_of != nullptr) CHECK(r.err.rfind("wlx-gen: error: " + file + std::to_string(line_of(edited, c.line_of)) + ":", 0) == 0);
    for (const char* m : c.message) CHECK(r.err.find(m) != std::string::npos);
    CHECK(!std::filesystem::exists(out));
  }
  // Elements nested deeper than any URDF (TinyXML would recurse on each): refused on the line of
  // the 65th, before TinyXML reads it.
  std::string deep = urdf, nested;
  for (int k = 0; k < 100; ++k) nested += "<g>\n";
  deep.replace(deep.find("</robot>"), 8, nested + "</robot>");
  wlx_test::write(dir / "wheeled_quadruped.urdf", deep);
  wlx_test::write(dir / "wheeled_quadruped.yaml", yaml);
  const auto r = wlx_test::run({(dir / "wheeled_quadruped.yaml").string(), "--out", out.string(), "--quiet"});
  CHECK(r.code == 2);
  const int robot_line = line_of(urdf, "</robot>");
  CHECK(r.err == "wlx-gen: error: wheeled_quadruped.urdf:" + std::to_string(robot_line + 63) + ": XML: elements nest more than 64 levels deep\n");
}

TEST_CASE("wlx-gen --depfile: the model file and the URDF it names, for the build to regenerate when either changes") {
  // A folder whose name needs Make's escapes (a space, a '#'), with a copy of the quadruped's files.
  const std::filesystem::path dir = wlx_test::work_dir() / "dep files #1";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::filesystem::copy_file(WLX_SOURCE_DIR "/models/wheeled_quadruped.yaml", dir / "wheeled_quadruped.yaml");
  std::filesystem::copy_file(WLX_SOURCE_DIR "/models/wheeled_quadruped.urdf", dir / "wheeled_quadruped.urdf");
  const std::string escaped = std::string(std::filesystem::absolute(dir).lexically_normal()).replace(
      std::string(std::filesystem::absolute(dir).lexically_normal()).find("dep files #1"), 12, "dep\\ files\\ \\#1");
  const auto r = wlx_test::run({(dir / "wheeled_quadruped.yaml").string(), "--out", (dir / "out").string(), "--quiet", "--depfile",
                                (dir / "gen.d").string(), "--depfile-target", (dir / "gen.stamp").string(), "--expect-model",
                                "wheeled_quadruped"});
  CAPTURE(r.err);
  REQUIRE(r.code == 0);
  CHECK(wlx_test::slurp(dir / "gen.d") == escaped + "/gen.stamp: \\\n  " + escaped + "/wheeled_quadruped.yaml \\\n  " + escaped +
                                               "/wheeled_quadruped.urdf\n");
  // Without --depfile-target, the target is the header every other one is included through.
  const auto plain = wlx_test::run({WLX_MODEL_FILE, "--out", (dir / "exc").string(), "--quiet", "--depfile", (dir / "exc.d").string()});
  REQUIRE(plain.code == 0);
  CHECK(wlx_test::slurp(dir / "exc.d") == escaped + "/exc/wlx/gen/all.hpp: \\\n  " +
                                               std::string(std::filesystem::absolute(WLX_MODEL_FILE).lexically_normal()) + "\n");
  // It lists what the headers depend on: without --out there are none.
  const auto no_out = wlx_test::run({WLX_MODEL_FILE, "--describe", "--depfile", (dir / "x.d").string()});
  CHECK(no_out.code == 2);
  CHECK(no_out.err.find("--depfile lists what --out's headers depend on: give --out") != std::string::npos);
  CHECK(!std::filesystem::exists(dir / "x.d"));
}

TEST_CASE("wlx-gen: robot.urdf --with robot.yaml, and --print-model") {
  const std::filesystem::path out = wlx_test::work_dir() / "urdf_with";
  std::filesystem::remove_all(out);
  // The YAML file without its `urdf:` line: the URDF comes from the command line.
  std::string yaml = wlx_test::slurp(WLX_SOURCE_DIR "/models/wheeled_quadruped.yaml");
  yaml.erase(yaml.find("urdf: wheeled_quadruped.urdf\n"), std::strlen("urdf: wheeled_quadruped.urdf\n"));
  const std::filesystem::path with = wlx_test::work_dir() / "robot.yaml";
  wlx_test::write(with, yaml);
  const auto r = wlx_test::run({WLX_SOURCE_DIR "/models/wheeled_quadruped.urdf", "--with", with.string(), "--out", out.string(), "--quiet"});
  CAPTURE(r.err);
  CHECK(r.code == 0);
  CHECK(std::filesystem::exists(out / "wlx" / "gen" / "all.hpp"));
  const std::string params = wlx_test::slurp(out / "wlx" / "gen" / "params.hpp");
  CHECK(params.find("double haa_lf_x = 0.3;") != std::string::npos);
  CHECK(params.find("double m_base = 40.0;") != std::string::npos);  // base_inertia, imu_link and lidar merged
  const auto alone = wlx_test::run({WLX_SOURCE_DIR "/models/wheeled_quadruped.urdf", "--out", out.string()});
  CHECK(alone.code == 2);
  CHECK(alone.err.find("a URDF needs --with robot.yaml") != std::string::npos);
  const auto printed = wlx_test::run({WLX_SOURCE_DIR "/models/wheeled_quadruped.yaml", "--print-model"});
  CHECK(printed.code == 0);
  CHECK(printed.out.find("  - name: imu_link\n    meaning: URDF link imu_link (fixed by joint imu_joint)\n    parent: base\n") !=
        std::string::npos);
  CHECK(printed.out.find("rotation: [{ry: 0.05}]") != std::string::npos);  // the merged base's principal axes
  // The printed model file generates the same headers as the URDF (banners apart: they name the files).
  const std::filesystem::path printed_file = wlx_test::work_dir() / "printed.yaml";
  wlx_test::write(printed_file, printed.out);
  const std::filesystem::path out_printed = wlx_test::work_dir() / "urdf_printed";
  std::filesystem::remove_all(out_printed);
  REQUIRE(wlx_test::run({printed_file.string(), "--out", out_printed.string(), "--quiet"}).code == 0);
  // model.json names the files too ("source") and fingerprints the headers with their banners
  // ("code_key"): apart from those two lines it is the same.
  const auto without_banner = [](const std::string& text) {
    std::string out, line;
    std::istringstream in(text);
    while (std::getline(in, line))
      if (line.find("Generated by wlx-gen") == std::string::npos && line.rfind(" \"source\": ", 0) != 0 &&
          line.rfind(" \"code_key\": ", 0) != 0)
        out += line + "\n";
    return out;
  };
  int compared = 0;
  for (const auto& entry : std::filesystem::directory_iterator(out / "wlx" / "gen")) {
    CAPTURE(entry.path().filename().string());
    const std::filesystem::path twin = out_printed / "wlx" / "gen" / entry.path().filename();
    REQUIRE(std::filesystem::exists(twin));
    CHECK(without_banner(wlx_test::slurp(entry.path())) == without_banner(wlx_test::slurp(twin)));
    ++compared;
  }
  CHECK(compared >= 10);
}
#endif

TEST_CASE("wlx-gen: a single link on a fixed base (one coordinate, one body): headers that compile warning-free and its dynamics by hand") {
  // The smallest model: a rod of length 0.5 m and mass 2 kg turning about y. Before, wlx-gen
  // failed on it ("lane scalar kane_R_0_0_0 is never read": the recursion never reads a body's
  // rotation when the one joint turns it about a fixed axis), and then wrote a value nothing
  // read (unused-variable warnings in a user's -Werror build).
  const std::filesystem::path dir = wlx_test::work_dir() / "one_link";
  std::filesystem::create_directories(dir);
  wlx_test::write(dir / "pendulum.yaml", R"(model: pendulum
description: one rod turning about y on a fixed base
parameters:
  - {name: len, value: 0.5, unit: m, kind: length, meaning: rod length}
  - {name: m1, value: 2, unit: kg, kind: mass, meaning: rod mass}
  - {name: I1, value: 0.01, unit: kg*m^2, kind: inertia, meaning: rod inertia about its centre}
  - {name: g, value: 9.81, unit: m/s^2, kind: gravity, meaning: gravity}
coordinates:
  inputs:
    - {name: swing, unit: rad, meaning: rod angle below the horizontal}
frames:
  - {name: rod, parent: K0, chain: [ry: swing]}
  - {name: tip, parent: rod, chain: [translate: [len, 0, 0]]}
bodies:
  - {name: rod, frame: rod, com: [len/2, 0, 0], mass: m1, inertia: [I1, I1, I1]}
dynamics:
  gravity: g
  commanded: [swing]
  actuated: [swing]
)");
  const auto r = wlx_test::run({(dir / "pendulum.yaml").string(), "--out", (dir / "out").string(), "--quiet"});
  CAPTURE(r.err);
  REQUIRE(r.code == 0);
  // By hand, at q = 0.3 (the centre at (l/2 cos q, 0, -l/2 sin q)): M = I + m (l/2)^2 = 0.135;
  // Q_gravity = -dV/dq = m g (l/2) cos q; the actuator's force for q' = 1.5, q'' = 2 is
  // M q'' - Q_gravity (no velocity term for one joint about a fixed axis).
  wlx_test::write(dir / "check.cpp", R"(#include <wlx/gen/all.hpp>
#include <cmath>
using namespace wlx::pendulum::gen;
int main() {
  Coordinates s, sdot, sddot;
  s << 0.3;
  sdot << 1.5;
  sddot << 2.0;
  RateBasis T;
  T.setIdentity();
  const Params p;
  CommandMatrix M;
  CommandVector Q, Qstar;
  reduced_dynamics(s, Coordinates::Zero(), T, p, {.M = &M, .Q_gravity = &Q});
  generalized_forces(s, sdot, sddot, T, p, {.Qstar = &Qstar});
  const double mass = 2, half = 0.25, inertia = 0.01, g = 9.81, M_hand = inertia + mass * half * half;
  const double Q_hand = mass * g * half * std::cos(0.3);
  const bool ok = std::abs(M(0, 0) - M_hand) <= 1e-15 && std::abs(Q(0) - Q_hand) <= 1e-14 &&
                  std::abs(Qstar(0) - (M_hand * 2.0 - Q_hand)) <= 1e-14;
  return ok ? 0 : 1;
}
)");
  const std::string exe = (dir / "check").string();
  const std::string compile = std::string(WLX_TEST_CXX) + " -std=c++20 -Wall -Wextra -Werror -isystem " + WLX_EIGEN_INCLUDE + " -I'" +
                              (dir / "out").string() + "' '" + (dir / "check.cpp").string() + "' -o '" + exe + "' 2>&1";
  INFO(compile);
  REQUIRE(std::system(compile.c_str()) == 0);
  CHECK(std::system(("'" + exe + "'").c_str()) == 0);
}

TEST_CASE("wlx-gen: stderr that cannot be written loses the message, not the exit code (never abort)") {
  const std::filesystem::path dir = wlx_test::work_dir() / "stderr_full";
  std::filesystem::create_directories(dir);
  wlx_test::write(dir / "bad.yaml", "model: broken\n");
  const auto r = wlx_test::run({(dir / "bad.yaml").string(), "--out", (dir / "out").string()}, {.stderr_path = "/dev/full"});
  CHECK(r.signal == 0);
  CHECK(r.code == 2);
  const auto usage = wlx_test::run({"--no-such-option"}, {.stderr_path = "/dev/full"});
  CHECK(usage.signal == 0);
  CHECK(usage.code == 2);
}
