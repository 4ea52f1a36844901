// The model file reader: the excavator's file reads, and every class of mistake in a model file
// is reported with file:line:column, the field and the reason. Each case injects one mistake
// into the real excavator.yaml, so the reader sees a realistic file; the expected line is where
// the test put the mistake, not what the reader says.
#include "../../generator/model_file.hpp"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

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
      {"gravity that is negative", "{name: g, value: 9.81,", "{name: g, value: -9.81,", {"gravity must be non-negative, got -9.81"}},
      // 1e308 deg is 1.7e306 rad: the sweep's bound, not an overflow, is what refuses it.
      {"a sweep of 1e308 degrees", "from: -30, to: 30, step: 0.1", "from: -1e308, to: 1e308, step: 0.1", {"step: more than 10^6 points"}},
      {"a body mass that is not a mass parameter", "mass: m_M1,", "mass: cxd,", {"'cxd' is a parameter of kind length; one of kind mass"}},
      {"a nominal value for an unknown input", "  z_Wr: 0.05", "  z_Wx: 0.05", {"no coordinate 'z_Wx'", "did you mean"}},
      {"a name the generated code uses itself", "{name: pitch, unit: rad", "{name: t12, unit: rad",
       {"'t12' cannot be used as a name", "intermediate terms"}},
      {"a C++ keyword as a name", "{name: roll, unit: rad", "{name: int, unit: rad", {"'int' cannot be used as a name", "C++ keyword"}},
      {"a name that is not an identifier", "{name: roll, unit: rad", "{name: 2roll, unit: rad", {"'2roll' is not a name"}},
      {"a power that would not finish", "[cxd/2, <sign>*cyd/2, 0]", "[cxd/2, 9^9^9, 0]", {"an exponent is a small integer"}},
      {"flow collections nested too deep", "  - {name: cxd, value: 3.0,", "  - {name: cxd, value: [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[3]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]],",
       {"nest more than 64 levels"}, false},
      {"a gravity parameter of the wrong kind", "  gravity: g", "  gravity: w", {"'w' is a parameter of kind length; one of kind gravity"}},
      {"a drive for a wheel whose contact frame the file builds", "actuated: [psi_l2,", "actuated: [{wheel: l}, psi_l2,",
       {"wheel 'l' has no hub", "actuate that joint instead"}},
      {"a drive for a wheel that does not exist", "actuated: [psi_l2,", "actuated: [{wheel: ll}, psi_l2,",
       {"no wheel 'll' under wheels", "did you mean 'l'?"}},
      {"a drive with an unknown field", "actuated: [psi_l2,", "actuated: [{wheel: l, torque: 3}, psi_l2,",
       {"unknown field 'torque'", "wheel, name"}},
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

// ---- hostile files (issue 26): bounded, no recursion the file controls, names and text checked ----

