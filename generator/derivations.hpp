// The derivations, in the order of the thesis chapters: kinematics (3.4), closure (3.3),
// non-holonomic rows (4, 5), convective terms (6.5-6.7) and body kinematics for the
// dynamics (6.2-6.3). Each returns the symbolic outputs of one emitted function.
#pragma once

#include "model.hpp"

#include <string>
#include <vector>

namespace wlx::codegen {

// One output argument of an emitted function: a pointer parameter, filled only when non-null.
struct OutputSpec {
  std::string name;
  std::string type;      // C++ type the pointer points to
  std::string doc;
  std::string prologue;  // statement run before the elements are written (zeroing), or empty
  std::vector<std::pair<std::string, ex>> elements;  // lvalue (with `{}` for the name) -> value
};

struct FunctionSpec {
  std::string name;
  std::string header;  // file name in generated/wlx/gen/
  std::string doc;
  bool needs_rates = false;  // takes sdot
  std::vector<OutputSpec> outputs;
};

// The value Phi_i(s) of one closure condition, in the model's symbols.
ex closure_value(const Model& m, const ClosureCondition& c);

FunctionSpec derive_kinematics(const Model& m);
FunctionSpec derive_closure(const Model& m);
FunctionSpec derive_nonholonomic(const Model& m);
FunctionSpec derive_convective(const Model& m);
FunctionSpec derive_bodies(const Model& m);
// Kinematics, closure and non-holonomic rows fused into one function, so that their common
// subexpressions (the frames' rotations and positions) are computed once per update.
FunctionSpec derive_kinematic_update(const Model& m);
// An inverse-dynamics step's two passes, fused the same way: at s, dPhi/ds, C(s) and the bodies'
// Jacobians; at s and s', the convective terms of both.
FunctionSpec derive_dynamics_update(const Model& m);
FunctionSpec derive_dynamics_convective(const Model& m);

// The height of the lowest corner of the model's clearance box above the ground (z = 0 of K0).
FunctionSpec derive_clearance(const Model& m);

// The derivations that apply to a model, in emission order (clearance only with a clearance box).
struct Derivation {
  const char* name;
  FunctionSpec (*derive)(const Model&);
};
std::vector<Derivation> derivations(const Model& m);
// All of them, derived.
std::vector<FunctionSpec> derive_all(const Model& m);

}  // namespace wlx::codegen
