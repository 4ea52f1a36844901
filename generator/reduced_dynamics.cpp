// reduced_dynamics: the equations of motion on the commanded speeds, by composite rigid bodies in
// the joints' own frames (composite_dynamics.cpp, on rows of lanes for sibling limbs), with the
// convective terms; lane_printer.hpp writes its code as C++.
#include "derivations_internal.hpp"
#include "lane_printer.hpp"

namespace wlx::codegen {

using namespace derivation;

namespace {

// reduced_dynamics as declared: its documentation and its input T. The names of its code are the
// printer's, which the model's coordinates and parameters therefore must not take.
FunctionSpec reduced_dynamics_spec(const Model& m) {
  FunctionSpec fn{"reduced_dynamics", "reduced_dynamics.hpp",
                  "The equations of motion on the commanded speeds u, in one pass with the convective terms: with "
                  "s' = T u and s'' = T u' + s''_bias, the generalized inertia, velocity and gravity forces on u are "
                  "M u' + b_velocity + B_bias s''_bias and Q_gravity. M by composite rigid bodies in the joints' own "
                  "frames: each composite I_k beyond joint k is carried into its parent's frame by the placement "
                  "between them, I_k S_k is carried up the chain and M on the coordinates is S_j . (I_k S_k) at each "
                  "joint j on it (S a joint's axis in its own frame), and M on u is T^T M T on T's pattern, whose "
                  "T^T M on the dense rows' coordinates is B_bias. b_velocity = T^T tau for the Newton-Euler "
                  "recursion at u' = 0 and s''_bias = 0 in the same frames, and Q_gravity = T^T tau for gravity, "
                  "from the composites' masses and first moments. Limbs of one shape run side by side, one lane "
                  "each.",
                  true, {}};
  lane_code::reserve_printer_names(m);
  fn.inputs = {{"T", "RateBasis",
                "s' = T u, the rates caused by unit commanded speeds (rate_basis at s); only the rows of the dependent "
                "pair and of the dependent joints are read, the others are fixed by the model file, and in them only "
                "the entries kRateBasisPattern marks (structure.hpp; the others are zero). The equations of motion "
                "read s' only on the joints that move in a step (T's nonzero rows): the inputs T holds have "
                "s' = T u = 0"}};
  return fn;
}

}  // namespace

FunctionSpec derive_reduced_dynamics(const Model& m) {
  FunctionSpec fn = reduced_dynamics_spec(m);
  lane_code::PrintedCode printed = lane_code::print(composite_rigid_body_program(m), kReducedOutputs);
  fn.lane_code = std::move(printed.code);
  fn.lane_scalars = std::move(printed.scalars);
  const std::vector<OpCount>& lane_ops = printed.ops;

  const FunctionSpec c = derive_convective(m);
  OutputSpec Mo{"M", "CommandMatrix", "generalized mass matrix on u (symmetric)", "", {}};
  OutputSpec bo{"b_velocity", "CommandVector", "velocity-dependent forces on u, s''_bias excluded", "", {}};
  OutputSpec Bo{"B_bias", "CommandRows", "forces on u per unit s''_bias: b = b_velocity + B_bias s''_bias", kZeroMatrix, {}};
  OutputSpec Qo{"Q_gravity", "CommandVector", "generalized gravity force on u (gravity along -z of K0)", "", {}};
  for (OutputSpec* o : {&Mo, &bo, &Bo, &Qo}) o->from_lanes = true;
  Mo.lane_ops = lane_ops[kM];
  bo.lane_ops = lane_ops[kB_velocity];
  Bo.lane_ops = lane_ops[kB_bias];
  Qo.lane_ops = lane_ops[kQ_gravity];
  fn.outputs = {c.outputs[0], c.outputs[1], Mo, bo, Bo, Qo};
  return fn;
}

}  // namespace wlx::codegen
