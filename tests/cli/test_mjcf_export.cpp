// `wlx export mjcf`'s refusals and quoting (cli/shell/mjcf_export.hpp), on the excavator's
// description edited to take each path: what the export cannot express is an error naming the
// closure row, a description without the fields it reads says so, names are quoted for XML, and a
// wheel on a hub whose bodies are not the wheel's alone spins with a placeholder, said. The
// agreement of an export with the generated functions is tests/bench/test_mujoco_peer.cpp's.
#include <mjcf_export.hpp>

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>
#include <wlx/error.hpp>

#include <fstream>
#include <sstream>
#include <string>

namespace {

using namespace wlx;
using Json = nlohmann::json;

Json excavator() {
  std::ifstream in(WLX_EXCAVATOR_DESCRIPTION);
  REQUIRE_MESSAGE(in, WLX_EXCAVATOR_DESCRIPTION);
  std::ostringstream s;
  s << in.rdbuf();
  return Json::parse(s.str());
}

std::string refusal(const Json& d) {
  try {
    cli::mjcf_of_description(d.dump());
  } catch (const Error& e) {
    return e.what();
  }
  return "(exported)";
}

}  // namespace

TEST_CASE("mjcf export: a closure row it cannot express is an error naming the row") {
  Json d = excavator();
  d["closure"].push_back({{"name", "inner_x"}, {"type", "point"}, {"frame", "knee_l"}, {"component", "x"}, {"equals", "x_C"}});
  CHECK(refusal(d) == "closure.inner_x: holds frame knee_l inside the machine (point row), which the export cannot express");
  d = excavator();
  d["closure"].push_back({{"name", "one"}, {"type", "sum"}, {"coordinates", {"psi_l1"}}});
  CHECK(refusal(d) == "closure.one: is a sum of fewer than two coordinates");
  d = excavator();
  d["closure"].push_back({{"name", "of_input"}, {"type", "sum"}, {"coordinates", {"x_Fl", "psi_l2"}}});
  CHECK(refusal(d) == "closure.of_input: sums a coordinate that is no joint of the tree, which the export cannot express");
  d = excavator();
  d["closure"][0]["type"] = "angle";
  CHECK(refusal(d).find("has type 'angle', which the export does not know") != std::string::npos);
}

TEST_CASE("mjcf export: a sum of three coordinates is a fixed tendon held at zero") {
  Json d = excavator();
  d["closure"].push_back({{"name", "three"}, {"type", "sum"}, {"coordinates", {"psi_l2", "psi_l3", "psi_l4"}}});
  const std::string xml = cli::mjcf_of_description(d.dump()).xml;
  CHECK(xml.find("<fixed name=\"three\">\n      <joint joint=\"psi_l2\" coef=\"1\"/>\n      <joint joint=\"psi_l3\" coef=\"1\"/>\n"
                 "      <joint joint=\"psi_l4\" coef=\"1\"/>\n    </fixed>") != std::string::npos);
  CHECK(xml.find("<tendon name=\"three\" tendon1=\"three\"/>") != std::string::npos);
}

TEST_CASE("mjcf export: a description without the fields it reads, or with a bad one, names the field") {
  Json d = excavator();
  d["frames"][1].erase("chain");
  CHECK(refusal(d) == "frames.hip_l.chain: missing (regenerate the model with this wlx-gen)");
  d = excavator();
  d["frames"][1]["chain"][0] = {{"translate", {1.0, "x", 0.0}}};
  CHECK(refusal(d) == "frames.hip_l.chain[0].translate: is not a number");
  d = excavator();
  d["bodies"][0]["mass"] = "no_such_mass";
  CHECK(refusal(d) == "bodies.M1.mass: names no parameter ('no_such_mass')");
  d = excavator();
  d["frames"][1]["parent"] = "nowhere";
  CHECK(refusal(d) == "frames.hip_l.parent: names no frame ('nowhere')");
  CHECK_THROWS_AS(cli::mjcf_of_description("{\"model\": "), Error);
}

TEST_CASE("mjcf export: names are quoted for XML, and two joints of one name are refused") {
  Json d = excavator();
  d["frames"][1]["name"] = "hip <&\"'> l";
  for (auto& f : d["frames"])
    if (f["parent"] == "hip_l") f["parent"] = "hip <&\"'> l";
  for (auto& b : d["bodies"])
    if (b["frame"] == "hip_l") b["frame"] = "hip <&\"'> l";
  const std::string xml = cli::mjcf_of_description(d.dump()).xml;
  CHECK(xml.find("<body name=\"hip &lt;&amp;&quot;&#39;&gt; l\"") != std::string::npos);
  CHECK(xml.find("hip <") == std::string::npos);
  d = excavator();
  d["frames"][4]["chain"][1]["coordinate"] = "psi_l1";  // hip_r's first joint named as hip_l's
  CHECK(refusal(d) == "frames.hip_r: joint 'psi_l1' is named twice");
}

TEST_CASE("mjcf export: a wheel on a hub spins with the hub's bodies only where they are the wheel's alone") {
  // The excavator's wheels are contact frames its file builds; made a wheel on a hub here: the
  // hub lever_end_l carries no body, so the spinning wheel gets a placeholder and says so.
  Json d = excavator();
  d["wheels"][0]["hub"] = "lever_end_l";
  const cli::MjcfExport with_placeholder = cli::mjcf_of_description(d.dump());
  CHECK(with_placeholder.placeholders.find("wheel l: its spinning body holds a placeholder") != std::string::npos);
  CHECK(with_placeholder.xml.find("<body name=\"spin_l\"") != std::string::npos);
  // A body of the wheel's own on the hub, its CoM on the axle and its inertia the same across it:
  // the spinning body takes it whole (no placeholder).
  d["bodies"].push_back({{"name", "wheel_l"}, {"frame", "lever_end_l"}, {"mass", "m_M6"}, {"inertia", {"Ixx_M6", "Ixx_M6", "Ixx_M6"}},
                         {"com", {0.0, 0.0, 0.0}}, {"principal_axes", {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}}});
  const cli::MjcfExport whole = cli::mjcf_of_description(d.dump());
  CHECK(whole.placeholders.find("wheel l") == std::string::npos);
  // Moved off the axle, it no longer spins with the wheel: the placeholder again.
  d["bodies"].back()["com"] = {0.0, 0.0, 0.1};
  CHECK(cli::mjcf_of_description(d.dump()).placeholders.find("wheel l: its spinning body holds a placeholder") != std::string::npos);
}
