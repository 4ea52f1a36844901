// Fuzz target: the model-file reader. Any text either reads into a Model or is refused with a
// ModelFileError; no other exception, crash, hang or sanitizer finding.
#include "../../generator/model_file.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(bytes), size);
  try {
    const wlx::codegen::Model m = wlx::codegen::parse_model(text, "fuzz.yaml");
    // One nominal value per coordinate (the dependents' Newton start values included), each finite.
    if (m.nominal.size() != m.coordinates.size()) std::abort();
    for (double v : m.nominal)
      if (!std::isfinite(v)) std::abort();
  } catch (const wlx::codegen::ModelFileError&) {
  }
  return 0;
}
