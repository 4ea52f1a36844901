// Solves the excavator's closure at its nominal pose with the runtime taken in by
// add_subdirectory(), and fails unless the closure holds to 1e-12 m.
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>

#include <cstdio>

int main() {
  const wlx::Model model;
  wlx::Data data;
  wlx::Coordinates s = wlx::nominal_inputs();
  wlx::solve_ik_closed_form(model, s);
  wlx::closure(model, data, s, false);
  const double residual = data.Phi.cwiseAbs().maxCoeff();
  std::printf("excavator at its nominal pose: max |Phi| = %.2e m\n", residual);
  return residual <= 1e-12 ? 0 : 1;
}
