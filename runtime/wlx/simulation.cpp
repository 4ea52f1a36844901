#include "wlx/simulation.hpp"

#include "wlx/error.hpp"
#include "wlx/kinematics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

using InputVector = Eigen::Matrix<double, kInputCount, 1>;

// The solution a run's continuation starts from: the dependent joints at the initial inputs, from
// the start values of Newton's method (nominal_inputs). A failure is left to the first evaluation,
// which reports it as the run's stop at t = 0.
void start_continuation(const Model& model, Coordinates& s, const Branches& branches) {
  Coordinates solved = s;
  try {
    solve_ik_closed_form(model, solved, branches);
    s = solved;
  } catch (const Error&) {
  }
}

// A kinematic run's right-hand side: the input rates at the inputs q (dependents re-solved first).
struct KinematicRates {
  const Scenario& sc;
  const Model& model;
  Data& data;
  Branches branches;  // the run's, chosen at its start (resolve_branches): one branch all along
  // Newton's limbs follow one solution from evaluation to evaluation (kContinuationJump).
  NewtonOptions continuation{.max_jump = kContinuationJump};
  Coordinates s = Coordinates::Zero(), sdot = Coordinates::Zero();
  long evaluations = 0;

  InputVector operator()(double /*t: the commanded rates are constant*/, const InputVector& q) {
    ++evaluations;
    s.head<kInputCount>() = q;
    solve_ik_closed_form(model, s, branches, nullptr, &continuation);
    sdot.head<kInputCount>() = sc.rates;
    solve_dependent_rates(model, data, s, sdot, sc.pair, sc.nonholonomic);
    return sdot.head<kInputCount>();
  }
};

// A torque-driven run's state: the inputs q, then the commanded speeds u.
using TorqueState = Eigen::Matrix<double, kInputCount + kCommandedCount, 1>;

// Its right-hand side: the dependents at q by the IK, u' by forward_dynamics under the source's
// torques at (t, s, u), and q' = the inputs' part of s' = T u.
struct TorqueRates {
  const Scenario& sc;
  const Model& model;
  Data& data;
  Branches branches;  // as KinematicRates'
  NewtonOptions continuation{.max_jump = kContinuationJump};
  Coordinates s = Coordinates::Zero();
  CommandVector u = CommandVector::Zero(), u_dot = CommandVector::Zero();
  TorqueVector tau = TorqueVector::Zero();
  DynamicsTerms terms = {};
  long evaluations = 0;

  TorqueState operator()(double t, const TorqueState& x) {
    ++evaluations;
    s.head<kInputCount>() = x.head<kInputCount>();
    u = x.tail<kCommandedCount>();
    solve_ik_closed_form(model, s, branches, nullptr, &continuation);
    tau = sc.torques(t, s, u);
    if (!tau.allFinite()) throw Error("torques", fmt::format("the torque source gave a non-finite torque at t = {:.6f} s", t));
    forward_dynamics(model, data, s, u, tau, u_dot, terms, sc.nonholonomic);
    TorqueState rate;
    rate << terms.sdot.head<kInputCount>(), u_dot;
    return rate;
  }
};

// The Dormand-Prince 5(4) pair (Hairer, Norsett, Wanner, Solving ODEs I, table 5.2): the nodes c_i,
// the stages, the 5th-order weights (= the last stage row: first same as last) and the difference
// to the embedded 4th-order weights, which estimates the local error.
namespace dopri {
constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176, a65 = -5103.0 / 18656;
constexpr double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784, b6 = 11.0 / 84;
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200, e6 = 22.0 / 525,
                 e7 = -1.0 / 40;
}  // namespace dopri

