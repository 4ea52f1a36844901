// Fuzz target: the model-file reader. Any text either reads into a Model or is refused with a
// ModelFileError; no other exception, crash, hang or sanitizer finding.
#include "../../generator/model_file.hpp"

#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(bytes), size);
  try {
    const wlx::codegen::Model m = wlx::codegen::parse_model(text, "fuzz.yaml");
    if (m.nominal.size() != m.coordinates.size()) std::abort();  // every coordinate has a nominal value (issue 24)
  } catch (const wlx::codegen::ModelFileError&) {
  }
  return 0;
}
