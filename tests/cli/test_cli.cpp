// The wlx command line, run as a user would: exit codes, stdout, stderr, files.
#include <doctest/doctest.h>
#include <input.hpp>
#include <nlohmann/json.hpp>
#include <wlx/gen/ik.hpp>
#include <wlx/gen/kinematics.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;

namespace {

struct Run {
  int code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Run run_wlx(const std::string& args, const std::string& input = "") {
  const fs::path dir = fs::temp_directory_path() / "wlx_cli_test";
  fs::create_directories(dir);
  std::ofstream(dir / "in") << input;
  const std::string cmd = std::string(WLX_BINARY) + " " + args + " < " + (dir / "in").string() + " > " +
                          (dir / "out").string() + " 2> " + (dir / "err").string();
  const int status = std::system(cmd.c_str());
  return {WEXITSTATUS(status), slurp(dir / "out"), slurp(dir / "err")};
}

}  // namespace

TEST_CASE("cli: wlx ik solves the nominal state; the numbers put back into the FK hit the targets") {
  const Run r = run_wlx("ik", "{}");
  REQUIRE(r.code == 0);
  CHECK(r.err.empty());
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"psi_l2", "psi_l3", "psi_l4", "psi_r2", "psi_r3", "psi_r4", "theta_l2", "theta_l3",
                          "theta_l4", "theta_l6", "theta_r2", "theta_r3", "theta_r4", "theta_r6", "x_Wl", "y_Wl",
                          "x_Wr", "y_Wr", "closure_residual"})
    CHECK(j.contains(key));
  // Independent check of the printed joints: nominal feet (3.5, +-1.5, 0) and wheel levels.
  wlx::gen::Coordinates s = wlx::gen::Coordinates::Zero();
  s(wlx::gen::coord::z_C) = 2.0;
  for (int k = wlx::gen::kInputCount; k < wlx::gen::kCoordinateCount; ++k)
    s(k) = j.at(std::string(wlx::gen::kCoordinateNames[k])).get<double>();
  wlx::gen::FramePositions pos;
  wlx::gen::kinematics(s, wlx::gen::Params{}, {.positions = &pos});
  CHECK((pos.col(wlx::gen::frame::F_l) - Eigen::Vector3d(3.5, 1.5, 0)).norm() <= 1e-12);
  CHECK((pos.col(wlx::gen::frame::F_r) - Eigen::Vector3d(3.5, -1.5, 0)).norm() <= 1e-12);
  CHECK(std::abs(pos(2, wlx::gen::frame::W_r) - 0.05) <= 1e-12);
  CHECK(j.at("x_Wr").get<double>() == doctest::Approx(pos(0, wlx::gen::frame::W_r)).epsilon(1e-15));
}

TEST_CASE("cli: wlx fk's table gives the joints in SI units (rad) like its JSON, degrees only beside them") {
  const Run table = run_wlx("fk", "{}");
  const Run json = run_wlx("fk --json", "{}");
  REQUIRE(table.code == 0);
  REQUIRE(json.code == 0);
  const auto coordinates = nlohmann::json::parse(json.out).at("coordinates");
  std::istringstream lines(table.out);
  int joints = 0;
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string name, unit, deg;
    double value = 0;
    if (!(words >> name >> value >> unit) || !coordinates.contains(name)) continue;
    ++joints;
    CHECK(unit == "rad");  // every dependent joint of the excavator is an angle
    CHECK(std::abs(value - coordinates.at(name).get<double>()) <= 5e-7);  // printed to 6 decimals
    double in_degrees = 0;
    REQUIRE((words >> in_degrees >> deg));
    CHECK(deg == "deg");
    CHECK(std::abs(in_degrees - coordinates.at(name).get<double>() * 180 / 3.14159265358979) <= 5e-5);
  }
  CHECK(joints == 14);
}

