// emit_function's placement of lane code's scalars (emit_function.cpp): each is defined right
// before the first line that reads it, and a scalar first read inside one of the lane code's
// blocks (an output's code, run only when it is requested) is defined again where a line after
// that block reads it, else the header would not compile (a model whose mass matrix entry is a
// body's mass itself, read again by the gravity forces after M's block).
#include "../../generator/emit.hpp"
#include "../../generator/model_file.hpp"

#include <doctest/doctest.h>

#include <string>

using namespace wlx::codegen;

namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

}  // namespace

TEST_CASE("emit_function: a lane scalar read inside a block of the lane code and after it is defined in both places") {
  const Model m = load_model_file(WLX_MODEL_FILE);
  const ex mass = m.parameter(m.bodies.front().mass).symbol;
  FunctionSpec fn{"probe", "probe.hpp", "A function whose lane code reads one scalar in a block and after it.", false, {}};
  OutputSpec M{"M", "CommandMatrix", "a mass matrix", "", {}};
  OutputSpec Q{"Q_gravity", "CommandVector", "a gravity force", "", {}};
  M.from_lanes = Q.from_lanes = true;
  fn.outputs = {M, Q};
  fn.lane_scalars = {{"kane_probe_mass", 2 * mass}, {"kane_probe_once", 3 * mass}};
  fn.lane_code =
      "    const Scalar kane_probe_sum = kane_probe_once + Scalar(1);\n"
      "    if (M != nullptr) {\n"
      "      (*M)(0, 0) = kane_probe_mass + kane_probe_sum;\n"
      "    }\n"
      "    if (Q_gravity != nullptr) {\n"
      "      (*Q_gravity)(0) = kane_probe_mass;\n"
      "    }\n";
  FunctionStats stats;
  const std::string text = emit_function(m, fn, EmitOptions{}, stats).text;
  // Read in two blocks: defined in each, inside it; read before both: defined once, outside.
  CHECK(count(text, "const Scalar kane_probe_mass = ") == 2);
  CHECK(count(text, "const Scalar kane_probe_once = ") == 1);
  const std::size_t first_block = text.find("if (M != nullptr) {"), second_block = text.find("if (Q_gravity != nullptr) {");
  const std::size_t first = text.find("const Scalar kane_probe_mass = "), second = text.find("const Scalar kane_probe_mass = ", first + 1);
  REQUIRE(first_block != std::string::npos);
  REQUIRE(second_block != std::string::npos);
  CHECK(first > first_block);
  CHECK(first < second_block);
  CHECK(second > second_block);
  CHECK(text.find("const Scalar kane_probe_once = ") < first_block);
}
