// The shipped scenario files: each runs, keeps both wheels from sliding, and shows the thesis'
// observations (docs/excavator.md section 8).
#include "../helpers/units.hpp"

#include <doctest/doctest.h>
#include <fmt/format.h>
#include <scenario_io.hpp>
#include <wlx/error.hpp>

#include <cmath>
#include <map>
#include <numbers>

using namespace wlx;
namespace c = gen::coord;

namespace {

using test::kDeg;

const Trajectory& run(const std::string& id) {
  static std::map<std::string, Trajectory> cache;
  auto it = cache.find(id);
  if (it == cache.end()) it = cache.emplace(id, simulate(commands::parse_scenario(commands::read_scenario_json(id)))).first;
  return it->second;
}

double end(const std::string& id, int coordinate) { return run(id).samples.back().s(coordinate); }

}  // namespace

TEST_CASE("scenarios: one file per NH and ST row of docs/excavator.md section 8, each sign separately") {
  const auto ids = commands::scenario_ids();
  for (const char* id : {"NH-1", "NH-2", "NH-3", "NH-4", "ST-A1+", "ST-A1-", "ST-A2+", "ST-A2-", "ST-A3+", "ST-A3-",
                         "ST-B1+", "ST-B1-", "ST-B2+", "ST-B2-", "ST-B3+", "ST-B3-"})
    CHECK(std::find(ids.begin(), ids.end(), id) != ids.end());
}

TEST_CASE("scenarios: every shipped NH/ST run completes with |v_W . n_W| <= 1e-12 at every step") {
  for (const auto& id : commands::scenario_ids()) {
    if (id.rfind("NH", 0) != 0 && id.rfind("ST", 0) != 0) continue;
    CAPTURE(id);
    const Trajectory& tr = run(id);
    CHECK(tr.complete);
    double worst = 0;
    for (const auto& smp : tr.samples) worst = std::max(worst, smp.nh_residual.cwiseAbs().maxCoeff());
    CHECK(worst <= 1e-12);
    const auto sc = commands::parse_scenario(commands::read_scenario_json(id));
    CHECK(static_cast<long>(tr.samples.size()) == sc.samples());
  }
}

TEST_CASE("scenarios: ST-A1: increasing roll makes yaw and y_C decrease; decreasing roll the opposite") {
  CHECK(end("ST-A1+", c::yaw) < 0);
  CHECK(end("ST-A1+", c::y_C) < 0);
  CHECK(end("ST-A1-", c::yaw) > 0);
  CHECK(end("ST-A1-", c::y_C) > 0);
  // Monotonic along the run.
  const auto& tr = run("ST-A1+");
  for (std::size_t k = 1; k < tr.samples.size(); ++k) CHECK(tr.samples[k].s(c::yaw) < tr.samples[k - 1].s(c::yaw));
}

TEST_CASE("scenarios: ST-A2: a positive left straddle steers left, y_C and yaw combining; ST-A3 mirrors it") {
  CHECK(end("ST-A2+", c::yaw) > 0);
  CHECK(end("ST-A2+", c::y_C) > 0);
  CHECK(end("ST-A2-", c::yaw) < 0);
  CHECK(end("ST-A2-", c::y_C) < 0);
  // Mirror image: the right lever turns the other way by nearly the same amount (the 5 cm
  // step under the right wheel breaks the symmetry slightly).
  CHECK(end("ST-A3+", c::yaw) == doctest::Approx(-end("ST-A2+", c::yaw)).epsilon(0.01));
  CHECK(end("ST-A3+", c::y_C) == doctest::Approx(-end("ST-A2+", c::y_C)).epsilon(0.02));
  CHECK(end("ST-A3-", c::yaw) == doctest::Approx(-end("ST-A2-", c::yaw)).epsilon(0.01));
}