TEST_CASE("cli: Newton agrees with the closed form and reports its iterations") {
  const Run cf = run_wlx("ik", R"({"z_C": 1.7, "roll": 0.05, "theta_l5": 0.2})");
  const Run nt = run_wlx("ik", R"({"z_C": 1.7, "roll": 0.05, "theta_l5": 0.2, "method": "newton"})");
  REQUIRE(cf.code == 0);
  REQUIRE(nt.code == 0);
  const auto a = nlohmann::json::parse(cf.out), b = nlohmann::json::parse(nt.out);
  for (const char* key : {"psi_l2", "psi_r4", "theta_l6", "theta_r3", "x_Wl"})
    CHECK(std::abs(a.at(key).get<double>() - b.at(key).get<double>()) <= 1e-12);
  CHECK(b.at("iterations_total").get<int>() > 0);
  CHECK(!a.contains("iterations"));
}

// Issue 43: the labels say what ran. Every limb of the excavator has a closed form (the generated
// ik.hpp's kClosedForm, checked here first); a model whose limbs have none is run through
// --model-file in test_model_file_plugin.cpp.
TEST_CASE("cli: wlx ik's method and limb_methods say what solved each limb; Newton's iterations only where it ran") {
  for (const auto& info : wlx::gen::kClosedForm) {
    const bool has_closed_form = info.solve != nullptr;
    REQUIRE(has_closed_form);
  }
  const Run cf = run_wlx("ik", R"({"z_C": 1.7})");
  const Run nt = run_wlx("ik", R"({"z_C": 1.7, "method": "newton"})");
  REQUIRE(cf.code == 0);
  REQUIRE(nt.code == 0);
  const auto a = nlohmann::json::parse(cf.out), b = nlohmann::json::parse(nt.out);
  CHECK(a.at("method") == "closed-form");
  CHECK(b.at("method") == "newton");
  REQUIRE(a.at("limb_methods").size() == wlx::gen::kLimbs.size());
  REQUIRE(b.at("limb_methods").size() == wlx::gen::kLimbs.size());
  for (const auto& limb : wlx::gen::kLimbs) {
    const std::string name(limb.name);
    CHECK(a.at("limb_methods").at(name) == "closed-form");
    CHECK(b.at("limb_methods").at(name) == "newton");
    CHECK(b.at("iterations").contains(name));
  }
  CHECK(!a.contains("iterations"));
  CHECK(!a.contains("iterations_total"));
}

TEST_CASE("cli: the method in words and by name for limbs that differ (a model whose limbs are solved two ways)") {
  // The excavator's limbs all have a closed form, so the mixed case is built here: what ik and fk
  // print for a model where the second limb has none.
  using namespace wlx::excavator::commands;
  std::array<IkMethod, wlx::kLimbCount> methods{};
  methods.fill(IkMethod::closed_form);
  CHECK(overall_method(methods, IkMethod::closed_form) == "closed-form");
  CHECK(methods_in_words(methods) == "the closed-form IK");
  methods[1] = IkMethod::newton;
  CHECK(overall_method(methods, IkMethod::closed_form) == "mixed");
  CHECK(methods_in_words(methods) == "the closed-form IK, and Newton's method for the limbs without a closed form (" +
                                         std::string(wlx::gen::kLimbs[1].title) + ")");
  methods.fill(IkMethod::newton);
  CHECK(overall_method(methods, IkMethod::closed_form) == "newton");
  CHECK(methods_in_words(methods) == "Newton's method");  // asked for: this model's limbs do have closed forms
  // What a request asks and the model has: every limb in closed form, or Newton's when asked.
  for (const IkMethod m : limb_methods(IkMethod::closed_form)) CHECK(m == IkMethod::closed_form);
  for (const IkMethod m : limb_methods(IkMethod::newton)) CHECK(m == IkMethod::newton);
}

