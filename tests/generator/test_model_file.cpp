// The model file reader: the excavator's file reads, and every class of mistake in a model file
// is reported with file:line:column, the field and the reason. Each case injects one mistake
// into the real excavator.yaml, so the reader sees a realistic file; the expected line is where
// the test put the mistake, not what the reader says.
#include "../../generator/model_file.hpp"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <fstream>
#include <sstream>

using namespace wlx::codegen;

namespace {

std::string excavator_text() {
  std::ifstream in(WLX_MODEL_FILE);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Mistake {
  const char* what;
  const char* find;     // text in excavator.yaml (first occurrence)
  const char* replace;  // what it becomes
  std::vector<const char*> message;  // fragments the error must contain
  bool check_line = true;            // the error points at the line of the mistake
};

}  // namespace

TEST_CASE("model file: the excavator reads, with the structure the thesis describes") {
  const Model m = load_model_file(WLX_MODEL_FILE);
  CHECK(m.name == "excavator");
  CHECK(m.coordinates.size() == 32);
  CHECK(m.input_count == 18);
  CHECK(m.closure.size() == 14);
  CHECK(m.frames.size() == 13);
  CHECK(m.bodies.size() == 7);
  CHECK(m.limbs.size() == 4);
  CHECK(m.wheels.size() == 2);
  CHECK(m.parameters.size() == 36);
  // The repetition writes the left side first, x y z inside: docs/excavator.md's coordinate order.
  CHECK(m.coordinates[6].name == "x_Fl");
  CHECK(m.coordinates[11].name == "z_Fr");
  CHECK(m.coordinates[31].name == "theta_r6");
  CHECK(m.parameter("m_M7").default_value == 157.08);
  CHECK(m.nominal[13] == 0.05);  // z_Wr
  CHECK(m.source.rfind("excavator.yaml, fingerprint ", 0) == 0);
}

TEST_CASE("model file: every kind of mistake names the place, the field and the reason") {
  const std::string good = excavator_text();
  const Mistake cases[] = {
      {"unknown symbol in an expression", "chain: [translate: [thighD, 0, 0]", "chain: [translate: [thighd, 0, 0]",
       {"frames", "unknown symbol 'thighd'", "did you mean 'thighD'"}},
      {"parent frame missing", "parent: hip_<side>", "parent: hipp_<side>", {"parent", "no frame 'hipp_l'", "did you mean 'hip_l'"}},
      {"frames in a cycle", "    parent: K0\n    chain: [tx: x_C", "    parent: F_l\n    chain: [tx: x_C",
       {"cycle", "C -> F_l"}, false},
      {"closure count differs from the dependent count",
       "      - {name: guidance_<side>, type: sum, coordinates: [theta_<side>4, theta_<side>5]}\n", "",
       {"12 closure conditions for 14 dependent joints"}, false},
      {"wheel on a frame that does not exist", "contact: W_<side>", "contact: Wheel_<side>", {"wheels", "contact", "no frame 'Wheel_l'"}},
      {"duplicate parameter", "{name: cyd, value: 3.0", "{name: cxd, value: 3.0", {"'cxd' is already the name of a parameter"}},
      {"duplicate coordinate name across kinds", "{name: pitch, unit: rad", "{name: wl, unit: rad",
       {"'wl' is already the name of a parameter"}},
      {"duplicate frame", "name: knee_<side>", "name: hip_<side>", {"frame 'hip_l' is defined twice"}},
      {"unit that does not fit the kind", "{name: thighD, value: 2.0, unit: m, kind: length",
       "{name: thighD, value: 2.0, unit: kg, kind: length", {"parameters", "unit", "kind length has unit m, not 'kg'"}},
      {"unknown kind", "{name: wl, value: 2.5, unit: m, kind: length", "{name: wl, value: 2.5, unit: m, kind: lenght",
       {"unknown kind 'lenght'", "did you mean 'length'"}},
      {"a length that is not positive", "{name: legD, value: 1.5", "{name: legD, value: -1.5", {"a length must be positive"}},
      {"a value that is not a number", "{name: cyd, value: 3.0", "{name: cyd, value: 3.0m", {"'3.0m' is not a number"}},
      {"unknown field", "    meaning: cabin frame K_C (origin r_C)", "    meanin: cabin frame K_C (origin r_C)",
       {"unknown field 'meanin'", "did you mean 'meaning'"}},
      {"missing field", "        parent: knee_<side>\n", "", {"missing field 'parent'"}, false},
      {"not valid YAML", "  - {name: cxd, value: 3.0,", "  - {name: cxd, value: [3.0,", {"not valid YAML"}, false},
      {"unknown repetition variable", "name: psi_<side>1", "name: psi_<sid>1", {"'<sid>' is not a repetition variable", "did you mean 'side'"}},
      {"unknown repetition table", "{for: side, name: z_W<side>", "{for: sides, name: z_W<side>", {"no repetition 'sides'"}},
      {"a revolute joint driven by a length", "rz: yaw", "rz: x_C", {"turns a revolute joint, so its unit must be rad"}},
      {"a prismatic joint driven by an angle", "ty: y_C", "ty: yaw", {"drives a prismatic joint, so its unit must be m"}},
      {"a joint driven by a coordinate and more", "rx: psi_<side>1", "rx: psi_<side>1 + 0.1", {"mixes coordinate 'psi_l1'"}},
      {"a coordinate driving two joints", "ry: pitch", "ry: yaw", {"coordinate 'yaw' already drives a joint"}},
      {"a coordinate where only parameters may appear", "com: [thighD/2, 0, 0]", "com: [x_C/2, 0, 0]",
       {"'x_C' is a coordinate; only parameters may appear"}},
      {"unknown function", "[cxd/2, <sign>*cyd/2, 0]", "[sinh(cxd)/2, <sign>*cyd/2, 0]", {"unknown function 'sinh'"}},
      {"expression that does not parse", "[cxd/2, <sign>*cyd/2, 0]", "[cxd/, <sign>*cyd/2, 0]", {"cannot read the expression 'cxd/'"}},
      {"unknown chain step", "ry: psi_<side>4]", "rw: psi_<side>4]", {"unknown chain step 'rw'"}},
      {"limb that is not square", "joints: [psi_<side>2, psi_<side>3, psi_<side>4]", "joints: [psi_<side>2, psi_<side>3]",
       {"limb 'leg_l' has 3 closure conditions and 2 joints"}, false},
      {"limbs that do not decouple", "joints: [psi_<side>2, psi_<side>3, psi_<side>4]",
       "joints: [psi_<side>2, psi_<side>3, theta_<side>2]", {"depends on joint 'psi_l4'", "the limbs must decouple"}, false},
      {"a joint in two limbs", "joints: [theta_<side>2, theta_<side>3, theta_<side>4, theta_<side>6]",
       "joints: [psi_<side>2, theta_<side>3, theta_<side>4, theta_<side>6]", {"joint 'psi_l2' already belongs to limb 'leg_l'"}},
      {"an input where a dependent joint is needed", "joints: [psi_<side>2, psi_<side>3, psi_<side>4]",
       "joints: [psi_<side>1, psi_<side>3, psi_<side>4]", {"'psi_l1' is an input; a dependent joint is needed here"}},
      {"unknown closure type", "type: level, frame: W_<side>, axis: x", "type: flat, frame: W_<side>, axis: x",
       {"needs `type: point`, `level` or `sum`", "not 'flat'"}},
      {"a point equal to an angle", "component: z, equals: z_W<side>", "component: z, equals: psi_<side>1",
       {"'psi_l1' is an angle"}},
      {"an axis that is not x, y or z", "component: z, equals: z_W<side>", "component: w, equals: z_W<side>",
       {"'w' is not an axis"}},
      {"a dependent rate that is not a candidate", "B: [theta_l5, theta_r5]", "B: [theta_l5, z_Wl]",
       {"'z_Wl' is not one of pair_candidates"}},
      {"a default pair that does not exist", "default_pair: A", "default_pair: C", {"no pair 'C' under pairs"}},
      {"a commanded speed in the dependent pair", "commanded: [z_C, x_C, roll, pitch]", "commanded: [z_C, y_C, roll, pitch]",
       {"a commanded rate cannot be one of the dependent pair"}},
      {"weights that do not match the actuators", "weights: [0.01, 100, 1, 0.01, 100, 1, 0.01, 0.01]",
       "weights: [0.01, 100, 1, 0.01, 100, 1, 0.01]", {"one weight per actuated joint: 8 needed"}},
      {"a weight that is not positive", "weights: [0.01, 100, 1,", "weights: [0.01, -100, 1,", {"a weight must be positive"}},
      {"a body mass that is not a mass parameter", "mass: m_M1,", "mass: cxd,", {"'cxd' is a parameter of kind length; one of kind mass"}},
      {"a nominal value for an unknown input", "  z_Wr: 0.05", "  z_Wx: 0.05", {"no coordinate 'z_Wx'", "did you mean"}},
      {"a name the generated code uses itself", "{name: pitch, unit: rad", "{name: t12, unit: rad",
       {"'t12' cannot be used as a name", "intermediate terms"}},
      {"a C++ keyword as a name", "{name: roll, unit: rad", "{name: int, unit: rad", {"'int' cannot be used as a name", "C++ keyword"}},
      {"a name that is not an identifier", "{name: roll, unit: rad", "{name: 2roll, unit: rad", {"'2roll' is not a name"}},
      {"a power that would not finish", "[cxd/2, <sign>*cyd/2, 0]", "[cxd/2, 9^9^9, 0]", {"an exponent is a small integer"}},
      {"flow collections nested too deep", "  - {name: cxd, value: 3.0,", "  - {name: cxd, value: [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[3]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]],",
       {"nest more than 64 levels"}, false},
      {"a gravity parameter of the wrong kind", "  gravity: g", "  gravity: w", {"'w' is a parameter of kind length; one of kind gravity"}},
  };
  for (const Mistake& c : cases) {
    CAPTURE(c.what);
    std::string text = good;
    const auto at = text.find(c.find);
    REQUIRE_MESSAGE(at != std::string::npos, "the test's anchor text is not in excavator.yaml: " << c.find);
    text.replace(at, std::string(c.find).size(), c.replace);
    std::string message;
    try {
      parse_model(text, "excavator.yaml");
    } catch (const ModelFileError& e) {
      message = e.what();
    }
    CAPTURE(message);
    REQUIRE_MESSAGE(!message.empty(), "the mistake was accepted");
    for (const char* fragment : c.message) CHECK(message.find(fragment) != std::string::npos);
    // file:line:column: field: reason
    CHECK(message.rfind("excavator.yaml:", 0) == 0);
    if (c.check_line) {
      const long line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(at), '\n');
      CHECK(message.rfind(fmt::format("excavator.yaml:{}:", line), 0) == 0);
    }
  }
}

TEST_CASE("model file: a file that is not there or not a map") {
  CHECK_THROWS_WITH_AS(load_model_file("/nonexistent/model.yaml"), doctest::Contains("cannot open the model file"), ModelFileError);
  CHECK_THROWS_WITH_AS(parse_model("- a\n- b\n", "x.yaml"), doctest::Contains("must be a YAML map"), ModelFileError);
  CHECK_THROWS_WITH_AS(parse_model("model: m\n", "x.yaml"), doctest::Contains("missing field 'parameters'"), ModelFileError);
}
