// The generated kernels of one model, compiled once per compiler into one program
// (tools/kernels_by_compiler.sh): each compilation wraps the generated headers in a namespace of
// its own (KERNEL_NAMESPACE), so that the two compilers' copies of the same inline functions stay
// apart at link time and run side by side in one process (main.cpp), where their ratio is not
// the machine's noise from one run to the next.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <random>
#include <type_traits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace KERNEL_NAMESPACE {
#include <wlx/gen/all.hpp>
}

namespace KERNEL_NAMESPACE {
namespace {

using namespace ::KERNEL_NAMESPACE::wlx::WLX_MODEL::gen;

struct State {
  Coordinates s, sdot, sddot;
  RateBasis T;
};
// 64 states, the same for both compilers (a fixed seed): a kernel's branches see varied inputs.
std::vector<State> make_states() {
  std::mt19937 rng(20261206);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<State> v(64);
  for (State& x : v) {
    for (int i = 0; i < x.s.size(); ++i) x.s(i) = u(rng), x.sdot(i) = u(rng), x.sddot(i) = u(rng);
    for (int i = 0; i < x.T.size(); ++i) x.T.data()[i] = u(rng);
  }
  return v;
}

struct Workspace {
  std::vector<State> states = make_states();
  Params p{};
  FramePositions positions;
  FrameRotations rotations;
  ClosureVector Phi, convective_Phi;
  ClosureJacobian dPhi_ds;
  WheelRows C;
  WheelVector convective_C;
  BodyVectors com, Jv_dot_sdot, Jw_dot_sdot;
  BodyRotations body_rotations;
  BodyJacobians Jv, Jw;
  CommandMatrix M;
  CommandVector b_velocity, Q_gravity, Qstar;
  CommandRows B_bias;
};

}  // namespace

// Runs kernel `which` (kernel_names() in main.cpp's order) n times over the states; returns a
// value that depends on every run's output, so that nothing is optimized away.
double run_kernel(int which, int n) {
  static Workspace w;
  double acc = 0;
  for (int k = 0; k < n; ++k) {
    const State& x = w.states[static_cast<std::size_t>(k & 63)];
    switch (which) {
      case 0: kinematics(x.s, w.p, {.positions = &w.positions, .rotations = &w.rotations}); acc += w.positions(0, 0); break;
      case 1:
        kinematic_update(x.s, w.p, {.positions = &w.positions, .rotations = &w.rotations, .Phi = &w.Phi, .dPhi_ds = &w.dPhi_ds, .C = &w.C}, false);
        acc += w.dPhi_ds(0, 0);
        break;
      case 2:
        bodies(x.s, x.sdot, w.p, {.com = &w.com, .rotations = &w.body_rotations, .Jv = &w.Jv, .Jw = &w.Jw, .Jv_dot_sdot = &w.Jv_dot_sdot, .Jw_dot_sdot = &w.Jw_dot_sdot}, false);
        acc += w.com(0, 0);
        break;
      case 3: dynamics_update(x.s, w.p, {.dPhi_ds = &w.dPhi_ds, .C = &w.C}, false); acc += w.dPhi_ds(0, 0); break;
      case 4: convective(x.s, x.sdot, w.p, {.dPhi_ds_dot_sdot = &w.convective_Phi, .C_dot_sdot = &w.convective_C}); acc += w.convective_Phi(0); break;
      case 5:
        reduced_dynamics(x.s, x.sdot, x.T, w.p, {.M = &w.M, .b_velocity = &w.b_velocity, .B_bias = &w.B_bias, .Q_gravity = &w.Q_gravity}, false);
        acc += w.M(0, 0);
        break;
      case 6: generalized_forces(x.s, x.sdot, x.sddot, x.T, w.p, {.Qstar = &w.Qstar}); acc += w.Qstar(0); break;
    }
    asm volatile("" ::: "memory");
  }
  return acc;
}

}  // namespace KERNEL_NAMESPACE