TEST_CASE("cli: wlx fk says how it found the dependent joints, and a branch is a question for wlx ik") {
  Run r = run_wlx("fk", "{}");
  REQUIRE(r.code == 0);
  CHECK(r.out.rfind("excavator pose, dependent joints by the closed-form IK:\n", 0) == 0);
  r = run_wlx("fk --json", "{}");
  REQUIRE(r.code == 0);
  auto j = nlohmann::json::parse(r.out);
  for (const auto& limb : wlx::gen::kLimbs) CHECK(j.at("limb_methods").at(std::string(limb.name)) == "closed-form");
  // All the dependent joints given: nothing was solved.
  nlohmann::json pose = nlohmann::json::object();
  for (const auto& [name, value] : j.at("coordinates").items()) pose[name] = value;
  r = run_wlx("fk --json", pose.dump());
  REQUIRE(r.code == 0);
  j = nlohmann::json::parse(r.out);
  for (const auto& limb : wlx::gen::kLimbs) CHECK(j.at("limb_methods").at(std::string(limb.name)) == "given");
  CHECK(run_wlx("fk", pose.dump()).out.rfind("excavator pose, dependent joints as given:\n", 0) == 0);
  r = run_wlx("fk", R"({"psi_l2": 0.1})");
  CHECK(r.code == 2);
  CHECK(r.err ==
        "wlx: error: stdin: give all 14 dependent joints or none, 1 given; with none, fk solves them by the "
        "closed-form IK\n");
  r = run_wlx("fk", R"({"z_C": 1.8, "branch": {"leg_l": 1}})");
  CHECK(r.code == 2);
  CHECK(r.out.empty());
  CHECK(r.err.rfind("wlx: error: branch: unknown key: branches apply to the IK (`wlx ik` takes \"branch\"), not to fk, "
                    "which takes "
                    "all joint values",
                    0) == 0);
  CHECK(r.err.find("the 14 dependent joints") != std::string::npos);
}

TEST_CASE("cli: bad input gets a message naming the field and exit code 2") {
  Run r = run_wlx("ik", R"({"x_Fll": 7})");
  CHECK(r.code == 2);
  CHECK(r.err == "wlx: error: x_Fll: unknown key; did you mean 'x_Fl'?\n");
  CHECK(r.out.empty());
  r = run_wlx("ik", R"({"x_Fl": 7})");
  CHECK(r.code == 2);
  CHECK(r.err ==
        "wlx: error: left leg: F_l out of reach: its target is 5.8523 m from the meeting point of the axes of psi_l2 and "
        "psi_l3, and F_l reaches [0.5000, 3.5000] m from it\n");
  r = run_wlx("ik", R"({"params": {"thighd": 2}})");
  CHECK(r.err == "wlx: error: params.thighd: unknown key; did you mean 'thighD'?\n");
  r = run_wlx("ik", R"({"params": {"w": 0}})");
  CHECK(r.err == "wlx: error: params.w: a length must be positive, got 0 m\n");
  r = run_wlx("ik", R"({"method": "mobile"})");
  CHECK(r.err == "wlx: error: method: must be \"closed-form\" or \"newton\", got \"mobile\"\n");
  r = run_wlx("ik", R"({"branch": {"leg_l": 4}})");
  CHECK(r.err == "wlx: error: branch.leg_l: left leg has branches 0 to 3, got 4\n");
  r = run_wlx("ik", R"({"yaw": 1e999})");
  CHECK(r.code == 2);
  CHECK(r.err.rfind("wlx: error: stdin: not valid JSON", 0) == 0);
  r = run_wlx("ik", "[1, 2]");
  CHECK(r.err == "wlx: error: expected a JSON object, got array\n");
}

