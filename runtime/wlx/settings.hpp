// The model file's run-time settings: every number of the model file that no generated function
// holds (the parameters' values, the nominal state, Newton's starts, the IK sweeps, the actuators'
// weights and torque limits, the contacts' friction). They are data, not code: a model compiled in
// (a built-in model, an embedding) takes them from its generated settings.hpp; a model file's
// plugin, whose headers have none (wlx-gen --data-at-run-time), is handed them from its model.json
// when it is loaded, so that editing them recompiles nothing. The runtime reads them only here.
#pragma once

#include "wlx/model_namespace.hpp"

#include <wlx/gen/all.hpp>

#include <array>
#include <limits>
#include <string>
#include <vector>

WLX_MODEL_NAMESPACE_BEGIN

// One sweep of the IK verification (ik_verification.hpp): one input moved over [from, to] in steps,
// one limb checked.
struct IkSweep {
  std::string id;      // "IK-L1", ...
  std::string input;   // the swept input's name
  double from = 0, to = 0, step = 0;  // SI units (radians for angles)
  bool degrees = false;               // quoted in degrees
  int limb = 0;                       // gen::kLimbs' index
  int branch = -1;                    // the limb's branch along the sweep; -1: the model's choice at its start
  // Number of points, both ends included.
  int points() const;
  double value(int k) const;
};

struct Settings {
  gen::Params params;                                               // the parameters' values
  std::array<double, gen::kInputCount> nominal_inputs{};            // the nominal state's inputs
  std::array<double, gen::kDependentCount> dependent_start{};       // Newton's start (nominal and limbs' start)
  std::array<double, gen::kInputCount> sweep_start{};               // the IK sweeps' start inputs
  std::vector<IkSweep> ik_sweeps;
  std::array<double, gen::kActuated.size()> weights{};              // the actuators' default weights
  bool has_torque_limits = false;                                   // false: unlimited
  std::array<double, gen::kActuated.size()> torque_limits{};        // N m, each > 0 when given
  std::array<double, gen::kContactCount> friction{};                // Coulomb coefficient per contact (kContacts)
  // The joints' ranges, in coordinate order (-inf, inf: none): the IK prefers the branch within
  // them, verify ik and simulate check them. And their largest speeds (0: none).
  std::array<double, gen::kCoordinateCount> lower = unlimited(-1), upper = unlimited(1);
  std::array<double, gen::kCoordinateCount> velocity_limit{};
  // Each limb's default branch (the model file's limbs[].branch), or -1: none given.
  std::array<int, gen::kLimbCount> default_branch = no_default_branches();

  // Loops, not std::array::fill, which is constexpr only from C++20 (a project embedding the
  // runtime may compile it as C++17).
  static constexpr std::array<double, gen::kCoordinateCount> unlimited(int sign) {
    std::array<double, gen::kCoordinateCount> a{};
    for (auto& v : a) v = sign * std::numeric_limits<double>::infinity();
    return a;
  }
  static constexpr std::array<int, gen::kLimbCount> no_default_branches() {
    std::array<int, gen::kLimbCount> b{};
    for (auto& v : b) v = -1;
    return b;
  }
};

// The settings in use. A model compiled with its settings.hpp has them from the start; a plugin's
// runtime throws wlx::Error until set_settings() has been given its model.json's.
const Settings& settings();
// Whether settings() has anything to give (always, where settings.hpp is compiled in).
bool has_settings() noexcept;
// Replaces the settings (a plugin's loader, once, before any evaluation: not thread-safe against
// readers). Checks every number (finite; weights, limits positive; sweeps' indices in range) and
// throws wlx::Error naming the first bad one, leaving the settings as they were.
void set_settings(const Settings& settings);

WLX_MODEL_NAMESPACE_END
