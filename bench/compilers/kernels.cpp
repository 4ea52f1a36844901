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
// The IK's inputs: the model file's first pose of its IK sweeps (reachable: the pose `wlx verify ik`
// starts from), so that the closed forms take their full path rather than a reach test's exit.
Coordinates ik_inputs() {
  Coordinates s = Coordinates::Zero();
  for (int i = 0; i < kInputCount; ++i) s(i) = kSweepStart[static_cast<std::size_t>(i)];
  return s;
}
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

struct alignas(64) Workspace {
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
  JointJacobian J;
  Coordinates ik_s = ik_inputs(), ik_out = ik_inputs();
};

}  // namespace

// One call of kernel K (main.cpp's kKernelNames order) at state x; returns a value of its output.
// Never inlined into the loop below: without the AVX2 dispatch the generated functions are inline
// templates, and GCC inlined some of them (convective) into that loop's switch and not others,
// which timed the harness's code as much as the kernel's (GCC's convective then 1.5 times clang's,
// which kept it a call). So each kernel is compiled as a function of its own, as the runtime calls
// them (runtime/wlx/generated_*.cpp compile them once, out of line).
template <int K>
__attribute__((noinline)) double call(const State& x, Workspace& w) {
  if constexpr (K == 0) {
    kinematics(x.s, w.p, {.positions = &w.positions, .rotations = &w.rotations});
    return w.positions(0, 0);
  } else if constexpr (K == 1) {
    kinematic_update(x.s, w.p, {.positions = &w.positions, .rotations = &w.rotations, .Phi = &w.Phi, .dPhi_ds = &w.dPhi_ds, .C = &w.C}, false);
    return w.dPhi_ds(0, 0);
  } else if constexpr (K == 2) {
    bodies(x.s, x.sdot, w.p, {.com = &w.com, .rotations = &w.body_rotations, .Jv = &w.Jv, .Jw = &w.Jw, .Jv_dot_sdot = &w.Jv_dot_sdot, .Jw_dot_sdot = &w.Jw_dot_sdot}, false);
    return w.com(0, 0);
  } else if constexpr (K == 3) {
    dynamics_update(x.s, w.p, {.dPhi_ds = &w.dPhi_ds, .C = &w.C}, false);
    return w.dPhi_ds(0, 0);
  } else if constexpr (K == 4) {
    convective(x.s, x.sdot, w.p, {.dPhi_ds_dot_sdot = &w.convective_Phi, .C_dot_sdot = &w.convective_C});
    return w.convective_Phi(0);
  } else if constexpr (K == 5) {
    reduced_dynamics(x.s, x.sdot, x.T, w.p, {.M = &w.M, .b_velocity = &w.b_velocity, .B_bias = &w.B_bias, .Q_gravity = &w.Q_gravity}, false);
    return w.M(0, 0);
  } else if constexpr (K == 6) {
    generalized_forces(x.s, x.sdot, x.sddot, x.T, w.p, {.Qstar = &w.Qstar});
    return w.Qstar(0);
  } else if constexpr (K == 7) {
    joint_jacobian(x.s, w.p, {.J = &w.J}, false);
    return w.J(0, 0);
  } else {
    static_cast<void>(x);
    int failed = -1;
    IkDiagnostics why;
    const std::array<int, kLimbCount> branches{};
    return static_cast<double>(ik_all(w.ik_s, w.p, branches, w.ik_out, failed, why)) + w.ik_out(kCoordinateCount - 1);
  }
}

// Runs kernel `which` n times over the states; returns a value that depends on every run's
// output, so that nothing is optimized away.
double run_kernel(int which, int n) {
  static Workspace w;
  using Call = double (*)(const State&, Workspace&);
  static constexpr Call kCalls[] = {call<0>, call<1>, call<2>, call<3>, call<4>, call<5>, call<6>, call<7>, call<8>};
  const Call kernel = kCalls[which];
  double acc = 0;
  for (int k = 0; k < n; ++k) {
    acc += kernel(w.states[static_cast<std::size_t>(k & 63)], w);
    asm volatile("" ::: "memory");
  }
  return acc;
}

}  // namespace KERNEL_NAMESPACE