TEST_CASE("cli: wlx ik reads the scenario files' value grammar: {\"deg\": x} for angles only; start needs Newton") {
  const Run deg = run_wlx("ik", R"({"roll": {"deg": 3}, "theta_l5": {"deg": -10}})");
  const Run rad = run_wlx("ik", R"({"roll": 0.05235987755982988, "theta_l5": -0.17453292519943295})");
  REQUIRE(deg.code == 0);
  REQUIRE(rad.code == 0);
  CHECK(deg.out == rad.out);  // 3 deg and -10 deg are these radians to the last digit
  Run r = run_wlx("ik", R"({"z_C": {"deg": 3}})");
  CHECK(r.code == 2);
  CHECK(r.err == "wlx: error: z_C: only angles may be given in degrees; give this value in SI units\n");
  r = run_wlx("ik", R"({"roll": {"rad": 3}})");
  CHECK(r.code == 2);
  CHECK(r.err.find("roll: expected a number or {\"deg\": x}") != std::string::npos);
  r = run_wlx("ik", R"({"roll": {"deg/s": 3}})");  // a rate's unit for an angle: a mistake, not a synonym
  CHECK(r.code == 2);
  CHECK(r.err == "wlx: error: roll: expected a number or {\"deg\": x}, got {\"deg/s\":3}\n");
  r = run_wlx("ik", R"({"start": {"psi_l2": 0.1}})");
  CHECK(r.code == 2);
  // psi_l2 is the left leg's, which its closed form solves: a start there asks for Newton's method.
  CHECK(r.err == "wlx: error: start.psi_l2: is Newton's starting guess, and left leg is solved by its closed form, which "
                 "takes none: give \"method\": \"newton\" to solve it by Newton's method from this start\n");
  const Run started = run_wlx("ik", R"({"method": "newton", "start": {"psi_l2": {"deg": 14}}})");
  const Run plain = run_wlx("ik", R"({"method": "closed-form"})");
  REQUIRE(started.code == 0);
  const auto a = nlohmann::json::parse(started.out), b = nlohmann::json::parse(plain.out);
  CHECK(std::abs(a.at("psi_l2").get<double>() - b.at("psi_l2").get<double>()) <= 1e-12);  // the same solution
}

TEST_CASE("cli: wlx ik --batch answers line by line and keeps going after a bad line") {
  const Run r = run_wlx("ik --batch", "{\"z_Fl\": 0.1, \"method\": \"newton\"}\n{\"z_Fl\": 9}\n{\"z_Fl\": 0.2, \"method\": \"newton\"}\n");
  CHECK(r.code == 2);
  std::istringstream lines(r.out);
  std::string line;
  std::vector<nlohmann::json> out;
  while (std::getline(lines, line)) out.push_back(nlohmann::json::parse(line));
  REQUIRE(out.size() == 3);
  CHECK(out[0].contains("psi_l2"));
  CHECK(out[1].at("line") == 2);
  CHECK(out[1].at("error").get<std::string>().rfind("left leg: F_l out of reach", 0) == 0);
  CHECK(out[1].at("kind") == "out-of-reach");  // the IK's status, for a program that acts on it
  CHECK(out[2].at("closure_residual").get<double>() <= 1e-13);
  // Warm start from line 1: a small step needs few iterations.
  CHECK(out[2].at("iterations").at("leg_l").get<int>() <= 4);
  CHECK(r.err.find("wlx ik: line 2: left leg") != std::string::npos);
}

TEST_CASE("cli: wlx verify ik writes one CSV per sweep and passes") {
  const fs::path dir = fs::temp_directory_path() / "wlx_cli_test" / "verify";
  fs::remove_all(dir);
  const Run r = run_wlx("verify ik --sweep IK-L1 --sweep IK-WR2 --out " + dir.string());
  CHECK(r.code == 0);
  CHECK(r.out.find("all sweeps pass") != std::string::npos);
  // Both limbs have a closed form: its columns, and no word of a limb without one.
  CHECK(r.out.find("check CF (m)") != std::string::npos);
  CHECK(r.out.find("|CF-N| (rad)") != std::string::npos);
  CHECK(r.out.find("No closed form") == std::string::npos);
  const std::string csv = slurp(dir / "IK-L1.csv");
  CHECK(csv.rfind("x_Fl,psi_l2,psi_l3,psi_l4,", 0) == 0);
  CHECK(csv.find(",check_error_closed_form,check_error_newton,level_error_closed_form,level_error_newton,newton_minus_"
                 "closed_form,") != std::string::npos);
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 1 + 251);
  CHECK(csv.find("nan") == std::string::npos);
  CHECK(fs::exists(dir / "IK-WR2.csv"));
  const Run bad = run_wlx("verify ik --sweep IK-L9 --out " + dir.string());
  CHECK(bad.code == 2);
  CHECK(bad.err == "wlx: error: --sweep: no sweep 'IK-L9'; did you mean 'IK-L1'?\n");
}

