// Checks of the inverse dynamics that do not use the Kane formula under test, for any model:
// the power of the generalized force equals the rate of change of the energy along a motion.
#pragma once

#include <wlx/dynamics.hpp>
#include <wlx/error.hpp>
#include <wlx/forward_dynamics.hpp>
#include <wlx/ik.hpp>
#include <wlx/simulation.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace wlx::test {

// Integrates the constant commanded speeds u from `initial` for 2 ms (dt = 1e-5) and returns the
// largest |Q* . u - d(T + V)/dt| / max(1, |Q* . u|) along it, with d/dt by a five-point stencil
// (truncation ~dt^4, rounding ~1e-16 |E| / dt: about 1e-8 for machines of a few tonnes). u is
// scaled so that the fastest coordinate moves at 1 unit/s.
inline double energy_balance_error(const Model& model, const Coordinates& initial, CommandVector u) {
  Data d;
  DynamicsTerms t;
  inverse_dynamics(model, d, initial, u, CommandVector::Zero(), t);
  u /= t.sdot.cwiseAbs().maxCoeff();
  Scenario sc;
  sc.params = model.params();
  sc.initial = initial;
  sc.pair = dynamics_pair();
  for (int k = 0; k < kCommandedCount; ++k) sc.rates(kCommandedSpeeds[static_cast<std::size_t>(k)]) = u(k);
  sc.duration = 0.002;
  sc.dt = 1e-5;
  const Trajectory tr = simulate(sc);
  if (!tr.complete) return INFINITY;
  const auto energy = [&](std::size_t k) {
    const Sample& smp = tr.samples[k];
    return kinetic_energy(model, d, smp.s, smp.sdot) + potential_energy(model, d, smp.s);
  };
  double worst = 0;
  for (std::size_t k = 2; k + 2 < tr.samples.size(); k += 20) {
    const double dEdt = (energy(k - 2) - 8 * energy(k - 1) + 8 * energy(k + 1) - energy(k + 2)) / (12 * sc.dt);
    inverse_dynamics(model, d, tr.samples[k].s, u, CommandVector::Zero(), t);
    const double power = t.Qstar.dot(u);
    worst = std::max(worst, std::abs(power - dEdt) / std::max(1.0, std::abs(power)));
  }
  return worst;
}

}  // namespace wlx::test
