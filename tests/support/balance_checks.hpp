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

// A torque-driven motion by the forward dynamics (RK4 on the inputs and the commanded speeds u,
// the dependents re-solved by the IK at every stage): the kinetic and potential energy at every
// step and the actuators' power tau . J_beta u there. Independent of the run's own integrator.
struct ForwardRun {
  std::vector<double> kinetic, potential, power;
  bool complete = true;
};

inline ForwardRun integrate_forward(const Model& model, const Coordinates& initial, const CommandVector& u0,
                                    const TorqueVector& tau, double duration, double dt) {
  using Inputs = Eigen::Matrix<double, kInputCount, 1>;
  Data d;
  DynamicsTerms t;
  Coordinates s = initial;
  const auto rhs = [&](const Inputs& q, const CommandVector& u, Inputs& dq, CommandVector& du) {
    s.head<kInputCount>() = q;
    solve_ik_closed_form(model, s);
    forward_dynamics(model, d, s, u, tau, du, t);
    dq = t.sdot.head<kInputCount>();
  };
  ForwardRun run;
  Inputs q = initial.head<kInputCount>();
  CommandVector u = u0;
  const long steps = std::lround(duration / dt);
  try {
    for (long k = 0; k <= steps; ++k) {
      Inputs k1q, k2q, k3q, k4q;
      CommandVector k1u, k2u, k3u, k4u;
      rhs(q, u, k1q, k1u);  // leaves s, t at the step's start
      run.kinetic.push_back(kinetic_energy(model, d, s, t.sdot));
      run.potential.push_back(potential_energy(model, d, s));
      run.power.push_back(tau.dot(t.J_beta * u));
      if (k == steps) break;
      rhs(q + 0.5 * dt * k1q, u + 0.5 * dt * k1u, k2q, k2u);
      rhs(q + 0.5 * dt * k2q, u + 0.5 * dt * k2u, k3q, k3u);
      rhs(q + dt * k3q, u + dt * k3u, k4q, k4u);
      q += dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
      u += dt / 6 * (k1u + 2 * k2u + 2 * k3u + k4u);
    }
  } catch (const Error&) {
    run.complete = false;
  }
  return run;
}

}  // namespace wlx::test
