// model.json read into the runtime's settings (cli/commands/description.hpp): the description wlx-gen
// writes beside the excavator's headers gives exactly the numbers its settings.hpp compiles in (two
// emitters of the same model file, compared), and a description of other code is refused by name.
#include <description.hpp>

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>
#include <wlx/error.hpp>

#include <fstream>
#include <sstream>
#include <string>

namespace {

using namespace wlx;

std::string description_text() {
  std::ifstream in(WLX_EXCAVATOR_DESCRIPTION);
  REQUIRE_MESSAGE(in, WLX_EXCAVATOR_DESCRIPTION);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string refusal(const nlohmann::json& d) {
  try {
    commands::settings_of_description(d.dump());
  } catch (const Error& e) {
    return e.what();
  }
  return "accepted";
}

}  // namespace

TEST_CASE("model.json: the excavator's description gives the numbers its settings.hpp compiles in") {
  const Settings s = commands::settings_of_description(description_text());
  const Settings& compiled = settings();
  for (const auto& info : gen::kParamInfo) {
    CAPTURE(info.name);
    CHECK(s.params.*info.member == compiled.params.*info.member);
  }
  CHECK(s.nominal_inputs == compiled.nominal_inputs);
  CHECK(s.dependent_start == compiled.dependent_start);
  CHECK(s.sweep_start == compiled.sweep_start);
  REQUIRE(s.ik_sweeps.size() == compiled.ik_sweeps.size());
  for (std::size_t k = 0; k < s.ik_sweeps.size(); ++k) {
    CAPTURE(compiled.ik_sweeps[k].id);
    CHECK(s.ik_sweeps[k].id == compiled.ik_sweeps[k].id);
    CHECK(s.ik_sweeps[k].input == compiled.ik_sweeps[k].input);
    CHECK(s.ik_sweeps[k].from == compiled.ik_sweeps[k].from);
    CHECK(s.ik_sweeps[k].to == compiled.ik_sweeps[k].to);
    CHECK(s.ik_sweeps[k].step == compiled.ik_sweeps[k].step);
    CHECK(s.ik_sweeps[k].degrees == compiled.ik_sweeps[k].degrees);
    CHECK(s.ik_sweeps[k].limb == compiled.ik_sweeps[k].limb);
  }
  CHECK(s.weights == compiled.weights);
  CHECK(s.has_torque_limits == compiled.has_torque_limits);
  CHECK(s.friction == compiled.friction);
  // The thesis' numbers, as a reader of the file would quote them (not from either emitter).
  CHECK(s.params.thighD == 2.0);
  CHECK(s.nominal_inputs[gen::coord::z_Wr] == 0.05);
  CHECK(s.ik_sweeps.size() == 12);
}

TEST_CASE("model.json: a description of other code is refused, naming what differs") {
  const nlohmann::json d = nlohmann::json::parse(description_text());
  nlohmann::json other = d;
  other["model"] = "walker";
  CHECK(refusal(other).find("it describes model 'walker', not 'excavator'") != std::string::npos);
  other = d;
  other["parameters"].erase(other["parameters"].begin());
  CHECK(refusal(other).find("it has 35 parameters, the code 36") != std::string::npos);
  other = d;
  other["settings"]["nominal"].erase("z_C");
  CHECK(refusal(other).find("settings.nominal does not hold exactly 18 values") != std::string::npos);
  other = d;
  other["settings"]["weights"].push_back(1.0);
  CHECK(refusal(other).find("settings.weights does not hold exactly 8 numbers") != std::string::npos);
  other = d;
  other["settings"]["ik_sweeps"][0]["limb"] = "arm";
  CHECK(refusal(other).find("settings.ik_sweeps.IK-L1: the code has no limb 'arm'") != std::string::npos);
  other = d;
  other["settings"]["friction"][0] = "high";
  CHECK(refusal(other).find("settings.friction[0] is not a number") != std::string::npos);
  CHECK(refusal(nlohmann::json::array()).find("it is not a wlx model description of format 1") != std::string::npos);
  // Well-formed, but a number the runtime cannot use: set_settings names it and keeps the old ones.
  other = d;
  other["settings"]["weights"][2] = -1.0;
  const std::string message = commands::load_description(other.dump());
  CHECK(message == "model.json: dynamics.weights.psi_l4: must be positive, got -1");
  CHECK(settings().weights[2] == 1.0);
}