TEST_CASE("scenarios: ST-B: with the straddle angles dependent, roll, yaw and y_C move alone") {
  for (const char* id : {"ST-B1+", "ST-B1-"}) {
    CAPTURE(id);
    CHECK(end(id, c::yaw) == 0.0);
    CHECK(end(id, c::y_C) == 0.0);
    CHECK(std::abs(end(id, c::roll)) == doctest::Approx(20 * kDeg));
    CHECK(std::abs(end(id, c::theta_l5)) > 1 * kDeg);  // the straddle angles follow
  }
  for (const char* id : {"ST-B2+", "ST-B2-"}) {
    CAPTURE(id);
    CHECK(std::abs(end(id, c::yaw)) == doctest::Approx(20 * kDeg));
    CHECK(end(id, c::y_C) == 0.0);
    CHECK(std::abs(end(id, c::theta_l5)) > 1 * kDeg);
    CHECK(std::abs(end(id, c::theta_r5)) > 1 * kDeg);
  }
  for (const char* id : {"ST-B3+", "ST-B3-"}) {
    CAPTURE(id);
    CHECK(std::abs(end(id, c::y_C)) == doctest::Approx(1.0));
    CHECK(end(id, c::yaw) == 0.0);
    CHECK(end(id, c::theta_l5) * end(id, c::y_C) > 0);  // both levers swing towards the motion
    CHECK(end(id, c::theta_r5) * end(id, c::y_C) > 0);
  }
}

TEST_CASE("scenarios: {\"deg\": x} for an initial angle and {\"deg/s\": x} for an angular rate are x * pi / 180 in SI") {
  const auto parse = [](const std::string& initial_roll, const std::string& roll_rate) {
    return commands::parse_scenario(nlohmann::json::parse(R"({"dependent": ["y_C", "yaw"], "duration": 1, "initial": {"roll": )" +
                                                          initial_roll + R"(}, "rates": {"roll": )" + roll_rate + "}}"));
  };
  const auto in_degrees = parse(R"({"deg": 3})", R"({"deg/s": -5})");
  const auto in_si = parse("0.05235987755982988", "-0.08726646259971647");  // 3 deg, -5 deg/s
  const int roll = c::roll;
  CHECK(in_degrees.initial(roll) == in_si.initial(roll));
  CHECK(in_degrees.rates(roll) == in_si.rates(roll));
}

