// Compiled with nothing but generated/ and Eigen on the include path (see tests/CMakeLists.txt):
// proves the headers a controller embeds need nothing else.
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
  return pos.allFinite() && Phi.allFinite() && C.allFinite() && Cd.allFinite() && com.allFinite() ? 0 : 1;
}
