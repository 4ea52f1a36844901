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

CommandVector Scenario::commanded_speeds() const {
  CommandVector u;
  for (int k = 0; k < kCommandedCount; ++k) u(k) = rates(kCommandedSpeeds[static_cast<std::size_t>(k)]);
  return u;
}

long Scenario::samples() const { return std::lround(duration / dt) + 1; }

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

  // The loop of every run (integration.hpp, compiled once): a sample after each step's first
  // evaluation, then the step. The state goes between the integrator's vectors and the run's
  // fixed-size ones at each evaluation. `name(i)` names the state's entry i for a message about a
  // value that became non-finite.
  const auto integrate = [&](auto& f, const auto& x0, const auto& fill, const auto& name) {
    using State = std::decay_t<decltype(x0)>;
    const integration::Rates rates = [&](double t, const Eigen::VectorXd& x, Eigen::VectorXd& rate) { rate = f(t, State(x)); };
    const auto sample = [&](long k, double t) {
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
    };
    static_cast<integration::Outcome&>(out) =
        integration::integrate(rates, Eigen::VectorXd(x0), {n, sc.dt, sc.integrator, sc.tolerance}, sample, name, [&] { return drivers(sc); });
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
