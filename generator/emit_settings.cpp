// Emission of settings.hpp: the model file's run-time settings compiled in (written unless the
// data is read at run time from model.json).
#include "emit.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string>

namespace wlx::codegen {

EmittedFile emit_settings_header(const Model& m, const EmitOptions& opt) {
  const auto list = [](const auto& values, const auto& text) {
    std::string out;
    for (const auto& v : values) out += (out.empty() ? "" : ", ") + text(v);
    return out;
  };
  std::string h = banner(m, opt, "Model settings: the model file's numbers that no generated function holds, compiled in.");
  h += "//\n// The nominal state, Newton's starts, the IK sweeps, the actuators' weights and torque limits and\n"
       "// the contacts' friction, as the model file gives them. The runtime reads them through its\n"
       "// settings() (wlx/settings.hpp), which a plugin fills from model.json instead: a plugin's headers\n"
       "// have no settings.hpp, so that editing these numbers recompiles nothing.\n";
  h += "#pragma once\n\n#include <array>\n#include <limits>\n#include <string_view>\n\n#include \"structure.hpp\"\n\n" +
       namespace_open(opt) + "\n";

  // The joints' limits and the limbs' default branches.
  const auto bound = [](double v) {
    return std::isinf(v) ? std::string(v < 0 ? "-kNoLimit" : "kNoLimit") : literal(v);
  };
  std::vector<int> branches;
  for (const auto& l : m.limbs) branches.push_back(l.branch);
  h += fmt::format("inline constexpr double kNoLimit = std::numeric_limits<double>::infinity();\n"
                   "// The joints' ranges, in coord:: order (the model file's `limits` and a URDF's <limit>s; -kNoLimit and\n"
                   "// kNoLimit: none). The IK prefers the branch within them; verify ik and simulate check them.\n"
                   "inline constexpr std::array<double, {0}> kJointLower{{{{{1}}}}};\n"
                   "inline constexpr std::array<double, {0}> kJointUpper{{{{{2}}}}};\n"
                   "// The joints' largest speeds (rad/s or m/s; 0: none), in coord:: order.\n"
                   "inline constexpr std::array<double, {0}> kJointVelocityLimit{{{{{3}}}}};\n"
                   "// Each limb's default branch of its closed form (the model file's limbs[].branch; -1: none given, the\n"
                   "// runtime takes the first branch from 0 whose joints are within their ranges).\n"
                   "inline constexpr std::array<int, {4}> kDefaultBranches{{{{{5}}}}};\n\n",
                   m.coordinates.size(), list(m.lower, bound), list(m.upper, bound), list(m.velocity, literal), m.limbs.size(),
                   list(branches, [](int b) { return std::to_string(b); }));

  // Inverse dynamics (empty without a dynamics section, as structure.hpp's kActuated).
  const Dynamics none{};
  const Dynamics& d = m.dynamics ? *m.dynamics : none;
  std::vector<double> limits(d.actuated.size(), 0.0);
  if (!d.torque_limits.empty()) limits = d.torque_limits;
  h += fmt::format("// The actuators' default weights (the model file's dynamics.weights).\n"
                   "inline constexpr std::array<double, {}> kDefaultWeights{{{{{}}}}};\n"
                   "// The actuators' torque limits (|tau_i| <= limit, N m; the model file's dynamics.torque_limits),\n"
                   "// respected by the contact-keeping torque distribution; kHasTorqueLimits false: unlimited (zeros).\n"
                   "inline constexpr bool kHasTorqueLimits = {};\n"
                   "inline constexpr std::array<double, {}> kTorqueLimits{{{{{}}}}};\n\n",
                   d.weights.size(), list(d.weights, literal), d.torque_limits.empty() ? "false" : "true", limits.size(),
                   list(limits, literal));

  const std::vector<GroundContact> contacts = ground_contacts(m);
  h += fmt::format("// Each contact's Coulomb coefficient (kContacts' order; the model file's contacts.friction).\n"
                   "inline constexpr std::array<double, {}> kContactFriction{{{{{}}}}};\n\n",
                   contacts.size(), list(contacts, [](const GroundContact& c) { return literal(c.friction); }));

  h += fmt::format("// The IK verification's start inputs (the model file's nominal state with ik_sweeps.start) and sweeps.\n"
                   "inline constexpr std::array<double, {}> kSweepStart{{{{{}}}}};\n",
                   m.sweep_start.size(), list(m.sweep_start, literal));
  h += fmt::format("inline constexpr std::array<SweepInfo, {}> kIkSweeps{{{{\n", m.sweeps.size());
  for (const auto& sw : m.sweeps)
    h += fmt::format("    {{{}, {}, {}, {}, {}, {}, {}, {}}},  // {}\n", quoted(sw.id), sw.input, literal(sw.from), literal(sw.to),
                     literal(sw.step), sw.degrees ? "true" : "false", sw.limb, sw.branch,
                     m.coordinates[static_cast<std::size_t>(sw.input)].name);
  h += "}};\n\n";

  const auto inputs = static_cast<std::ptrdiff_t>(m.input_count);
  const std::vector<double> nominal(m.nominal.begin(), m.nominal.begin() + inputs), start(m.nominal.begin() + inputs, m.nominal.end());
  h += fmt::format("// The nominal inputs (the model file's `nominal`; the dependent joints follow from the IK).\n"
                   "inline constexpr std::array<double, {}> kNominalInputs{{{{{}}}}};\n"
                   "// Where Newton's method starts for the dependent joints when no earlier solution is at hand (the\n"
                   "// model file's `nominal` and the limbs' `start`; 0 where neither gives one), in coord:: order from\n"
                   "// the first dependent joint.\n"
                   "inline constexpr std::array<double, {}> kDependentStart{{{{{}}}}};\n\n",
                   nominal.size(), list(nominal, literal), start.size(), list(start, literal));
  return {"wlx/gen/settings.hpp", h + namespace_close(opt)};
}

}  // namespace wlx::codegen
