#include "wlx/simulation.hpp"

#include "wlx/error.hpp"
#include "wlx/kinematics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace wlx {

namespace {

using InputVector = Eigen::Matrix<double, kInputCount, 1>;

// The scenario's right-hand side: input rates at the inputs q (dependents re-solved first).
struct RightHandSide {
  const Scenario& sc;
  const Model& model;
  Data& data;
  Coordinates s, sdot;

  const InputVector& operator()(const InputVector& q) {
    s.head<kInputCount>() = q;
    solve_ik_closed_form(model, s, sc.branches);
    sdot.head<kInputCount>() = sc.rates;
    solve_dependent_rates(model, s, sdot, sc.pair, data, sc.nonholonomic);
    rate = sdot.head<kInputCount>();
    return rate;
  }
  InputVector rate;
};

}  // namespace

long Scenario::samples() const { return std::lround(duration / dt) + 1; }

void Scenario::validate() const {
  if (!(std::isfinite(duration) && duration > 0))
    throw Error("duration", fmt::format("must be a positive number of seconds, got {}", duration));
  if (!(std::isfinite(dt) && dt > 0)) throw Error("dt", fmt::format("must be a positive number of seconds, got {}", dt));
  if (duration / dt > 1e8)
    throw Error("dt", fmt::format("{} s over {} s is {:.3g} steps, more than the limit of 1e8", dt, duration, duration / dt));
  if (std::abs(duration / dt - std::round(duration / dt)) > 1e-6 * (duration / dt))
    throw Error("dt", fmt::format("the duration {} s is not a whole number of steps of {} s", duration, dt));
  for (int k : pair.index)
    if (rates(k) != 0)
      throw Error(fmt::format("rates.{}", gen::kCoordinateNames[static_cast<std::size_t>(k)]),
                  fmt::format("{} is a dependent rate in this scenario (pair {}): it is computed, not commanded",
                              gen::kCoordinateNames[static_cast<std::size_t>(k)], pair.label()));
  if (weighting) {
    if (pair.index != kPairA.index)
      throw Error("dependent", fmt::format("an inverse-dynamics run needs the dependent pair (y_C', yaw') (MODEL.md "
                                           "section 7), got {}",
                                           pair.label()));
    for (int k = 0; k < kInputCount; ++k)
      if (rates(k) != 0 && std::find(kCommandedSpeeds.begin(), kCommandedSpeeds.end(), k) == kCommandedSpeeds.end())
        throw Error(fmt::format("rates.{}", gen::kCoordinateNames[static_cast<std::size_t>(k)]),
                    "an inverse-dynamics run commands only z_C, x_C, roll and pitch; every other input is constant");
  }
  for (int k = 0; k < kInputCount; ++k) {
    const std::string name(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    if (!std::isfinite(initial(k))) throw Error("initial." + name, fmt::format("must be a finite number, got {}", initial(k)));
    if (!std::isfinite(rates(k))) throw Error("rates." + name, fmt::format("must be a finite number, got {}", rates(k)));
  }
}

double cabin_clearance(const Params& p, const Coordinates& s) {
  namespace c = gen::coord;
  // Row 2 of R_C: the z components of the cabin axes.
  const double sp = std::sin(s(c::pitch)), cp = std::cos(s(c::pitch)), sr = std::sin(s(c::roll)), cr = std::cos(s(c::roll));
  return s(c::z_C) - (std::abs(sp) * p.cxd / 2 + std::abs(cp * sr) * p.cyd / 2 + std::abs(cp * cr) * p.cabin_height / 2);
}

Trajectory simulate(const Scenario& sc, const Progress& progress) {
  sc.validate();
  std::vector<Sample> samples;
  samples.reserve(static_cast<std::size_t>(sc.samples()));
  Trajectory out = simulate_each(sc, [&](const Sample& smp) { samples.push_back(smp); }, progress);
  out.samples = std::move(samples);
  return out;
}

Trajectory simulate_each(const Scenario& sc, const std::function<void(const Sample&)>& on_sample, const Progress& progress) {
  sc.validate();
  const Model model(sc.params);
  auto data_storage = std::make_unique<Data>();  // ~7 KB: kept off the stack
  Data& data = *data_storage;
  RightHandSide f{sc, model, data, sc.initial, Coordinates::Zero(), InputVector::Zero()};
  Trajectory out;
  const long n = sc.samples();
  InputVector q = sc.initial.head<kInputCount>();
  DynamicsTerms terms;
  Vector4 u;
  for (int k = 0; k < 4; ++k) u(k) = sc.rates(kCommandedSpeeds[static_cast<std::size_t>(k)]);
  for (long k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * sc.dt;
    try {
      const InputVector k1 = f(q);
      Sample smp;
      smp.t = t;
      smp.s = f.s;
      smp.sdot = f.sdot;
      smp.cond_J_beta = data.cond_J_beta;
      forward_kinematics(model, f.s, data);
      smp.contacts << data.frame_positions(0, gen::frame::W_l), data.frame_positions(1, gen::frame::W_l),
          data.frame_positions(0, gen::frame::W_r), data.frame_positions(1, gen::frame::W_r);
      smp.contact_velocity = contact_velocities(model, f.s, f.sdot, data);  // also fills data.C, data.spin
      smp.nh_residual = data.C * f.sdot;
      smp.spin_rate = data.spin * f.sdot;
      smp.cabin_clearance = cabin_clearance(model.params(), f.s);
      if (sc.weighting) {
        inverse_dynamics(model, f.s, u, Vector4::Zero(), data, terms, sc.nonholonomic);
        smp.Qstar = terms.Qstar;
        smp.tau = distribute_torques(terms.J_beta, terms.Qstar, *sc.weighting);
      }
      on_sample(smp);
      if (progress) progress(k + 1, n);
      if (k + 1 == n) break;
      if (sc.integrator == Integrator::euler) {
        q += sc.dt * k1;
      } else {
        const InputVector k2 = f(q + 0.5 * sc.dt * k1);
        const InputVector k3 = f(q + 0.5 * sc.dt * k2);
        const InputVector k4 = f(q + sc.dt * k3);
        q += sc.dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      }
    } catch (const Error& e) {
      out.complete = false;
      out.error = fmt::format("stopped at t = {:.4f} s (step {} of {}): {}", t, k, n - 1, e.what());
      break;
    }
  }
  return out;
}

}  // namespace wlx
