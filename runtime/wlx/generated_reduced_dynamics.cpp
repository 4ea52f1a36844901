// The generated functions of the dynamics on the commanded speeds (the composite-rigid-body pass, a
// model's largest function, and the Newton-Euler forces), in double, compiled once
// for the model's runtime library. The library's users see their declarations only
// (WLX_GEN_COMPILED_<model>, which the library defines for them; generated types.hpp), so a
// translation unit that calls them does not compile them again: they are most of a model's compile
// time. Each generated header is included by exactly one of the runtime's generated_*.cpp, and a
// model without one of them (no dynamics, no clearance box) has nothing to compile there.
#define WLX_GEN_DEFINE_DOUBLE 1

#if __has_include(<wlx/gen/reduced_dynamics.hpp>)
#include <wlx/gen/reduced_dynamics.hpp>
#endif
#if __has_include(<wlx/gen/generalized_forces.hpp>)
#include <wlx/gen/generalized_forces.hpp>
#endif
