// The generated functions of the frames, the joints' twists, loop closure, wheel rows, clearance box and fused closed-form IK, in double, compiled once
// for the model's runtime library. The library's users see their declarations only
// (WLX_GEN_COMPILED_<model>, which the library defines for them; generated types.hpp), so a
// translation unit that calls them does not compile them again: they are most of a model's compile
// time. Each generated header is included by exactly one of the runtime's generated_*.cpp, and a
// model without one of them (no dynamics, no clearance box) has nothing to compile there.
#define WLX_GEN_DEFINE_DOUBLE 1

#if __has_include(<wlx/gen/kinematics.hpp>)
#include <wlx/gen/kinematics.hpp>
#endif
#if __has_include(<wlx/gen/joint_jacobian.hpp>)
#include <wlx/gen/joint_jacobian.hpp>
#endif
#if __has_include(<wlx/gen/closure.hpp>)
#include <wlx/gen/closure.hpp>
#endif
#if __has_include(<wlx/gen/nonholonomic.hpp>)
#include <wlx/gen/nonholonomic.hpp>
#endif
#if __has_include(<wlx/gen/clearance.hpp>)
#include <wlx/gen/clearance.hpp>
#endif
#if __has_include(<wlx/gen/ik.hpp>)
#include <wlx/gen/ik.hpp>
#endif
