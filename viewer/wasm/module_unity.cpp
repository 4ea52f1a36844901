// The viewer module's sources as one translation unit (compiled once per model with
// -DWLX_MODEL=<name>): they instantiate the same fixed-size Eigen templates and fmt's header-only
// formatting, which emcc then compiles once instead of in each of five objects (the native
// runtime is a unity build for the same reason). 390 s of CPU for three models' five objects each.
#include "../../runtime/wlx/model.cpp"
#include "../../runtime/wlx/kinematics.cpp"
#include "../../runtime/wlx/ik.cpp"
#include "../../cli/commands/limits.cpp"
#include "viewer_module.cpp"