// Advances x from t to t + span with Dormand-Prince steps under error control; f(t, x) is the
// right-hand side. `h` carries the step size from one call to the next; k1 = f(t, x) on entry.
template <class State, class F>
void dopri5_span(F& f, State& x, State k1, double t, double span, double tolerance, double& h, Trajectory& stats) {
  using namespace dopri;
  const double end = t + span;
  double now = t;
  int rejected_in_a_row = 0;
  while (now < end) {
    const bool last = h >= (end - now) * (1 - 1e-12);  // finish the span rather than leave a sliver
    const double step = last ? end - now : h;
    State next, k7;
    double scaled = 0;
    std::string failure;  // a stage that left the workspace (unreachable pose, singular J_beta)
    ErrorKind failure_kind = ErrorKind::other;
    try {
      const State k2 = f(now + c2 * step, x + step * a21 * k1);
      const State k3 = f(now + c3 * step, x + step * (a31 * k1 + a32 * k2));
      const State k4 = f(now + c4 * step, x + step * (a41 * k1 + a42 * k2 + a43 * k3));
      const State k5 = f(now + c5 * step, x + step * (a51 * k1 + a52 * k2 + a53 * k3 + a54 * k4));
      const State k6 = f(now + step, x + step * (a61 * k1 + a62 * k2 + a63 * k3 + a64 * k4 + a65 * k5));
      next = x + step * (b1 * k1 + b3 * k3 + b4 * k4 + b5 * k5 + b6 * k6);
      k7 = f(now + step, next);
      const State error = step * (e1 * k1 + e3 * k3 + e4 * k4 + e5 * k5 + e6 * k6 + e7 * k7);
      scaled = (error.array().abs() / (tolerance * (1 + x.array().abs().max(next.array().abs())))).maxCoeff();
      if (!std::isfinite(scaled)) {  // an overflow, not an error estimate: shrink, and say so if it persists
        failure = "a stage of the step became non-finite (inf or NaN)";
        scaled = 1e10;
      }
    } catch (const Error& e) {
      // The stages reach ahead of the step (up to 3.7 step lengths with these coefficients), so
      // a long step can probe poses the motion itself never reaches: reject and shrink. A real
      // failure shrinks the step to nothing and is reported below.
      failure = e.what();
      failure_kind = e.kind();
      scaled = 1e10;
    }
    // The usual controller: the error scales as step^5; a safety factor and bounded changes.
    const double factor = std::clamp(0.9 * std::pow(std::max(scaled, 1e-10), -0.2), 0.2, 5.0);
    if (scaled <= 1) {
      x = next;
      k1 = k7;  // first same as last
      now = last ? end : now + step;
      ++stats.steps;
      rejected_in_a_row = 0;
      if (!last || factor < 1) h = step * factor;  // a step clipped to the sample time says little
    } else {
      ++stats.rejected_steps;
      h = step * std::min(factor, 0.5);
      if (++rejected_in_a_row > 60 || h < 1e-14 * std::max(1.0, std::abs(end))) {
        if (!failure.empty())
          throw Error("", fmt::format("at t = {:.6f} s (adaptive step {:.3g} s): {}", now, step, failure), failure_kind);
        throw Error("tolerance", fmt::format("the adaptive step fell to {:.3g} s at t = {:.6f} s without meeting the "
                                             "tolerance {:.3g}: the motion is not smooth here (a singular J_beta or a "
                                             "limb at its reach); use rk4 with a small dt or loosen the tolerance",
                                             h, now, tolerance));
      }
    }
  }
}

// What drives a run's numbers, for a message about a value that became non-finite: the largest
// commanded rate, gravity and the heaviest body.
std::string drivers(const Scenario& sc) {
  int fastest = 0;
  for (int k = 1; k < kInputCount; ++k)
    if (std::abs(sc.rates(k)) > std::abs(sc.rates(fastest))) fastest = k;
  double heaviest = 0;
  for (const auto& body : gen::kBodyMass) heaviest = std::max(heaviest, sc.params.*body.mass);
  return fmt::format("inputs driving it: largest commanded rate {}' = {:g}, g = {:g} m/s^2, heaviest body {:g} kg",
                     gen::kCoordinateNames[static_cast<std::size_t>(fastest)], sc.rates(fastest), sc.params.*gen::kGravity, heaviest);
}