TEST_CASE("cli: wlx simulate writes trajectory.csv with the public columns") {
  const fs::path dir = fs::temp_directory_path() / "wlx_cli_test" / "sim";
  fs::remove_all(dir);
  const Run r = run_wlx("simulate NH-2 --out " + dir.string());
  CHECK(r.code == 0);
  const std::string csv = slurp(dir / "trajectory.csv");
  std::string expected = "t,x_C,y_C,z_C,yaw,pitch,roll,x_Fl,y_Fl,z_Fl,x_Fr,y_Fr,z_Fr,z_Wl,z_Wr,psi_l1,psi_r1,theta_l5,"
                         "theta_r5,psi_l2,psi_l3,psi_l4,psi_r2,psi_r3,psi_r4,theta_l2,theta_l3,theta_l4,theta_l6,theta_r2,"
                         "theta_r3,theta_r4,theta_r6,x_Wl,y_Wl,x_Wr,y_Wr,nh_residual_l,nh_residual_r,spin_rate_l,spin_rate_r,";
  CHECK(csv.rfind(expected, 0) == 0);
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 1 + 452);  // 0.451 s at 1 ms, t = 0 included
  CHECK(csv.find("nan") == std::string::npos);
  CHECK(r.out.find("452 samples") != std::string::npos);
}

TEST_CASE("cli: wlx simulate overrides, errors, and a run that fails midway") {
  const fs::path dir = fs::temp_directory_path() / "wlx_cli_test" / "sim2";
  fs::remove_all(dir);
  Run r = run_wlx("simulate ST-A2+ --integrator euler --dt 0.0005 --out " + dir.string());
  CHECK(r.code == 0);
  CHECK(r.out.find("903 samples (0.451 s, dt 0.0005 s, euler)") != std::string::npos);
  r = run_wlx("simulate ST-A9 --out " + dir.string());
  CHECK(r.code == 2);
  CHECK(r.err == "wlx: error: SCENARIO: 'ST-A9' is neither a file nor a scenario id; did you mean 'ST-A1+'?\n");
  r = run_wlx("simulate NH-1 --dt -1 --out " + dir.string());
  CHECK(r.err == "wlx: error: dt: must be a positive number of seconds, got -1\n");
  // Lifting the cabin at 3 m/s: the legs lose the feet after a few tenths of a second.
  const fs::path file = dir / "lift.json";
  std::ofstream(file) << R"({"id": "lift", "rates": {"z_C": 3}, "dependent": ["y_C", "yaw"], "duration": 1})";
  r = run_wlx("simulate " + file.string() + " --out " + dir.string());
  CHECK(r.code == 2);
  CHECK(r.err.find("wlx: error: stopped at t = ") == 0);
  CHECK(r.err.find("leg: F_l out of reach") != std::string::npos);
  const std::string csv = slurp(dir / "trajectory.csv");
  const auto rows = std::count(csv.begin(), csv.end(), '\n');
  CHECK(rows > 10);
  CHECK(rows < 1001);
  CHECK(csv.find("nan") == std::string::npos);
}

TEST_CASE("cli: wlx simulate ID-1 --weighting 2 adds the torque and Q* columns") {
  const fs::path dir = fs::temp_directory_path() / "wlx_cli_test" / "id1";
  fs::remove_all(dir);
  const Run r = run_wlx("simulate ID-1 --weighting 2 --out " + dir.string());
  CHECK(r.code == 0);
  CHECK(r.out.find("inverse dynamics with weights by contribution") != std::string::npos);
  const std::string csv = slurp(dir / "trajectory.csv");
  const std::string header = csv.substr(0, csv.find('\n'));
  CHECK(header.find(",tau_psi_l2,tau_psi_l3,tau_psi_l4,tau_psi_r2,tau_psi_r3,tau_psi_r4,tau_theta_l6,tau_theta_r6,"
                    "Qstar_z_C,Qstar_x_C,Qstar_roll,Qstar_pitch") != std::string::npos);
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 1 + 495);
  CHECK(run_wlx("simulate ID-1 --weighting 4 --out " + dir.string()).err ==
        "wlx: error: --weighting: must be model-weights, contribution or contacts (or 1, 2, 3), got '4'\n");
  // By name, the same run as by the thesis' number: the same torques to the last digit.
  const fs::path named = fs::temp_directory_path() / "wlx_cli_test" / "id1-named";
  fs::remove_all(named);
  CHECK(run_wlx("simulate ID-1 --weighting contribution --out " + named.string()).code == 0);
  CHECK(slurp(named / "trajectory.csv") == csv);
}

