// Compiled with nothing but one model's generated/<model>/ and Eigen on the include path, for
// every built-in model, and run (see tests/CMakeLists.txt): the headers a controller embeds need
// nothing else, and the generated IK solves the model's nominal state.
#include <wlx/gen/all.hpp>

int main() {
  const wlx::gen::Params p;
  const wlx::gen::Coordinates s = wlx::gen::Coordinates::Zero();
  wlx::gen::FramePositions pos;
  wlx::gen::ClosureVector Phi;
  wlx::gen::WheelRows C;
  wlx::gen::WheelVector Cd;
  wlx::gen::BodyVectors com;
  wlx::gen::kinematics(s, p, &pos, nullptr);
  wlx::gen::closure(s, p, &Phi, nullptr);
  wlx::gen::nonholonomic(s, p, &C, nullptr);
  wlx::gen::convective(s, s, p, nullptr, &Cd);
  wlx::gen::bodies(s, s, p, &com, nullptr, nullptr, nullptr, nullptr, nullptr);
  // The derived inverse kinematics at the nominal state, every limb on branch 0.
  wlx::gen::Coordinates q = wlx::gen::Coordinates::Zero();
  for (int k = 0; k < wlx::gen::kInputCount; ++k) q(k) = wlx::gen::kNominalInputs[static_cast<std::size_t>(k)];
  wlx::gen::IkDiagnostics why;
  for (const auto& limb : wlx::gen::kClosedForm)
    if (limb.solve != nullptr && limb.solve(q, p, 0, q, why) != wlx::gen::IkStatus::ok) return 1;
  return pos.allFinite() && Phi.allFinite() && C.allFinite() && Cd.allFinite() && com.allFinite() ? 0 : 1;
}
