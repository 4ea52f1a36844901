// Emission of structure.hpp: prints the facts about the model's structure (structure_facts.hpp)
// as constexpr tables, one section per kind of fact.
#include "structure_facts.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace wlx::codegen {

namespace {

std::string int_list(const std::vector<int>& v) {
  std::string s;
  for (int x : v) s += (s.empty() ? "" : ", ") + std::to_string(x);
  return s;
}

// v filled up to n entries with -1, for a table's fixed-size array.
std::vector<int> padded(std::vector<int> v, std::size_t n) {
  v.resize(n, -1);
  return v;
}

const std::string& coordinate_name(const Model& m, int k) { return m.coordinates[static_cast<std::size_t>(k)].name; }

std::string structure_opening(const Model& m, const EmitOptions& opt) {
  std::string t = banner(m, opt, "Model structure: limbs, wheels, dependent pairs, inverse dynamics, nominal state.");
  t += "//\n// Everything the generic runtime needs to know about this model's structure, so that it never\n"
       "// names a coordinate, frame or parameter itself. Indices are into s (coord::), the frames (frame::),\n"
       "// the closure rows (kClosureNames) and the bodies (body::).\n";
  t += "#pragma once\n\n#include <array>\n#include <string_view>\n\n#include \"params.hpp\"\n#include \"types.hpp\"\n\n" +
       namespace_open(opt) + "\n";
  return t;
}

// Frames: parents, so that a drawing can connect them.
std::string frames_table(const StructureFacts& facts) {
  std::vector<std::string> derived;
  for (bool d : facts.frame_derived) derived.push_back(d ? "true" : "false");
  std::string t = "// Parent of each frame of interest (-1: the ground frame K0), in frame:: order.\n";
  t += fmt::format("inline constexpr std::array<int, {}> kFrameParent{{{{{}}}}};\n", facts.frame_parents.size(),
                   int_list(facts.frame_parents));
  t += fmt::format("// Whether the frame is one wlx-gen derived (a wheel's contact point, which slides round the rim as\n"
                   "// the hub tilts), not one fixed in the mechanism's chain.\n"
                   "inline constexpr std::array<bool, {}> kFrameDerived{{{{{}}}}};\n\n",
                   derived.size(), fmt::join(derived, ", "));
  return t;
}

std::string limbs_table(const Model& m, const StructureFacts& facts) {
  const std::size_t max_size = facts.max_limb_size, max_inputs = facts.max_limb_inputs;
  std::string t = fmt::format(
      "// Limbs: closure rows and the dependent joints they determine (a square diagonal block of dPhi/ds;\n"
      "// the rows of one limb involve no other limb's joints), and the inputs those rows read.\n"
      "inline constexpr int kLimbCount = {};\n"
      "inline constexpr int kMaxLimbSize = {};\n"
      "inline constexpr int kMaxLimbInputs = {};\n"
      "struct LimbInfo {{\n"
      "  std::string_view name;\n"
      "  std::string_view title;  // for messages\n"
      "  int size;                // rows = joints\n"
      "  std::array<int, kMaxLimbSize> rows;    // closure rows (-1 past size)\n"
      "  std::array<int, kMaxLimbSize> joints;  // dependent coordinates, in the order of the rows' unknowns\n"
      "  int input_count;\n"
      "  std::array<int, kMaxLimbInputs> inputs;  // the input coordinates the rows read\n"
      "}};\n",
      m.limbs.size(), max_size, max_inputs);
  t += fmt::format("inline constexpr std::array<LimbInfo, {}> kLimbs{{{{\n", m.limbs.size());
  for (std::size_t k = 0; k < m.limbs.size(); ++k) {
    const auto& l = m.limbs[k];
    const auto& inputs = facts.limb_inputs[k];
    std::string joints;
    for (int j : l.joints) joints += (joints.empty() ? "" : ", ") + coordinate_name(m, j);
    t += fmt::format("    {{\"{}\", {}, {}, {{{{{}}}}}, {{{{{}}}}}, {}, {{{{{}}}}}}},  // {}\n", l.name, quoted(l.title), l.rows.size(),
                     int_list(padded(l.rows, max_size)), int_list(padded(l.joints, max_size)), inputs.size(),
                     int_list(padded(inputs, max_inputs)), joints);
  }
  t += "}};\n";
  t += "namespace limb {\n";
  for (std::size_t k = 0; k < m.limbs.size(); ++k) t += fmt::format("inline constexpr int {} = {};\n", m.limbs[k].name, k);
  t += "}  // namespace limb\n\n";
  return t;
}

std::string wheels_table(const Model& m, const StructureFacts& facts) {
  std::string t =
      "// Wheels rolling without sliding sideways: contact frame, the input holding the ground level\n"
      "// under the wheel, and the rolling radius; for a wheel on a hub (its contact frame derived) the\n"
      "// hub frame and the axle (-1 where the model file builds the contact frame itself).\n"
      "struct WheelInfo {\n  std::string_view name;\n  int contact_frame;\n  int ground;\n  double Params::*radius;\n"
      "  int forward_axis;  // of the contact frame: 0 x, 1 y, 2 z\n  int lateral_axis;\n"
      "  int hub_frame;\n  int axle_axis;  // of the hub frame\n};\n";
  t += fmt::format("inline constexpr std::array<WheelInfo, {}> kWheels{{{{\n", m.wheels.size());
  for (std::size_t k = 0; k < m.wheels.size(); ++k) {
    const auto& w = m.wheels[k];
    t += fmt::format("    {{\"{}\", {}, {}, &Params::{}, {}, {}, {}, {}}},  // contact {}, ground {}\n", w.name,
                     facts.wheel_contact_frames[k], w.ground, w.radius, static_cast<int>(w.forward), static_cast<int>(w.lateral),
                     facts.wheel_hub_frames[k], w.hub.empty() ? -1 : static_cast<int>(w.axle), w.contact,
                     coordinate_name(m, w.ground));
  }
  t += "}};\n\n";
  return t;
}

std::string pairs_table(const Model& m, const StructureFacts& facts) {
  std::string t = fmt::format(
      "// The input rates that may be chosen as the dependent rates of the wheel constraints (one per\n"
      "// wheel), and the named choices.\n"
      "inline constexpr std::array<int, {}> kPairCandidates{{{{{}}}}};\n"
      "struct PairInfo {{\n  std::string_view name;\n  std::array<int, {}> coordinates;\n}};\n",
      m.pair_candidates.size(), int_list(m.pair_candidates), m.wheels.size());
  t += fmt::format("inline constexpr std::array<PairInfo, {}> kPairs{{{{\n", facts.pairs.size());
  for (const auto& p : facts.pairs) {
    std::vector<std::string> rates;
    for (int c : p.coordinates) rates.push_back(coordinate_name(m, c) + "'");
    t += fmt::format("    {{\"{}\", {{{{{}}}}}}},  // ({})\n", p.name, int_list(p.coordinates), fmt::join(rates, ", "));
  }
  t += fmt::format("}}}};\ninline constexpr int kDefaultPair = {};  // {}\n\n", facts.default_pair,
                   m.wheels.empty() ? "none" : m.default_pair);
  return t;
}

// Inverse dynamics (empty sets without a dynamics section: the runtime's types stay defined).
std::string dynamics_table(const Model& m, const StructureFacts& facts) {
  const Dynamics none{};
  const Dynamics& d = m.dynamics ? *m.dynamics : none;
  std::string commanded, actuated;
  std::vector<int> joints, wheels;
  std::vector<std::string> names;
  for (int k : d.commanded) commanded += (commanded.empty() ? "" : ", ") + coordinate_name(m, k);
  for (const Actuator& a : d.actuated) {
    actuated += (actuated.empty() ? "" : ", ") + a.name;
    joints.push_back(a.coordinate);
    wheels.push_back(a.wheel);
    names.push_back(quoted(a.name));
  }
  return fmt::format(
      "// Inverse dynamics: the commanded speeds u ({}), the dependent pair, the actuators\n"
      "// ({}), their default weights, and gravity (along -z of K0).\n"
      "// An actuator is a joint (kActuated: its coordinate) or the drive of a wheel on a hub\n"
      "// (kActuatedWheels: the wheel, whose spin relative to the hub is the drive's rate); -1 where not.\n"
      "inline constexpr bool kHasDynamics = {};\n"
      "inline constexpr std::array<int, {}> kCommanded{{{{{}}}}};\n"
      "inline constexpr int kDynamicsPair = {};  // {}\n"
      "inline constexpr std::array<int, {}> kActuated{{{{{}}}}};\n"
      "inline constexpr std::array<int, {}> kActuatedWheels{{{{{}}}}};\n"
      "inline constexpr std::array<std::string_view, {}> kActuatorNames{{{{{}}}}};\n"
      "inline constexpr double Params::*kGravity = {};\n\n",
      m.dynamics ? commanded : "none: the model file has no dynamics section", actuated, m.dynamics ? "true" : "false",
      d.commanded.size(), int_list(d.commanded), facts.dynamics_pair, m.dynamics ? d.pair : "none", joints.size(),
      int_list(joints), wheels.size(), int_list(wheels), names.size(), fmt::join(names, ", "),
      m.dynamics ? "&Params::" + d.gravity : "nullptr");
}

// The rate basis' structure.
std::string rate_basis_table(const Model& m, const StructureFacts& facts) {
  const int n = static_cast<int>(m.coordinates.size());
  const std::size_t nu = m.dynamics ? m.dynamics->commanded.size() : 0;
  std::string t = fmt::format(
      "// The rate basis T (s' = T u, one column per commanded speed): whether a coordinate's rate can\n"
      "// depend on a commanded speed. The closure's and the wheels' rows split the dependent rates into\n"
      "// independent blocks (a limb's joints with its wheel's rate, say), each moved only by the speeds\n"
      "// its rows involve; every other entry of T is exactly zero, and reduced_dynamics never reads it.\n"
      "inline constexpr std::array<std::array<bool, {}>, {}> kRateBasisPattern{{{{\n",
      nu, n);
  for (int j = 0; j < n; ++j) {
    const auto& speeds = facts.rate_basis[static_cast<std::size_t>(j)];
    std::vector<std::string> row;
    for (std::size_t k = 0; k < nu; ++k)
      row.push_back(std::binary_search(speeds.begin(), speeds.end(), static_cast<int>(k)) ? "true" : "false");
    t += fmt::format("    {{{{{}}}}},  // {}\n", fmt::join(row, ", "), coordinate_name(m, j));
  }
  t += "}};\n\n";
  return t;
}

// Body Jacobian columns, and the drive rows'.
std::string jacobian_columns_tables(const Model& m, const StructureFacts& facts) {
  const std::size_t max_columns = facts.max_columns;
  std::string t = fmt::format(
      "// Per body, the coordinates its velocity Jacobians Jv, Jw depend on: every other column is a\n"
      "// structural zero (bodies() never writes it).\n"
      "inline constexpr int kMaxBodyColumns = {};\n"
      "struct BodyColumns {{\n  int count;\n  std::array<int, kMaxBodyColumns> index;\n}};\n",
      max_columns);
  t += fmt::format("inline constexpr std::array<BodyColumns, {}> kBodyColumns{{{{\n", m.bodies.size());
  for (std::size_t k = 0; k < m.bodies.size(); ++k)
    t += fmt::format("    {{{}, {{{{{}}}}}}},  // {}\n", facts.body_columns[k].size(),
                     int_list(padded(facts.body_columns[k], max_columns)), m.bodies[k].name);
  t += "}};\n\n";
  t += fmt::format(
      "// Per wheel, the coordinates its drive row (dynamics_update's `drive`) depends on; every other\n"
      "// entry is a structural zero. Empty for a wheel without a drive.\n"
      "inline constexpr std::array<BodyColumns, {}> kDriveColumns{{{{\n",
      m.wheels.size());
  for (std::size_t w = 0; w < m.wheels.size(); ++w)
    t += fmt::format("    {{{}, {{{{{}}}}}}},  // {}\n", facts.drive_columns[w].size(),
                     int_list(padded(facts.drive_columns[w], max_columns)), m.wheels[w].name);
  t += "}};\n\n";
  return t;
}

// Closure rows, as the model file gives them (for checks that put a solution into the FK).
std::string closure_rows_table(const Model& m, const StructureFacts& facts) {
  std::string t =
      "// Each closure row: its kind, the frame it constrains, the K0 component (point) or the frame's axis\n"
      "// (level), and the input it equals (point), else -1.\n"
      "enum class RowKind { point, level, sum };\n"
      "struct ClosureRowInfo {\n  RowKind kind;\n  int frame;\n  int axis;\n  int target;\n};\n";
  t += fmt::format("inline constexpr std::array<ClosureRowInfo, {}> kClosureRows{{{{\n", m.closure.size());
  for (std::size_t k = 0; k < m.closure.size(); ++k) {
    const auto& c = m.closure[k];
    const char* kind = c.kind == ClosureCondition::Kind::PointEqualsCoordinate ? "point"
                       : c.kind == ClosureCondition::Kind::AttachedDirectionLevel ? "level" : "sum";
    t += fmt::format("    {{RowKind::{}, {}, {}, {}}},  // {}\n", kind, facts.closure_frames[k], static_cast<int>(c.axis),
                     c.target, c.name);
  }
  t += "}};\n\n";
  return t;
}

// Contacts with the ground: every frame that closure rows tie to K0 (point rows carry a force,
// level rows a moment) and every wheel's contact frame (its rolling row carries the lateral
// force, its drive the longitudinal one). Their multipliers are the forces the ground exerts;
// the runtime reads which rows belong to which contact from here and names no robot.
std::string contacts_table(const Model& m, const std::vector<GroundContact>& contacts) {
  std::string t =
      "// Contacts with the ground: each frame that closure rows tie to K0 and each wheel's contact frame.\n"
      "// The multipliers of a contact's point rows are the force the ground exerts on it (K0 components),\n"
      "// those of its level rows a moment about (axis x e_z); a wheel's rolling row adds the lateral force\n"
      "// along its contact frame's lateral axis, its drive torque / radius the longitudinal one. The\n"
      "// ground's normal is K0's z axis; `supports` says whether a z point row holds the contact up.\n"
      "enum class ContactKind { foot, wheel };\n"
      "struct ContactInfo {\n  std::string_view name;  // in output columns: f_n_<name>, ...\n  ContactKind kind;\n"
      "  int frame;\n  int wheel;  // kWheels' index, -1 for a foot\n"
      "  std::array<int, 3> point_rows;  // the closure rows of the origin's K0 x, y, z (-1: none)\n"
      "  std::array<int, 3> level_rows;  // the closure rows keeping the frame's x, y, z axis level (-1: none)\n"
      "  bool supports;\n};\n";
  t += fmt::format("inline constexpr int kContactCount = {};\n", contacts.size());
  t += fmt::format("inline constexpr std::array<ContactInfo, {}> kContacts{{{{\n", contacts.size());
  for (const auto& c : contacts)
    t += fmt::format("    {{\"{}\", ContactKind::{}, {}, {}, {{{{{}}}}}, {{{{{}}}}}, {}}},  // {}\n", c.name,
                     c.wheel >= 0 ? "wheel" : "foot", c.frame, c.wheel, int_list(std::vector<int>(c.point.begin(), c.point.end())),
                     int_list(std::vector<int>(c.level.begin(), c.level.end())), c.point[2] >= 0 ? "true" : "false",
                     m.frames[static_cast<std::size_t>(c.frame)].name);
  t += "}};\n\n";
  return t;
}

// The IK sweeps' type (their values: settings.hpp or model.json) and the clearance box's frame.
std::string sweeps_and_clearance(const Model& m, int clearance_frame) {
  std::string t =
      "// The IK verification: each sweep moves one input over [from, to] in steps (SI units), from the\n"
      "// inputs kSweepStart, and checks one limb (the sweeps: settings.hpp or model.json).\n"
      "struct SweepInfo {\n  std::string_view id;\n  int input;\n  double from, to, step;\n"
      "  bool degrees;  // quoted in degrees\n  int limb;\n  int branch;  // the limb's branch along the sweep; -1: the model's choice\n};\n\n";
  t += fmt::format("inline constexpr bool kHasClearance = {};\n"
                   "// The frame the clearance box moves with (frame::; -1: none); its size: clearance()'s half_extents.\n"
                   "inline constexpr int kClearanceFrame = {};\n\n",
                   m.clearance ? "true" : "false", clearance_frame);
  return t;
}

}  // namespace

EmittedFile emit_structure_header(const Model& m, const EmitOptions& opt) {
  const StructureFacts facts = structure_facts(m);
  std::string t = structure_opening(m, opt);
  t += frames_table(facts);
  t += limbs_table(m, facts);
  t += wheels_table(m, facts);
  t += pairs_table(m, facts);
  t += dynamics_table(m, facts);
  t += rate_basis_table(m, facts);
  t += jacobian_columns_tables(m, facts);
  t += closure_rows_table(m, facts);
  t += contacts_table(m, facts.contacts);
  t += sweeps_and_clearance(m, facts.clearance_frame);
  t += namespace_close(opt);
  return {"wlx/gen/structure.hpp", t};
}

}  // namespace wlx::codegen
