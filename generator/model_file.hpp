// Reading a model file (YAML; the format is documented in docs/model-format.md) into a Model.
//
// Every error names the place (file:line:column), the field (a path such as
// `frames[3].chain[1].rx`) and the reason, and nothing of a bad file reaches the derivations:
// names are unique and valid C++ identifiers, expressions use only the model's own symbols
// (parsed by GiNaC's parser against a strict table), frames form a tree rooted at K0, units
// fit the parameter kinds, and the closure has one equation per dependent joint, split into
// limbs whose blocks of dPhi/ds are square.
#pragma once

#include "model.hpp"

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace wlx::codegen {

struct ModelFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The bounds of a model file (docs/model-format.md, "Limits"), each far above what a machine
// needs (the excavator: 13 frames at most 5 from K0, 32 coordinates, 51 expanded entries, a
// 20 KB file) and far below what exhausts the generator's memory or stack. A file beyond one is
// an error naming the field and the bound.
inline constexpr std::size_t kMaxModelFileBytes = std::size_t{1} << 20;  // 1 MiB
inline constexpr std::size_t kMaxExpandedEntries = 4096;  // list entries after `for:` repetition, in all lists
inline constexpr std::size_t kMaxFrames = 512;
inline constexpr std::size_t kMaxUrdfElements = 65536;  // XML elements of a URDF (kMaxFrames links need a few thousand)
inline constexpr std::size_t kMaxChainDepth = 64;      // frames between any frame and K0
inline constexpr std::size_t kMaxCoordinates = 512;    // coordinates (joints and inputs)
inline constexpr std::size_t kMaxExpressionBytes = 1024;
inline constexpr int kMaxExpressionDepth = 32;         // parentheses and unary signs nested in one expression

// Why `name` cannot appear in generated C++ (a keyword, a macro of the compiler or of the
// included headers, std, Eigen, a reserved spelling), or "" when it can. Every name a model file
// defines passes this; so does each part of wlx-gen's --namespace.
std::string cpp_name_problem(const std::string& name);
// The same for the model's name, which also must not be one of wlx's own namespaces.
std::string model_name_problem(const std::string& name);

// Why `value` cannot be the value of a parameter of this kind ("must be positive"), or "" when it
// can: the one rule for the model file's values and for wlx-gen's --bake.
std::string parameter_value_problem(ParameterKind kind, double value);

// " (did you mean 'x'?)" when one of the candidates is close to `name`, else "".
std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates);

// `source_name` is what messages and the generated banners call the file; a `urdf:` path in it is
// relative to `directory`. A non-empty `urdf_path` is the URDF to read (wlx-gen robot.urdf --with
// robot.yaml), in place of the file's `urdf:`.
Model parse_model(const std::string& text, const std::string& source_name, const std::string& directory = {},
                  const std::string& urdf_path = {});
Model load_model_file(const std::string& path, const std::string& urdf_path = {});
// The model file as wlx-gen reads it: for a file with a URDF, the URDF's parameters, dependent
// joints, frames and bodies written into it (a model file that needs no URDF); checked first.
std::string print_model_file(const std::string& path, const std::string& urdf_path = {});

}  // namespace wlx::codegen