#ifdef WLX_BUILT_MODEL_wheeled_quadruped  // not in the sanitized tree
TEST_CASE("cli: wlx ik keeps the wheeled quadruped's knees within its URDF's limits, and says so of a branch that leaves them") {
  // The URDF's knees bend backwards only: [-2.8, -0.4] rad about y on the left, [0.4, 2.8] about -y
  // on the right (models/wheeled_quadruped.urdf). No branch given: every knee within its range.
  Run r = run_wlx("--model wheeled_quadruped ik", "{}");
  REQUIRE(r.code == 0);
  auto j = nlohmann::json::parse(r.out);
  CHECK(j.at("within_limits") == true);
  for (const char* knee : {"kfe_lf", "kfe_lh"}) {
    CAPTURE(knee);
    CHECK(j.at(knee).get<double>() >= -2.8);
    CHECK(j.at(knee).get<double>() <= -0.4);
  }
  for (const char* knee : {"kfe_rf", "kfe_rh"}) {
    CAPTURE(knee);
    CHECK(j.at(knee).get<double>() >= 0.4);
    CHECK(j.at(knee).get<double>() <= 2.8);
  }
  // Branch 2 of the right front leg (its knee's other root) is taken when asked for, and said to
  // leave the knee's range.
  r = run_wlx("--model wheeled_quadruped ik", R"({"branch": {"leg_rf": 2}})");
  REQUIRE(r.code == 0);
  j = nlohmann::json::parse(r.out);
  CHECK(j.at("kfe_rf").get<double>() < 0);
  CHECK(j.at("within_limits") == false);
  CHECK(j.at("outside_limits").get<std::string>().rfind("kfe_rf = -", 0) == 0);
  CHECK(j.at("outside_limits").get<std::string>().find("is outside its range [0.4, 2.8]") != std::string::npos);
}
#endif

#ifdef WLX_BUILT_MODEL_wheeled_quadruped  // not in the sanitized tree
TEST_CASE("cli: the wheeled quadruped's inverse dynamics has a column per actuator, drives too, and weightings of its size") {
  const fs::path dir = fs::temp_directory_path() / "wlx_cli_test" / "quadruped";
  fs::remove_all(dir);
  Run r = run_wlx("--model wheeled_quadruped simulate ID-Q2 --out " + dir.string());
  REQUIRE(r.code == 0);
  const std::string csv = slurp(dir / "trajectory.csv");
  const std::string header = csv.substr(0, csv.find('\n'));
  CHECK(header.find(",tau_haa_lf,tau_hfe_lf,tau_kfe_lf,") != std::string::npos);
  CHECK(header.find(",tau_kfe_rh,tau_wheel_joint_lf,tau_wheel_joint_rf,tau_wheel_joint_lh,tau_wheel_joint_rh,Qstar_x_B,")
        != std::string::npos);
  CHECK(csv.find("nan") == std::string::npos);
  // A weighting has one entry per actuator: sixteen here, not the excavator's eight.
  const fs::path file = dir / "diag.json";
  std::ofstream(file) << R"({"rates": {"z_B": -0.1}, "dependent": ["y_lf", "y_rf", "y_lh", "y_rh"], "duration": 0.01,
                             "weighting": {"diag": [1, 1, 1, 1, 1, 1, 1, 1]}})";
  r = run_wlx("--model wheeled_quadruped simulate " + file.string() + " --out " + dir.string());
  CHECK(r.code == 2);
  CHECK(r.err.find("wlx: error: weighting.diag: must be an array of 16 weights (one per actuator: haa_lf, ") == 0);
  CHECK(r.err.find("wheel_joint_rh), got [1,1,1,1,1,1,1,1]") != std::string::npos);
  std::ofstream(file) << R"({"rates": {"z_B": -0.1}, "dependent": ["y_lf", "y_rf", "y_lh", "y_rh"], "duration": 0.01,
                             "weighting": {"diag": [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2]}})";
  CHECK(run_wlx("--model wheeled_quadruped simulate " + file.string() + " --out " + dir.string()).code == 0);
}
#endif