namespace {

// The smallest model the reader takes, with `frames` and `extra` put in.
std::string tiny_model(const std::string& frames, const std::string& extra = "", const std::string& name = "tiny") {
  return "model: " + name +
         "\n"
         "parameters:\n"
         "  - {name: a, value: 0.5, unit: m, kind: length, meaning: a length}\n"
         "coordinates:\n"
         "  inputs:\n"
         "    - {name: q, unit: rad, meaning: a joint}\n" +
         extra + "frames:\n" + frames;
}

std::string error_of(const std::string& text) {
  try {
    parse_model(text, "hostile.yaml");
  } catch (const ModelFileError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("model file: the tiny model the hostile cases start from reads") {
  CHECK(error_of(tiny_model("  - {name: base, parent: K0, chain: [rz: q]}\n")) == "");
}

TEST_CASE("model file: a key given twice, or a key that is a list or a map, is reported with its place") {
  const std::string frames = "  - {name: base, parent: K0, chain: [rz: q]}\n";
  // (the file, the whole message): the places are counted in the text here (tiny_model: 8 lines).
  const std::pair<std::string, std::string> cases[] = {
      {tiny_model(frames) + "model: other\n", "hostile.yaml:9:1: model: given twice (first at line 1)"},
      {tiny_model("  - {name: base, parent: K0, name: other, chain: [rz: q]}\n"),
       "hostile.yaml:8:30: frames[0].name: given twice (first at line 8)"},
      {tiny_model(frames) + "nominal:\n  q: 0.1\n  q: 0.2\n", "hostile.yaml:11:3: nominal.q: given twice (first at line 10)"},
      {tiny_model(frames) + "? [a, b]\n: 1\n", "hostile.yaml:9:3: a key is a list: keys are names"},
      {tiny_model("  - {name: base, parent: K0, chain: [{[1]: 2}]}\n"),
       "hostile.yaml:8:39: frames[0].chain[0]: a key is a list: keys are names"},
      {tiny_model(frames) + "? {a: 1}\n: 1\n", "hostile.yaml:9:3: a key is a map: keys are names"},
  };
  for (const auto& c : cases) CHECK(error_of(c.first) == c.second);
}

TEST_CASE("model file: nesting is bounded with a message naming the limit; brackets in strings and comments do not count") {
  const std::string frames = "  - {name: base, parent: K0, chain: [rz: q]}\n";
  const std::string brackets(70, '[');
  CHECK(error_of(tiny_model(frames) + "description: \"" + brackets + "\"\n") == "");
  CHECK(error_of(tiny_model(frames) + "description: '" + brackets + "'\n") == "");
  CHECK(error_of(tiny_model(frames) + "# " + brackets + "\n") == "");
  CHECK(error_of(tiny_model(frames + "  # " + brackets + "\n")) == "");
  // Block lists 600 deep: yaml-cpp's own guard (500) said only "bad file".
  std::string deep = "description:\n";
  for (int k = 0; k < 600; ++k) deep += "- ";
  const std::string message = error_of(tiny_model(frames) + deep + "x\n");
  CAPTURE(message);
  CHECK(message == "hostile.yaml:10:127: lists and maps nest more than 64 levels deep (the limit)");  // the 64th "- "
}

TEST_CASE("model file: a cycle through 10^5 frames is an error, not a stack overflow") {
  // Each frame's parent is the next; the last one's is the first. Read recursively, this
  // overflowed the generator's stack (SIGSEGV).
  constexpr int n = 100000;
  std::string frames;
  for (int k = 0; k < n; ++k) frames += fmt::format("  - {{name: f{}, parent: f{}, chain: []}}\n", k, (k + 1) % n);
  const std::string message = error_of(tiny_model(frames));
  CAPTURE(message);
  CHECK(message.find("more than 4096 list entries") != std::string::npos);
  // Within the entry bound but beyond the frame bound.
  std::string many;
  for (int k = 0; k < 1000; ++k) many += fmt::format("  - {{name: f{}, parent: K0, chain: []}}\n", k);
  CHECK(error_of(tiny_model(many)).find("has 1000 frames; a model has at most 512") != std::string::npos);
}

TEST_CASE("model file: a cycle through 500 frames is named, shortened; a chain 100 deep is refused") {
  std::string frames;
  for (int k = 0; k < 500; ++k) frames += fmt::format("  - {{name: f{}, parent: f{}, chain: []}}\n", k, (k + 1) % 500);
  const std::string cycle = error_of(tiny_model(frames));
  CAPTURE(cycle);
  CHECK(cycle.find("the frames' parents form a cycle: f0 -> f1 -> f2 -> f3 -> f4 -> ... -> f496 -> f497 -> f498 -> f499 -> f0 (500 frames)") !=
        std::string::npos);
  std::string chain = "  - {name: f0, parent: K0, chain: [rz: q]}\n";
  for (int k = 1; k < 100; ++k) chain += fmt::format("  - {{name: f{}, parent: f{}, chain: [tx: a]}}\n", k, k - 1);
  const std::string deep = error_of(tiny_model(chain));
  CAPTURE(deep);
  CHECK(deep.find("frame 'f64' is 65 frames away from K0, more than 64") != std::string::npos);
  // 64 deep is a chain the reader takes (the bound is inclusive); parents listed after their
  // children are found without recursion too.
  std::string ok = "  - {name: f0, parent: K0, chain: [rz: q]}\n";
  for (int k = 63; k >= 1; --k) ok += fmt::format("  - {{name: f{}, parent: f{}, chain: [tx: a]}}\n", k, k - 1);
  CHECK(error_of(tiny_model(ok)) == "");
}

TEST_CASE("model file: a repeat product of 10^9 rows is refused before anything is expanded") {
  // Nine tables of ten rows, crossed: 10^9 frames from a file of about 2 KB.
  std::string repeat = "repeat:\n";
  std::string tables, name = "f";
  for (int t = 0; t < 9; ++t) {
    repeat += fmt::format("  r{}:\n", t);
    for (int row = 0; row < 10; ++row) repeat += fmt::format("    - {{v{}: {}}}\n", t, row);
    tables += fmt::format("{}r{}", t ? ", " : "", t);
    name += fmt::format("<v{}>", t);
  }
  const std::string frames = fmt::format("  - for: [{}]\n    name: {}\n    parent: K0\n    chain: []\n", tables, name);
  const std::string message = error_of(tiny_model(frames, repeat));
  CAPTURE(message);
  CHECK(message.find("repeats its entry more than 4096 times") != std::string::npos);
}

TEST_CASE("model file: expressions are bounded in length and nesting") {
  const auto with = [](const std::string& expression) {
    return error_of(tiny_model(fmt::format("  - {{name: base, parent: K0, chain: [rz: q, tx: {}]}}\n", expression)));
  };
  CHECK(with(std::string(40, '(') + "a" + std::string(40, ')')).find("nest more than 32 deep") != std::string::npos);
  CHECK(with(std::string(40, '-') + "a").find("nest more than 32 deep") != std::string::npos);
  CHECK(with(std::string(32, '(') + "a" + std::string(32, ')')) == "");  // the bound itself is taken
  std::string sum = "a";
  while (sum.size() < 2000) sum += " + a";
  CHECK(with(sum).find("bytes; at most 1024") != std::string::npos);
}

TEST_CASE("model file: a name that is a keyword, a macro of the compiler or the headers, std or Eigen is refused, for every kind of name") {
  // Each of these compiles into the headers as an identifier (a frame's constant, a body's, the
  // model's namespace) and breaks them: `unix` and `linux` are 1 under GNU modes, M_PI and EOF
  // expand to numbers, errno to a function call.
  const char* names[] = {"unix", "linux", "errno", "assert", "stdin", "M_PI", "M_PIf", "EOF", "NAN", "INT_MAX", "EIGEN_ALIGN",
                         "std", "Eigen", "int", "and", "override", "__x", "_x", "isnan"};
  for (const char* n : names) {
    CAPTURE(n);
    const std::string frame = error_of(tiny_model(fmt::format("  - {{name: {}, parent: K0, chain: [rz: q]}}\n", n)));
    CHECK(frame.find(fmt::format("'{}' cannot be used as a name", n)) != std::string::npos);
    const std::string model = error_of(tiny_model("  - {name: base, parent: K0, chain: [rz: q]}\n", "", n));
    CHECK(model.find(fmt::format("'{}' cannot be", n)) != std::string::npos);
  }
  for (const char* n : {"wlx", "gen", "text", "detail"})
    CHECK(error_of(tiny_model("  - {name: base, parent: K0, chain: [rz: q]}\n", "", n)).find("wlx and its runtime use that namespace name") !=
          std::string::npos);
  // Names like these are fine: lower case, or short upper case (frame C, body M1 of the excavator).
  for (const char* n : {"C", "M1", "hip_l", "Fl", "unix_like", "m_pi"})
    CHECK(error_of(tiny_model(fmt::format("  - {{name: {}, parent: K0, chain: [rz: q]}}\n", n))) == "");
  CHECK(cpp_name_problem("M_PI") != "");
  CHECK(cpp_name_problem("hip") == "");
}

TEST_CASE("model file: text is one line of printable UTF-8, also where a repetition variable puts it in") {
  const auto meaning = [](const std::string& yaml_value, const std::string& extra = "") {
    return error_of(tiny_model(fmt::format("  - {{name: base, parent: K0, chain: [rz: q], meaning: {}}}\n", yaml_value), extra));
  };
  CHECK(meaning("\"two\\nlines\"").find("has a line break at byte 3") != std::string::npos);
  CHECK(meaning("\"nul\\0\"").find("control character U+0000") != std::string::npos);
  CHECK(meaning("\"bell\\a\"").find("control character U+0007") != std::string::npos);
  CHECK(meaning("'back\\slash'").find("has a backslash") != std::string::npos);
  CHECK(meaning("\"next\\u2028line\"").find("control character U+2028") != std::string::npos);
  CHECK(meaning("'quotes \" and */ and ?\?/ are fine: quoted where written'") == "");
  // A repetition row's value is text of the file too: checked after it is put in.
  const std::string repeat = "repeat:\n  side:\n    - {s: \"x\\n#define evil 1\"}\n";
  const std::string message = error_of(tiny_model("  - {for: side, name: base, parent: K0, chain: [rz: q], meaning: side <s>}\n", repeat));
  CAPTURE(message);
  CHECK(message.find("has a line break") != std::string::npos);
}

TEST_CASE("model file: only a regular file of at most 1 MiB is read") {
  CHECK_THROWS_WITH_AS(load_model_file("/dev/zero"), doctest::Contains("is a device, not a regular file"), ModelFileError);
  CHECK_THROWS_WITH_AS(load_model_file("/"), doctest::Contains("is a folder"), ModelFileError);
  const std::string dir = fmt::format("/tmp/wlx_model_file_{}", static_cast<long>(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string fifo = dir + "/model.fifo", big = dir + "/big.yaml";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  // No writer: the reader must not wait for one.
  CHECK_THROWS_WITH_AS(load_model_file(fifo), doctest::Contains("is a pipe (FIFO)"), ModelFileError);
  std::ofstream(big) << tiny_model("  - {name: base, parent: K0, chain: [rz: q]}\n") << std::string(kMaxModelFileBytes, '#');
  CHECK_THROWS_WITH_AS(load_model_file(big), doctest::Contains("more than the limit of 1048576 bytes"), ModelFileError);
  std::filesystem::remove_all(dir);
}

TEST_CASE("model file: an expression that is NaN, complex, infinite or singular at the default parameters names its field") {
  const auto with = [](const std::string& expression) {
    return error_of(tiny_model(fmt::format("  - {{name: base, parent: K0, chain: [rz: q, tx: {}]}}\n", expression)));
  };
  // acos(2) was emitted as code computing sqrt(-3): NaN in every call.
  const std::string acos2 = with("acos(2)");
  CAPTURE(acos2);
  CHECK(acos2.rfind("hostile.yaml:8:", 0) == 0);
  CHECK(acos2.find("frames[0].chain[1].tx: 'acos(2)' at the default parameters is complex") != std::string::npos);
  CHECK(with("sqrt(-a)").find("'sqrt(-a)' at the default parameters is complex") != std::string::npos);
  CHECK(with("1/(a - 0.5)").find("'1/(a - 0.5)' at the default parameters is singular") != std::string::npos);  // a = 0.5
  CHECK(with("log(a - 0.5)").find("at the default parameters is singular") != std::string::npos);
  CHECK(with("exp(a*2000)").find("at the default parameters is not finite") != std::string::npos);
  CHECK(with("acos(a)") == "");  // a = 0.5: fine
  CHECK(with("sqrt(a)/a") == "");

  // Finite in exact arithmetic but not in double, which the emitted code computes in: the message
  // names the operation. e exactly; in double exp(1000) and exp(999) are both inf, so the emitted code computes inf/inf.
  const std::string ratio = with("exp(1000)/exp(999)");
  CAPTURE(ratio);
  CHECK(ratio.rfind("hostile.yaml:8:", 0) == 0);
  CHECK(ratio.find("frames[0].chain[1].tx: 'exp(1000)/exp(999)' evaluates to nan in double at the default parameters "
                   "(overflow: exp(") != std::string::npos);  // exp(1000) or exp(999), whichever GiNaC orders first
  // The same through a parameter (a = 0.5).
  const std::string through_a = with("exp(a*2000)/exp(a*1998)");
  CAPTURE(through_a);
  CHECK(through_a.find("evaluates to nan in double at the default parameters (overflow: exp(") != std::string::npos);
  CHECK(with("exp(700)/exp(699)") == "");  // both within double's range
}

TEST_CASE("model file: a pole, a complex value or a domain error at the default parameters is an error naming the field") {
  const std::string text = "model: tiny\n"
                           "parameters:\n"
                           "  - {name: a, value: 1, unit: m, kind: length, meaning: a length}\n"
                           "  - {name: b, value: 1, unit: m, kind: length, meaning: another}\n"
                           "coordinates:\n  inputs:\n    - {name: q, unit: rad, meaning: a joint}\n"
                           "frames:\n  - {name: base, parent: K0, chain: [rz: q, translate: [0, EXPR, 0]]}\n";
  const auto with = [&](const std::string& expression) {
    std::string t = text;
    return error_of(t.replace(t.find("EXPR"), 4, expression));
  };
  const std::string pole = with("1/(a-b)");
  CAPTURE(pole);
  CHECK(pole.rfind("hostile.yaml:9:", 0) == 0);
  CHECK(pole.find("frames[0].chain[1].translate[1]: '1/(a-b)' at the default parameters is singular") != std::string::npos);
  CHECK(with("acos(2*a)").find("translate[1]: 'acos(2*a)' at the default parameters is complex") != std::string::npos);
  CHECK(with("sqrt(a-2)").find("translate[1]: 'sqrt(a-2)' at the default parameters is complex") != std::string::npos);
  CHECK(with("1/(a-b+1)") == "");
}

// Wheel drives on hubs (the quadruped's): their names, and the mistakes a file can make with them.
TEST_CASE("model file: a wheel on a hub may be driven; the drive's name and its mistakes") {
  std::ifstream in(WLX_SOURCE_DIR "/tests/models/quadruped.yaml");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string good = buffer.str();
  const std::string anchor = "{wheel: lf}, {wheel: rf}";
  REQUIRE(good.find(anchor) != std::string::npos);
  const Model m = parse_model(good, "quadruped.yaml");
  REQUIRE(m.dynamics);
  REQUIRE(m.dynamics->actuated.size() == 16);
  CHECK(m.dynamics->actuated[12].name == "spin_lf");
  CHECK(m.dynamics->actuated[12].wheel == 0);
  CHECK(m.dynamics->actuated[12].coordinate == -1);
  CHECK(m.dynamics->actuated[0].coordinate >= 0);
  const auto with = [&](const std::string& replacement) {
    std::string text = good;
    text.replace(text.find(anchor), anchor.size(), replacement);
    try {
      return parse_model(text, "quadruped.yaml").dynamics->actuated[12].name;
    } catch (const ModelFileError& e) {
      return std::string(e.what());
    }
  };
  CHECK(with("{wheel: lf, name: motor_lf}, {wheel: rf}") == "motor_lf");
  CHECK(with("{wheel: lf}, {wheel: lf}").find("dynamics.actuated[13]: listed twice") != std::string::npos);
  CHECK(with("{wheel: lf, name: x_lf}, {wheel: rf}").find("named 'x_lf', as is a coordinate") != std::string::npos);
  CHECK(with("{wheel: lf, name: 3x}, {wheel: rf}").find("'3x' is not a name") != std::string::npos);
  CHECK(with("{name: motor_lf}, {wheel: rf}").find("missing field 'wheel'") != std::string::npos);
}

// Issue 43: a limb's `start`, `nominal` and `ik_sweeps.start` take the constant expressions that
// ik_sweeps' from/to/step take (a repeated limb's <sign>*0.6), not only plain numbers.
TEST_CASE(
    "model file: start values, nominal values and the sweeps' start take expressions of numbers, as the sweeps' ends "
    "do") {
  std::ifstream in(WLX_SOURCE_DIR "/models/walker.yaml");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string good = buffer.str();
  const std::string anchor = "    joints: [abduct_<side>, lift_<side>, knee_<side>]\n";
  REQUIRE(good.find(anchor) != std::string::npos);
  const auto with_start = [&](const std::string& start) {
    std::string text = good;
    text.replace(text.find(anchor), anchor.size(), anchor + "    start: " + start + "\n");
    return text;
  };
  const auto index = [](const Model& m, const std::string& name) {
    for (std::size_t k = 0; k < m.coordinates.size(); ++k)
      if (m.coordinates[k].name == name) return k;
    FAIL("no coordinate " << name);
    return std::size_t{0};
  };
  // The left side's sign is 1, the right side's -1 (walker.yaml's repeat table): the values are
  // worked out here from the text, not read back from the reader.
  const Model m = parse_model(with_start("{abduct_<side>: <sign>*0.1, knee_<side>: 1*<sign>*-0.6}"), "walker.yaml");
  CHECK(m.nominal[index(m, "abduct_l")] == doctest::Approx(0.1).epsilon(1e-15));
  CHECK(m.nominal[index(m, "abduct_r")] == doctest::Approx(-0.1).epsilon(1e-15));
  CHECK(m.nominal[index(m, "knee_l")] == doctest::Approx(-0.6).epsilon(1e-15));
  CHECK(m.nominal[index(m, "knee_r")] == doctest::Approx(0.6).epsilon(1e-15));
  // A plain number reads as before; what is not a number of numbers is still an error naming the field.
  const Model plain = parse_model(with_start("{knee_<side>: -0.6}"), "walker.yaml");
  CHECK(plain.nominal[index(plain, "knee_r")] == -0.6);
  std::string message;
  try {
    parse_model(with_start("{knee_<side>: <sign>*thigh}"), "walker.yaml");
  } catch (const ModelFileError& e) {
    message = e.what();
  }
  CAPTURE(message);
  CHECK(message.find("limbs[0]{side=l}.start.knee_<side>") != std::string::npos);
  CHECK(message.find("'1*thigh' is not a number") != std::string::npos);

  // `nominal` and `ik_sweeps.start` the same way (the excavator's file: z_Wr in both).
  std::string excavator = excavator_text();
  const std::string nominal = "  z_Wr: 0.05", sweep_start = "start: {z_Wr: 0.0}";
  REQUIRE(excavator.find(nominal) != std::string::npos);
  REQUIRE(excavator.find(sweep_start) != std::string::npos);
  excavator.replace(excavator.find(nominal), nominal.size(), "  z_Wr: 0.1/2");
  excavator.replace(excavator.find(sweep_start), sweep_start.size(), "start: {z_Wr: -2*0.01}");
  const Model e = parse_model(excavator, "excavator.yaml");
  CHECK(e.nominal[index(e, "z_Wr")] == doctest::Approx(0.05).epsilon(1e-15));
  CHECK(e.sweep_start[index(e, "z_Wr")] == doctest::Approx(-0.02).epsilon(1e-15));
}