TEST_CASE("scenarios: bad scenario files get messages naming the field") {
  const auto message = [](const std::string& text) {
    try {
      commands::parse_scenario(nlohmann::json::parse(text));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(message(R"({"dependent": ["y_C", "yaw"], "duration": 1, "rates": {"rol": 1}})") ==
        "rates.rol: unknown key; did you mean 'roll'?");
  CHECK(message(R"({"dependent": ["y_C", "yaw"], "duration": 1, "rates": {"x_C": {"deg/s": 3}}})") ==
        "rates.x_C: only angles may be given in degrees; give this value in SI units");
  // One degree form per quantity: an angle in "deg", an angular rate in "deg/s"; the other is a mistake.
  CHECK(message(R"({"dependent": ["y_C", "yaw"], "duration": 1, "initial": {"roll": {"deg/s": 3}}})") ==
        "initial.roll: expected a number or {\"deg\": x}, got {\"deg/s\":3}");
  CHECK(message(R"({"dependent": ["y_C", "yaw"], "duration": 1, "rates": {"roll": {"deg": 3}}})") ==
        "rates.roll: expected a number or {\"deg/s\": x}, got {\"deg\":3}");
  CHECK(message(R"({"dependent": ["y_C"], "duration": 1})") == "dependent: must be an array of 2 names, got [\"y_C\"]");
  CHECK(message(R"({"dependent": ["y_C", "yaw"]})") == "duration: missing: the run's length in seconds");
  CHECK(message(R"({"dependent": ["y_C", "yaw"], "duration": 1, "integrator": "rk45"})") ==
        "integrator: must be \"rk4\", \"euler\" or \"dopri5\", got \"rk45\"");
  CHECK(message(R"({"dependent": ["y_C", "yaw"], "duration": 1, "dt": 0.3})") ==
        "dt: the duration 1 s is not a whole number of steps of 0.3 s");
  CHECK(message(R"({"dependent": ["y_C", "yaw"], "duration": 1, "params": {"m_M1": -3}})") ==
        "params.m_M1: a mass must be positive, got -3 kg");
  CHECK_THROWS_WITH_AS(commands::read_scenario_json("NH-7"), "SCENARIO: 'NH-7' is neither a file nor a scenario id; did you mean 'NH-1'?",
                       Error);
}

TEST_CASE("scenarios: a run driven by the torques of ID-1..3 retraces each (round trip), from the run or from its CSV columns") {
  struct Case { const char* id; const char* rates; };
  for (const Case& k : {Case{"ID-1", R"({"x_C": 3.0})"}, Case{"ID-2", R"({"roll": {"deg/s": -10}})"}, Case{"ID-3", R"({"z_C": -3.0})"}}) {
    const Trajectory& inverse = run(k.id);
    REQUIRE(inverse.complete);
    const std::string duration = fmt::format("{}", inverse.samples.back().t);
    const std::string common = std::string(R"({"rates": )") + k.rates + R"(, "duration": )" + duration +
                               R"(, "dt": 0.001, "integrator": "dopri5", "tolerance": 1e-12, "on_contact_loss": "continue", )";
    // The same torques written inline as the CSV's columns (t, tau_<actuator>), cubic between them.
    nlohmann::json table;
    table["interpolation"] = "cubic";
    for (const auto& smp : inverse.samples) table["t"].push_back(smp.t);
    for (int a = 0; a < kActuatedCount; ++a)
      for (const auto& smp : inverse.samples)
        table["tau_" + std::string(kActuatorNames[static_cast<std::size_t>(a)])].push_back(smp.tau(a));
    for (const nlohmann::json& torques : {nlohmann::json{{"run", k.id}}, table}) {
      nlohmann::json j = nlohmann::json::parse(common + R"("torques": null})");
      j["torques"] = torques;
      const Trajectory forward = simulate(commands::parse_scenario(j));
      CAPTURE(forward.error);
      REQUIRE(forward.complete);
      REQUIRE(forward.samples.size() == inverse.samples.size());
      double worst = 0;
      for (std::size_t i = 0; i < forward.samples.size(); ++i)
        worst = std::max(worst, (forward.samples[i].s - inverse.samples[i].s).cwiseAbs().maxCoeff());
      MESSAGE(std::string(k.id) << ": |s_forward - s_inverse| <= " << worst << " m or rad (dopri5 at 1e-12, cubic table at 1 ms)");
      CHECK(worst <= 1e-8);  // the issue's bound for the round trip at a tight tolerance
    }
  }
}

TEST_CASE("scenarios: bad torque sources get messages naming the field") {
  const auto message = [](const std::string& torques, const std::string& extra = "") {
    try {
      commands::parse_scenario(nlohmann::json::parse(R"({"duration": 0.01, "dt": 0.001, )" + extra + R"("torques": )" + torques + "}"));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(message(R"({"run": "ID-1"})", R"("weighting": 1, )") ==
        "torques: a run is driven by its rates (the weighting then splits their torques) or by torques, not both");
  CHECK(message(R"({"run": "NH-1"})") == "torques.run: 'NH-1' has no weighting: it is a kinematic run, and only an inverse-dynamics run computes torques");
  CHECK(message(R"({"run": "ID-9"})").find("did you mean") != std::string::npos);
  CHECK(message(R"({"t": [0, 0.01]})") == "torques: has \"t\" but no column \"tau_psi_l2\": a table gives every actuator's torque");
  CHECK(message(R"({"file": "/nonexistent/t.csv"})").starts_with("torques.file: /nonexistent/t.csv: "));
  CHECK(message(R"({"run": "ID-1", "file": "x.csv"})") == "torques: give exactly one of \"file\", \"run\" or the columns \"t\", \"tau_<actuator>\"");
  CHECK(message(R"({"run": "ID-1", "interpolation": "spline"})") == "torques.interpolation: must be \"linear\" or \"cubic\", got \"spline\"");
  std::string columns = R"({"t": [0, 0.005])";
  for (const std::string_view a : kActuatorNames) columns += ", \"tau_" + std::string(a) + "\": [0, 1]";
  CHECK(message(columns + "}") == "torques: the table covers t = 0 to 0.005 s; the run needs 0 to 0.01 s");
  CHECK(message(R"({"run": "ID-1"})", R"("rates": {"theta_l5": 1}, )").starts_with("rates.theta_l5: a forward-dynamics run commands only"));
}
