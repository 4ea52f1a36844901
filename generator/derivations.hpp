// The derivations, in the order of the thesis chapters: kinematics (3.4), closure (3.3),
// non-holonomic rows (4, 5), convective terms (6.5-6.7) and body kinematics for the
// dynamics (6.2-6.3). Each returns the symbolic outputs of one emitted function.
#pragma once

#include "expr_graph.hpp"
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
  // Written by the function's lane code (FunctionSpec::lane_code), not element by element; then
  // `elements` is empty and lane_ops counts its share of that code's operations.
  bool from_lanes = false;
  OpCount lane_ops = {};
};

// One input argument besides s, sdot and p: a matrix of the scalar type, read by the lane code.
struct InputSpec {
  std::string name;
  std::string type;  // a types.hpp name with an ...Of<Scalar> template
  std::string doc;
};

// The identifiers (and other words of letters, digits and '_') in a piece of emitted code, in order.
std::vector<std::string> identifiers(const std::string& code);

struct FunctionSpec {
  std::string name;
  std::string header;  // file name in generated/wlx/gen/
  std::string doc;
  bool needs_rates = false;  // takes sdot
  std::vector<OutputSpec> outputs;
  std::vector<InputSpec> inputs = {};
  // Code on rows of scalars (detail::Lanes, types.hpp) that writes the from_lanes outputs, run when
  // any of them is requested, after the scalars it reads (lane_scalars: name -> value) are computed.
  std::vector<std::pair<std::string, ex>> lane_scalars = {};
  std::string lane_code = {};
};

// The value Phi_i(s) of one closure condition, in the model's symbols.
ex closure_value(const Model& m, const ClosureCondition& c);

FunctionSpec derive_kinematics(const Model& m);
FunctionSpec derive_closure(const Model& m);
FunctionSpec derive_nonholonomic(const Model& m);
FunctionSpec derive_convective(const Model& m);
FunctionSpec derive_bodies(const Model& m);
// Each coordinate's joint as a twist in K0 (what Pinocchio's computeJointJacobians returns).
FunctionSpec derive_joint_jacobian(const Model& m);
// Kinematics, closure and non-holonomic rows fused into one function, so that their common
// subexpressions (the frames' rotations and positions) are computed once per update.
FunctionSpec derive_kinematic_update(const Model& m);
// An inverse-dynamics step's two passes, fused the same way: at s, dPhi/ds and C(s); at s, s' and
// the rate basis T, the convective terms and the equations of motion on the commanded speeds
// (only for a model with a dynamics section).
FunctionSpec derive_dynamics_update(const Model& m);
FunctionSpec derive_reduced_dynamics(const Model& m);
// The same equations' Q* by the recursive Newton-Euler equations at given s'' (no mass matrix).
FunctionSpec derive_generalized_forces(const Model& m);
// The commanded speeds each coordinate's rate depends on (the nonzero columns of its row of the rate
// basis T, s' = T u), ascending; none for a held input or without a dynamics section.
std::vector<std::vector<int>> rate_basis_pattern(const Model& m);

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
