// Compiled with nothing but one model's generated/<model>/ and Eigen on the include path, for
// every built-in model, as C++17 with -Wall -Wextra -Wpedantic -Werror -Wold-style-cast
// -fno-exceptions -fno-rtti, by the build's compiler and by clang when there is one, and run (see
// tests/CMakeLists.txt): the headers a controller embeds need nothing else, compile where embedded
// toolchains are strict and old, and every function instantiates for double and for float.
// Run, it solves the model's nominal state with the generated IK in both types and checks the
// float solution against the closure evaluated in double.
#include <wlx/gen/all.hpp>

#include <cmath>
#include <cstdio>

namespace gen = wlx::gen;

// Every generated function for one scalar type at the nominal inputs, dependent joints from the
// closed-form IK (branch 0); false when a solve fails or an output is not finite.
template <typename Scalar>
bool evaluate_all(const gen::Params& p, gen::CoordinatesOf<Scalar>& s) {
  for (int k = 0; k < gen::kInputCount; ++k) s(k) = Scalar(gen::kNominalInputs[static_cast<std::size_t>(k)]);
  std::array<int, gen::kLimbCount> branches{};
  int failed = -1;
  gen::IkDiagnostics why;
  if (gen::ik_all(s, p, branches, s, failed, why) != gen::IkStatus::ok) {
    std::fprintf(stderr, "ik_all failed at limb %d (stage %d, value %g)\n", failed, why.stage, why.value);
    return false;
  }
  const gen::CoordinatesOf<Scalar> sdot = gen::CoordinatesOf<Scalar>::Constant(Scalar(0.1));
  gen::FramePositionsOf<Scalar> positions;
  gen::FrameRotationsOf<Scalar> rotations;
  gen::ClosureVectorOf<Scalar> Phi;
  gen::ClosureJacobianOf<Scalar> dPhi_ds;
  gen::WheelRowsOf<Scalar> C, spin;
  gen::ClosureVectorOf<Scalar> dPhi_ds_dot_sdot;
  gen::WheelVectorOf<Scalar> C_dot_sdot;
  gen::BodyVectorsOf<Scalar> com, Jv_dot_sdot, Jw_dot_sdot;
  gen::BodyRotationsOf<Scalar> body_rotations;
  gen::BodyJacobiansOf<Scalar> Jv, Jw;
  Scalar lowest = 0;
  gen::kinematics(s, p, {&positions, &rotations});
  gen::closure(s, p, {&Phi, &dPhi_ds});
  gen::nonholonomic(s, p, {&C, &spin});
  gen::convective(s, sdot, p, {&dPhi_ds_dot_sdot, &C_dot_sdot});
  // C++17 names the outputs by assignment (C++20: {.com = &com, .Jv = &Jv, ...}).
  gen::BodiesOutputsOf<Scalar> bodies_outputs;
  bodies_outputs.com = &com;
  bodies_outputs.rotations = &body_rotations;
  bodies_outputs.Jv = &Jv;
  bodies_outputs.Jw = &Jw;
  bodies_outputs.Jv_dot_sdot = &Jv_dot_sdot;
  bodies_outputs.Jw_dot_sdot = &Jw_dot_sdot;
  gen::bodies(s, sdot, p, bodies_outputs);
  gen::kinematic_update(s, p, {&positions, &rotations, &Phi, &dPhi_ds, &C});
  gen::clearance(s, p, {&lowest});
  bool finite = positions.allFinite() && Phi.allFinite() && dPhi_ds.allFinite() && C.allFinite() && spin.allFinite() &&
                dPhi_ds_dot_sdot.allFinite() && C_dot_sdot.allFinite() && com.allFinite() && Jv_dot_sdot.allFinite() &&
                Jw_dot_sdot.allFinite() && std::isfinite(lowest);
  for (int b = 0; b < gen::kBodyCount; ++b) finite = finite && Jv[static_cast<std::size_t>(b)].allFinite() && Jw[static_cast<std::size_t>(b)].allFinite();
  return finite;
}

int main() {
  const gen::Params p;
  gen::Coordinates s;
  gen::CoordinatesOf<float> s_float;
  if (!evaluate_all<double>(p, s) || !evaluate_all<float>(p, s_float)) return 1;
  // Every limb alone too, through the table of closed forms (the double instantiations).
  gen::IkDiagnostics why;
  for (const auto& limb : gen::kClosedForm)
    if (limb.solve != nullptr && limb.solve(s, p, 0, s, why) != gen::IkStatus::ok) return 1;
  // The float solution, put into the closure in double: within the float IK's own tolerance.
  gen::ClosureVector Phi;
  gen::ClosureOutputs closure_outputs;  // the one output wanted; dPhi_ds stays null and is not computed
  closure_outputs.Phi = &Phi;
  gen::closure(s_float.cast<double>().eval(), p, closure_outputs);
  const double residual = Phi.cwiseAbs().maxCoeff();
  std::printf("%.*s: float IK at the nominal state: closure residual %.2e (tolerance %.2e); double: joints within %.2e\n",
              static_cast<int>(gen::kModelName.size()), gen::kModelName.data(), residual, double(gen::ik_tolerance<float>()),
              (s_float.cast<double>() - s).cwiseAbs().maxCoeff());
  return residual <= double(gen::ik_tolerance<float>()) ? 0 : 1;
}
