// Works out the facts about a model's structure that structure.hpp and settings.hpp state: frames'
// parents, the inputs each limb reads, the dependent pairs, the rate basis' and the Jacobians'
// structural nonzeros, and the contacts with the ground.
#include "structure_facts.hpp"

#include <algorithm>
#include <set>

namespace wlx::codegen {

namespace {

// Structural dependencies of one closure row: every coordinate it involves.
std::set<int> row_coordinates(const Model& m, const ClosureCondition& c) {
  std::set<int> out;
  if (c.kind == ClosureCondition::Kind::CoordinateSum) return {c.coordinates.begin(), c.coordinates.end()};
  for (const auto& j : m.frame(c.frame).joints) out.insert(j.coordinate);
  if (c.target >= 0) out.insert(c.target);
  return out;
}

void find_frame_parents(const Model& m, StructureFacts& facts) {
  for (const auto& f : m.frames) {
    facts.frame_parents.push_back(f.parent == "K0" ? -1 : m.frame_index(f.parent));
    facts.frame_derived.push_back(f.derived_from_wheel >= 0);
  }
}

void find_limb_inputs(const Model& m, StructureFacts& facts) {
  for (const auto& l : m.limbs) {
    facts.max_limb_size = std::max(facts.max_limb_size, l.rows.size());
    std::set<int> inputs;
    for (int r : l.rows)
      for (int k : row_coordinates(m, m.closure[static_cast<std::size_t>(r)]))
        if (k < m.input_count) inputs.insert(k);
    facts.limb_inputs.emplace_back(inputs.begin(), inputs.end());
    facts.max_limb_inputs = std::max(facts.max_limb_inputs, inputs.size());
  }
}

void find_wheel_frames(const Model& m, StructureFacts& facts) {
  for (const auto& w : m.wheels) {
    facts.wheel_contact_frames.push_back(m.frame_index(w.contact));
    facts.wheel_hub_frames.push_back(w.hub.empty() ? -1 : m.frame_index(w.hub));
  }
}

void find_pairs(const Model& m, StructureFacts& facts) {
  // A model without wheels has one pair, of no rates.
  facts.pairs = m.wheels.empty() ? std::vector<DependentPair>{{"none", {}}} : m.pairs;
  for (std::size_t k = 0; k < facts.pairs.size(); ++k)
    if (facts.pairs[k].name == m.default_pair) facts.default_pair = static_cast<int>(k);
  const std::string dynamics_pair = m.dynamics ? m.dynamics->pair : std::string();
  for (std::size_t k = 0; k < facts.pairs.size(); ++k)
    if (facts.pairs[k].name == dynamics_pair) facts.dynamics_pair = static_cast<int>(k);
}

// The coordinates a frame's velocity Jacobians have a nonzero column for.
std::vector<int> jacobian_columns(const Frame& frame, int n) {
  const auto Jv = linear_jacobian(frame, n);
  const auto Jw = angular_jacobian(frame, n);
  std::vector<int> cols;
  for (int j = 0; j < n; ++j) {
    bool nonzero = false;
    for (int i = 0; i < 3; ++i)
      nonzero = nonzero || !Jv[static_cast<std::size_t>(j)][i].is_zero() || !Jw[static_cast<std::size_t>(j)][i].is_zero();
    if (nonzero) cols.push_back(j);
  }
  return cols;
}

void find_jacobian_columns(const Model& m, StructureFacts& facts) {
  const int n = static_cast<int>(m.coordinates.size());
  for (const auto& b : m.bodies) {
    facts.body_columns.push_back(jacobian_columns(b.com_frame, n));
    facts.max_columns = std::max(facts.max_columns, facts.body_columns.back().size());
  }
  // Per wheel, the coordinates its drive row can depend on: the hub's velocity Jacobians' columns
  // (the row is t . Jv / r - a . Jw of the hub), none for a wheel without a drive.
  facts.drive_columns.resize(m.wheels.size());
  if (m.dynamics)
    for (const Actuator& a : m.dynamics->actuated) {
      if (a.wheel < 0) continue;
      auto& cols = facts.drive_columns[static_cast<std::size_t>(a.wheel)];
      cols = jacobian_columns(m.frame(m.wheels[static_cast<std::size_t>(a.wheel)].hub), n);
      facts.max_columns = std::max(facts.max_columns, cols.size());
    }
}

}  // namespace

StructureFacts structure_facts(const Model& m) {
  StructureFacts facts;
  find_frame_parents(m, facts);
  find_limb_inputs(m, facts);
  find_wheel_frames(m, facts);
  find_pairs(m, facts);
  facts.rate_basis = rate_basis_pattern(m);
  find_jacobian_columns(m, facts);
  for (const auto& c : m.closure) facts.closure_frames.push_back(c.frame.empty() ? -1 : m.frame_index(c.frame));
  facts.contacts = ground_contacts(m);
  facts.clearance_frame = m.clearance ? m.frame_index(m.clearance->frame) : -1;
  return facts;
}

std::vector<GroundContact> ground_contacts(const Model& m) {
  std::vector<GroundContact> contacts;
  const auto contact_of = [&](int frame) -> GroundContact& {
    for (auto& c : contacts)
      if (c.frame == frame) return c;
    contacts.push_back({{}, frame, -1, {-1, -1, -1}, {-1, -1, -1}, 0.0});
    return contacts.back();
  };
  for (std::size_t i = 0; i < m.closure.size(); ++i) {
    const auto& c = m.closure[i];
    if (c.kind == ClosureCondition::Kind::CoordinateSum) continue;  // joints among themselves: internal
    GroundContact& contact = contact_of(m.frame_index(c.frame));
    auto& rows = c.kind == ClosureCondition::Kind::PointEqualsCoordinate ? contact.point : contact.level;
    rows[static_cast<std::size_t>(c.axis)] = static_cast<int>(i);
  }
  for (std::size_t w = 0; w < m.wheels.size(); ++w) contact_of(m.frame_index(m.wheels[w].contact)).wheel = static_cast<int>(w);
  // Output columns are named by the frame without underscores (F_l: f_n_Fl), the contact points'
  // columns' convention; the frame's own name where two would collide.
  for (auto& c : contacts) {
    c.name = m.frames[static_cast<std::size_t>(c.frame)].name;
    c.name.erase(std::remove(c.name.begin(), c.name.end(), '_'), c.name.end());
    c.friction = c.wheel >= 0 ? m.friction.wheels : m.friction.feet;
  }
  for (std::size_t a = 0; a < contacts.size(); ++a)
    for (std::size_t b = 0; b < contacts.size(); ++b)
      if (a != b && contacts[a].name == contacts[b].name) contacts[a].name = m.frames[static_cast<std::size_t>(contacts[a].frame)].name;
  return contacts;
}

}  // namespace wlx::codegen
