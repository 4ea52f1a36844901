// Newton's limb steps (limb_steps.hpp), compiled once for each limb size up to
// kPrecompiledLimbSize: about 6 s of CPU per size at -O3, so a file of its own, which a parallel
// build compiles beside numerics.cpp.
#include "wlx/limb_steps.hpp"

namespace wlx::limb_steps {

#define WLX_LIMB_STEPS_INSTANTIATE(N)                                                   \
  template bool newton_step<N>(const Square<N>&, const Column<N>&, Column<N>&);         \
  template Column<N> regularized_step<N>(const Square<N>&, const Column<N>&, double);   \
  template Column<N> damped_step<N>(const Square<N>&, const Column<N>&, double);
WLX_LIMB_STEPS_INSTANTIATE(1)
WLX_LIMB_STEPS_INSTANTIATE(2)
WLX_LIMB_STEPS_INSTANTIATE(3)
WLX_LIMB_STEPS_INSTANTIATE(4)
WLX_LIMB_STEPS_INSTANTIATE(5)
WLX_LIMB_STEPS_INSTANTIATE(6)
#undef WLX_LIMB_STEPS_INSTANTIATE
static_assert(kPrecompiledLimbSize == 6, "instantiate every size up to kPrecompiledLimbSize above");

}  // namespace wlx::limb_steps
