// What the emit*.cpp files share and nothing else uses.
#pragma once

#include "emit.hpp"

#include <string>

namespace wlx::codegen {

// The macro with which a library says it compiles this model's double functions: one per model,
// so that another model's headers in the same translation unit stay inline.
std::string compiled_macro(const EmitOptions& opt);

}  // namespace wlx::codegen