TEST_CASE("cli: every validation rule names the field, the value and the rule, with exit code 2") {
  const fs::path dir = fs::temp_directory_path() / "wlx_cli_test" / "rules";
  fs::create_directories(dir);
  struct Case {
    std::string args, input, file, message;
  };
  const std::string ok = R"("dependent": ["y_C", "yaw"], "duration": 0.01)";
  const Case cases[] = {
      {"ik", R"({"x_C": "1"})", "", "x_C: must be a number, got string \"1\""},
      {"ik", R"({"params": {"cxd": -3}})", "", "params.cxd: a length must be positive, got -3 m"},
      {"ik", R"({"params": {"m_M2": 0}})", "", "params.m_M2: a mass must be positive, got 0 kg"},
      {"ik", R"({"params": {"Izz_M1": 9000}})", "", "params.Izz_M1: 9000 kg*m^2 exceeds the sum of the other two"},
      {"ik", R"({"params": {"Iyy_M7": -1}})", "", "params.Iyy_M7: a principal inertia must be positive, got -1"},
      {"ik", R"({"params": "none"})", "", "params: must be an object, got string"},
      {"ik", R"({"start": {"psi_l9": 0}})", "", "start.psi_l9: unknown key; did you mean 'psi_l2'?"},
      {"ik", R"({"branch": 1.5})", "", "branch: must be an integer, got 1.5"},
      {"ik", R"({"branch": {"leg_x": 1}})", "", "branch.leg_x: unknown key; did you mean 'leg_l'?"},
      {"simulate FILE", "", "{" + ok + R"(, "durration": 1})", "durration: unknown key; did you mean 'duration'?"},
      {"simulate FILE", "", R"({"dependent": ["y_C", "y_C"], "duration": 1})",
       "dependent: the dependent rates must differ"},
      {"simulate FILE", "", R"({"dependent": ["y_C", "psi_l2"], "duration": 1})",
       "dependent: 'psi_l2' cannot be a dependent rate: choose 2 of x_C, y_C, z_C, yaw, pitch, roll, theta_l5, "
       "theta_r5"},
      {"simulate FILE", "", R"({"dependent": ["y_C", "yaw"], "duration": 0})",
       "duration: must be a positive number of seconds, got 0"},
      {"simulate FILE", "", R"({"dependent": ["y_C", "yaw"], "duration": 1e6, "dt": 1e-6})",
       "dt: 1e-06 s over 1000000 s is 1e+12 steps, more than the limit of 1e8"},
      {"simulate FILE", "", "{" + ok + R"(, "weighting": 4})", "weighting: must be \"model-weights\" (or 1), \"contribution\" (2), \"contacts\" (3), {\"diag\": [8 weights]} or"},
      {"simulate FILE", "", "{" + ok + R"(, "weighting": {"diag": [1, 1, 1, 1, 1, 1, 1, 0]}})",
       "weighting.diag: a weight must be positive and finite, got 0"},
      {"simulate FILE", "", "{" + ok + R"(, "weighting": 1, "rates": {"theta_l5": 0.1}})",
       "rates.theta_l5: an inverse-dynamics run commands only z_C, x_C, roll and pitch"},
      {"simulate FILE", "", "{" + ok + R"(, "max_condition": 0.5})", "max_condition: must be above 1, got 0.5"},
      {"simulate FILE", "", "{" + ok + R"(, "initial": {"z_C": {"deg": 3}}})",
       "initial.z_C: only angles may be given in degrees; give this value in SI units"},
      {"simulate NH-1 --dt nan", "", "", "dt: must be a positive number of seconds, got nan"},
      {"simulate NH-1 --dt 0.0003", "", "", "dt: the duration 2 s is not a whole number of steps of 0.0003 s"},
      {"simulate NH-1 --integrator rk45", "", "", "--integrator: must be rk4, euler or dopri5, got 'rk45'"},
      {"simulate NH-1 --tolerance 1e-8", "", "",
       "--tolerance: applies to the adaptive integrator only: add --integrator dopri5"},
      {"simulate NH-1 --integrator dopri5 --tolerance 0", "", "",
       "tolerance: must be between 1e-14 (rounding) and 1e-2, got 0"},
      {"simulate", "", "", "SCENARIO: missing: give a scenario file or id (--list shows the ids)"},
  };
  for (const Case& c : cases) {
    std::string args = c.args;
    if (!c.file.empty()) {
      std::ofstream(dir / "case.json") << c.file;
      args.replace(args.find("FILE"), 4, (dir / "case.json").string());
    }
    if (args.rfind("simulate", 0) == 0 && args != "simulate") args += " --out " + (dir / "out").string();
    CAPTURE(args);
    CAPTURE(c.input);
    const Run r = run_wlx(args, c.input);
    CHECK(r.code == 2);
    CHECK(r.err.find("wlx: error: " + c.message) == 0);
    const bool nan_only_when_quoted = r.err.find("nan") == std::string::npos || c.message.find("nan") != std::string::npos;
    CHECK(nan_only_when_quoted);
  }
}