// Throws naming the first quantity of a sample (its CSV column) that is not finite: caught where
// it arises rather than when a file is written, with the time and the inputs that drive it.
void check_finite(const Sample& smp, const Scenario& sc) {
  const auto fail = [&](const std::string& name, double value) {
    throw Error(name, fmt::format("became non-finite ({}) at t = {:.6f} s; {}", value, smp.t, drivers(sc)));
  };
  const auto name = [](int k) { return std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]); };
  for (int k = 0; k < kCoordinateCount; ++k) {
    if (!std::isfinite(smp.s(k))) fail(name(k), smp.s(k));
    if (!std::isfinite(smp.sdot(k))) fail(name(k) + "_dot", smp.sdot(k));
  }
  for (int w = 0; w < kWheelCount; ++w) {
    const std::string stem = contact_column_stem(w);
    const std::string_view wheel = gen::kWheels[static_cast<std::size_t>(w)].name;
    for (int i = 0; i < 2; ++i)
      if (!std::isfinite(smp.contacts(2 * w + i))) fail(fmt::format("{}_{}", "xy"[i], stem), smp.contacts(2 * w + i));
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(smp.contact_velocity(i, w)))
        fail(fmt::format("v{}_{}", "xyz"[i], stem), smp.contact_velocity(i, w));
    if (!std::isfinite(smp.nh_residual(w))) fail(fmt::format("nh_residual_{}", wheel), smp.nh_residual(w));
    if (!std::isfinite(smp.spin_rate(w))) fail(fmt::format("spin_rate_{}", wheel), smp.spin_rate(w));
  }
  if (!std::isfinite(smp.cond_J_beta)) fail("cond_J_beta", smp.cond_J_beta);
  if (std::isnan(smp.clearance) || smp.clearance == -std::numeric_limits<double>::infinity()) fail("clearance", smp.clearance);
  for (int k = 0; k < kActuatedCount; ++k)
    if (!std::isfinite(smp.tau(k))) fail("tau_" + std::string(kActuatorNames[static_cast<std::size_t>(k)]), smp.tau(k));
  for (int k = 0; k < kCommandedCount; ++k)
    if (!std::isfinite(smp.Qstar(k))) fail("Qstar_" + name(kCommandedSpeeds[static_cast<std::size_t>(k)]), smp.Qstar(k));
}

// What in a sample leaves the joints' limits (the first range, else the first speed), or "".
std::string limit_violation(const Sample& smp) {
  if (const int k = first_outside_limits(smp.s); k >= 0) return describe_outside_limits(smp.s, k);
  const auto& limit = settings().velocity_limit;
  for (int k = 0; k < kCoordinateCount; ++k) {
    const double v = limit[static_cast<std::size_t>(k)];
    if (v > 0 && !(std::abs(smp.sdot(k)) <= v))
      return fmt::format("{}'s rate {:.6g} is above its largest speed {:.6g}", gen::kCoordinateNames[static_cast<std::size_t>(k)],
                         smp.sdot(k), v);
  }
  return {};
}

}  // namespace

std::string_view integrator_name(Integrator integrator) noexcept {
  switch (integrator) {
    case Integrator::rk4: return "rk4";
    case Integrator::euler: return "euler";
    case Integrator::dopri5: return "dopri5";
  }
  return "?";
}

std::optional<Integrator> integrator_from_name(std::string_view name) noexcept {
  for (Integrator i : {Integrator::rk4, Integrator::euler, Integrator::dopri5})
    if (integrator_name(i) == name) return i;
  return std::nullopt;
}

CommandVector Scenario::commanded_speeds() const {
  CommandVector u;
  for (int k = 0; k < kCommandedCount; ++k) u(k) = rates(kCommandedSpeeds[static_cast<std::size_t>(k)]);
  return u;
}

long Scenario::samples() const { return std::lround(duration / dt) + 1; }

void validate_time_grid(double duration, double dt) {
  if (!(std::isfinite(duration) && duration > 0))
    throw Error("duration", fmt::format("must be a positive number of seconds, got {}", duration));
  if (!(std::isfinite(dt) && dt > 0)) throw Error("dt", fmt::format("must be a positive number of seconds, got {}", dt));
  if (duration / dt > 1e8)
    throw Error("dt", fmt::format("{} s over {} s is {:.3g} steps, more than the limit of 1e8", dt, duration, duration / dt));
  if (std::abs(duration / dt - std::round(duration / dt)) > 1e-6 * (duration / dt))
    throw Error("dt", fmt::format("the duration {} s is not a whole number of steps of {} s", duration, dt));
}