TEST_CASE("cli: wlx export mjcf writes the model's MJCF atomically, the same for --model and --model-file, which compiles nothing") {
  const fs::path dir = fs::temp_directory_path() / "wlx_cli_export";
  fs::remove_all(dir);
  fs::create_directories(dir / "cache");
  const Run built_in = run_wlx("export mjcf --model excavator --out " + (dir / "builtin.xml").string());
  REQUIRE(built_in.code == 0);
  const std::string xml = slurp(dir / "builtin.xml");
  CHECK(xml.find("<mujoco model=\"excavator\">") != std::string::npos);
  CHECK(xml.find("<freejoint name=\"C\"/>") != std::string::npos);
  CHECK(xml.find("<joint name=\"guidance_l\" joint1=\"theta_l4\" joint2=\"theta_l5\"") != std::string::npos);
  CHECK(xml.find("nan") == std::string::npos);
  CHECK(xml.rfind("</mujoco>\n") == xml.size() - 10);
  // The excavator's virtual joints carry no body: placeholders, said on stderr.
  CHECK(built_in.err.find("frame W_l: moves but carries no body") != std::string::npos);
  // A model file is described, never compiled: CXX=/bin/false would fail any compile.
  const std::string env = "CXX=/bin/false WLX_CACHE_DIR=" + (dir / "cache").string() + " ";
  const int status = std::system((env + WLX_BINARY + " export mjcf --model-file " + WLX_EXCAVATOR_MODEL_FILE + " --out " +
                                  (dir / "file.xml").string() + " > /dev/null 2>&1").c_str());
  REQUIRE(WEXITSTATUS(status) == 0);
  CHECK(slurp(dir / "file.xml") == xml);
  // Nothing left beside the files (they were written under temporary names and renamed).
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  CHECK(names == std::vector<std::string>{"builtin.xml", "cache", "file.xml"});
  fs::remove_all(dir);
}

TEST_CASE("cli: wlx export mjcf refuses --params and --scenarios with exit code 2, naming the option") {
  const Run params = run_wlx("export mjcf --params /dev/null --out /tmp/wlx_cli_never.xml");
  CHECK(params.code == 2);
  CHECK(params.err.find("--params: the export writes the model at its description's parameter values") != std::string::npos);
  const Run scenarios = run_wlx("export mjcf --scenarios /tmp --out /tmp/wlx_cli_never.xml");
  CHECK(scenarios.code == 2);
  CHECK(!fs::exists("/tmp/wlx_cli_never.xml"));
  const Run missing = run_wlx("export");
  CHECK(missing.code == 2);
}