void Scenario::validate() const {
  validate_time_grid(duration, dt);
  if (integrator == Integrator::dopri5 && !(std::isfinite(tolerance) && tolerance >= 1e-14 && tolerance <= 1e-2))
    throw Error("tolerance", fmt::format("must be between 1e-14 (rounding) and 1e-2, got {}", tolerance));
  for (int k : pair.index)
    if (rates(k) != 0)
      throw Error(fmt::format("rates.{}", gen::kCoordinateNames[static_cast<std::size_t>(k)]),
                  fmt::format("{} is a dependent rate in this scenario (pair {}): it is computed, not commanded",
                              gen::kCoordinateNames[static_cast<std::size_t>(k)], pair.label()));
  if (weighting && torques)
    throw Error("torques", "a run is driven by its rates (the weighting then splits their torques) or by torques, not both");
  if (weighting || torques) {
    const char* run = torques ? "a forward-dynamics run" : "an inverse-dynamics run";
    if (pair.index != dynamics_pair().index)
      throw Error("dependent", fmt::format("{} needs the dependent pair {} (the model's dynamics section), got {}", run,
                                           dynamics_pair().label(), pair.label()));
    for (int k = 0; k < kInputCount; ++k)
      if (rates(k) != 0 && std::find(kCommandedSpeeds.begin(), kCommandedSpeeds.end(), k) == kCommandedSpeeds.end()) {
        std::string commanded;
        for (std::size_t i = 0; i < kCommandedSpeeds.size(); ++i)
          commanded += fmt::format("{}{}", i == 0 ? "" : i + 1 == kCommandedSpeeds.size() ? " and " : ", ",
                                   gen::kCoordinateNames[static_cast<std::size_t>(kCommandedSpeeds[i])]);
        throw Error(fmt::format("rates.{}", gen::kCoordinateNames[static_cast<std::size_t>(k)]),
                    fmt::format("{} commands only {}; every other input is constant", run, commanded));
      }
  }
  for (int k = 0; k < kInputCount; ++k) {
    const std::string name(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    if (!std::isfinite(initial(k))) throw Error("initial." + name, fmt::format("must be a finite number, got {}", initial(k)));
    if (!std::isfinite(rates(k))) throw Error("rates." + name, fmt::format("must be a finite number, got {}", rates(k)));
  }
}

double lowest_clearance(const Model& model, const Coordinates& s) {
// wlx-gen writes clearance.hpp only for a model file with a clearance box (and removes a stale one).
#if __has_include(<wlx/gen/clearance.hpp>)
  double lowest = 0;
  gen::clearance(s, model.params(), {.lowest = &lowest});
  return lowest;
#else
  static_cast<void>(model);
  static_cast<void>(s);
  return std::numeric_limits<double>::infinity();
#endif
}

namespace {

// A sample's kinematic part: what the run's last evaluation left in (s, s') and data.
void kinematic_sample(const Model& model, Data& data, const Coordinates& s, const Coordinates& sdot, Sample& smp) {
  smp.s = s;
  smp.sdot = sdot;
  smp.cond_J_beta = data.cond_J_beta;
  forward_kinematics(model, data, s);
  for (int w = 0; w < kWheelCount; ++w) {
    const int f = gen::kWheels[static_cast<std::size_t>(w)].contact_frame;
    for (int i = 0; i < 2; ++i) smp.contacts(2 * w + i) = data.frame_positions(i, f);  // compiles for no wheels
  }
  smp.contact_velocity = contact_velocities(model, data, s, sdot);  // also fills data.C, data.spin
  smp.nh_residual = data.C * sdot;
  smp.spin_rate = data.spin * sdot;
  smp.clearance = lowest_clearance(model, s);
}

// A dynamics sample's contact forces, margins and momentum balance; the run stops where a contact
// would pull on the ground or the machine would tip (unless asked to go on), and always where the
// forces do not balance the bodies' accelerations: a result the model does not satisfy.
void contact_sample(const Model& model, Data& data, const Scenario& sc, const Coordinates& s, const DynamicsTerms& terms,
                    const TorqueVector& tau, Sample& smp) {
  if constexpr (kContactCount > 0) {
    // A non-finite torque or force is named by check_finite, which runs next, by its column.
    if (!(tau.allFinite() && terms.tau_bodies.allFinite())) return;
    contact_forces(model, data, s, terms, tau, smp.forces);
    const MomentumBalance balance = momentum_balance(model, data, s, terms.sdot, terms.sddot, smp.forces);
    smp.momentum_residual = std::max(balance.force, balance.moment);
    if (!(smp.momentum_residual <= 1e-6))
      throw Error("contacts", fmt::format("the contact forces do not balance the bodies' accelerations (relative residual "
                                          "{:.3g}): a held input moves the machine as a whole, or the model's contacts are "
                                          "not all closure rows to the ground",
                                          smp.momentum_residual));
    stability(model, data, s, smp.forces, smp.stability);
    if (!sc.stop_on_contact_loss) return;
    // Tipping first: where it happens a contact also unloads, and the edge says more.
    if (smp.stability.polygon_size == 0)
      throw Error("contacts", "no contact carries load: the machine leaves the ground, which the model does not describe",
                  ErrorKind::contact);
    if (smp.stability.tip_angle <= 0)
      throw Error("contacts", fmt::format("the machine tips over the edge {}-{} (force-angle margin {:.4g} deg)",
                                          contact_name(smp.stability.tip_edge[0]), contact_name(smp.stability.tip_edge[1]),
                                          smp.stability.tip_angle * 180 / 3.14159265358979323846),
                  ErrorKind::contact);
    for (int c = 0; c < kContactCount; ++c)
      if (gen::kContacts[static_cast<std::size_t>(c)].supports && smp.forces.normal(c) < 0)
        throw Error("contacts", fmt::format("contact {} would pull on the ground (normal force {:.6g} N): it lifts off, which "
                                            "the model does not describe; another weighting may keep it down, or "
                                            "\"on_contact_loss\": \"continue\" goes on",
                                            contact_name(c), smp.forces.normal(c)),
                    ErrorKind::contact);
  } else {
    static_cast<void>(model), static_cast<void>(data), static_cast<void>(sc), static_cast<void>(s);
    static_cast<void>(terms), static_cast<void>(tau), static_cast<void>(smp);
  }
}

}  // namespace

Trajectory simulate(const Scenario& sc, const Progress& progress) {
  sc.validate();
  std::vector<Sample> samples;
  // Reserved up to a few thousand samples, then grown as the run goes: a sample holds the contact
  // forces and margins (about 2 KB), so all of a 10^6-step run reserved up front would claim
  // gigabytes a stopped run never uses (and take AddressSanitizer 0.6 s to release at a signal).
  samples.reserve(static_cast<std::size_t>(std::min<long>(sc.samples(), 4096)));
  Trajectory out = simulate_each(sc, [&](const Sample& smp) { samples.push_back(smp); }, progress);
  out.samples = std::move(samples);
  return out;
}

Trajectory simulate_each(const Scenario& sc, const std::function<void(const Sample&)>& on_sample, const Progress& progress) {
  sc.validate();
  const Model model(sc.params);
  auto data_storage = std::make_unique<Data>();  // ~7 KB: kept off the stack
  Data& data = *data_storage;
  Trajectory out;
  const long n = sc.samples();
  double h = sc.dt;  // dopri5's step, adapted as it goes

  // The loop of every run: a sample after each step's first evaluation, then the step. `name(i)`
  // names the state's entry i for a message about a value that became non-finite.
  const auto integrate = [&](auto& f, auto x, const auto& fill, const auto& name) {
    using State = decltype(x);
    for (long k = 0; k < n; ++k) {
      const double t = static_cast<double>(k) * sc.dt;
      try {
        const State k1 = f(t, x);
        Sample smp;
        smp.t = t;
        fill(smp);
        check_finite(smp, sc);
        if (const std::string why = limit_violation(smp); !why.empty()) {
          if (sc.stop_on_limit) throw Error("limits", why + " (\"on_limit\": \"continue\" goes on)", ErrorKind::limit);
          if (out.limit_warning.empty()) out.limit_warning = fmt::format("at t = {:.4f} s: {}", t, why);
        }
        on_sample(smp);
        if (progress) progress(k + 1, n);
        if (k + 1 == n) break;
        if (sc.integrator == Integrator::euler) {
          x += sc.dt * k1;
          ++out.steps;
        } else if (sc.integrator == Integrator::rk4) {
          const State k2 = f(t + 0.5 * sc.dt, State(x + 0.5 * sc.dt * k1));
          const State k3 = f(t + 0.5 * sc.dt, State(x + 0.5 * sc.dt * k2));
          const State k4 = f(t + sc.dt, State(x + sc.dt * k3));
          x += sc.dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
          ++out.steps;
        } else {
          dopri5_span(f, x, k1, t, sc.dt, sc.tolerance, h, out);
        }
        // Checked after every step: an overflow is reported in the step that made it.
        for (int i = 0; i < x.size(); ++i)
          if (!std::isfinite(x(i)))
            throw Error(name(i), fmt::format("became non-finite ({}) in the step to t = {:.6f} s; {}", x(i),
                                             static_cast<double>(k + 1) * sc.dt, drivers(sc)));
      } catch (const Error& e) {
        out.complete = false;
        out.error = fmt::format("stopped at t = {:.4f} s (step {} of {}): {}", t, k, n - 1, e.what());
        out.stop_time = t;
        out.stop_reason = e.what();
        out.stop_kind = e.kind();
        break;
      }
    }
    out.evaluations = f.evaluations;
  };
  const auto coordinate = [](int i) { return std::string(gen::kCoordinateNames[static_cast<std::size_t>(i)]); };

  if (sc.driven_by_torques()) {
    TorqueRates f{sc, model, data, resolve_branches(model, sc.initial, sc.branches)};
    TorqueState x;
    x << sc.initial.head<kInputCount>(), sc.commanded_speeds();
    f.s = sc.initial;
    start_continuation(model, f.s, f.branches);
    const auto fill = [&](Sample& smp) {
      kinematic_sample(model, data, f.s, f.terms.sdot, smp);
      smp.tau = f.tau;
      smp.Qstar = f.terms.Qstar;
      smp.u = f.u;
      smp.u_dot = f.u_dot;
      smp.power = f.tau.dot(f.terms.J_beta * f.u);
      smp.kinetic = kinetic_energy(model, data, f.s, f.terms.sdot);
      smp.potential = potential_energy(model, data, f.s);
      // The bodies' forces on s at this s'' (forward_dynamics' equations of motion do not give them).
      DynamicsTerms& t = f.terms;
#if __has_include(<wlx/gen/generalized_forces.hpp>)  // (a run driven by torques needs a dynamics section)
      gen::generalized_forces(f.s, t.sdot, t.sddot, t.T, model.params(), {.tau = &t.tau_bodies});
#endif
      contact_sample(model, data, sc, f.s, t, f.tau, smp);
      // Driven by torques, the body may fall: the model has no contact but its feet and wheels.
      if (smp.clearance < 0)
        throw Error("clearance", fmt::format("the clearance box's lowest corner is {:.4f} m below the ground: the body "
                                             "touches it, which the model does not describe", -smp.clearance),
                    ErrorKind::contact);
    };
    integrate(f, x, fill, [&](int i) {
      return i < kInputCount ? coordinate(i) : "u." + coordinate(kCommandedSpeeds[static_cast<std::size_t>(i - kInputCount)]);
    });
  } else {
    KinematicRates f{sc, model, data, resolve_branches(model, sc.initial, sc.branches)};
    f.s = sc.initial;
    start_continuation(model, f.s, f.branches);
    const CommandVector u = sc.commanded_speeds();
    DynamicsTerms terms;
    const auto fill = [&](Sample& smp) {
      kinematic_sample(model, data, f.s, f.sdot, smp);
      if (sc.weighting) {
        inverse_dynamics(model, data, f.s, u, CommandVector::Zero(), terms, sc.nonholonomic);
        smp.Qstar = terms.Qstar;
        smp.tau = sc.weighting->kind == Weighting::Kind::contacts
                      ? distribute_torques_on_contacts(model, data, f.s, terms).tau
                      : distribute_torques(terms.J_beta, terms.Qstar, *sc.weighting);
        contact_sample(model, data, sc, f.s, terms, smp.tau, smp);
      }
    };
    integrate(f, InputVector(sc.initial.head<kInputCount>()), fill, coordinate);
  }
  return out;
}

WLX_MODEL_NAMESPACE_END
