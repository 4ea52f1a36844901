// The structure the two dynamics passes are built on: the coordinates' roles in s' = T u, the
// commanded speeds each rate depends on (T's pattern), and the tree of the bodies' chains.
#include "derivations_internal.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <set>

namespace wlx::codegen {

namespace derivation {

bool same_joint(const JointRecord& a, const JointRecord& b) {
  if (a.coordinate != b.coordinate || a.revolute != b.revolute) return false;
  for (int c = 0; c < 3; ++c)
    if (!a.axis[c].is_equal(b.axis[c]) || !a.origin[c].is_equal(b.origin[c])) return false;
  return true;
}

RateRoles rate_roles(const Model& m) {
  const Dynamics& dyn = *m.dynamics;
  const int n = coordinate_count(m);
  const std::vector<int> pair = m.wheels.empty() ? std::vector<int>{} : m.pair(dyn.pair).coordinates;
  RateRoles roles{std::vector<int>(static_cast<std::size_t>(n), -1), std::vector<bool>(static_cast<std::size_t>(n), false)};
  for (std::size_t k = 0; k < dyn.commanded.size(); ++k) roles.speed_of[static_cast<std::size_t>(dyn.commanded[k])] = static_cast<int>(k);
  for (int j = 0; j < n; ++j) roles.dense[static_cast<std::size_t>(j)] = j >= m.input_count || std::count(pair.begin(), pair.end(), j) > 0;
  return roles;
}

std::vector<std::vector<int>> rate_speeds(const Model& m, const RateRoles& roles) {
  const std::vector<int>& speed_of = roles.speed_of;
  const auto dense = [&](int j) { return roles.dense[static_cast<std::size_t>(j)]; };
  const int n = coordinate_count(m);
  std::vector<std::vector<ex>> rows;
  for (const auto& c : m.closure) rows.push_back(closure_row(m, c).gradient);
  if (m.dynamics && !m.wheels.empty())
    for (const auto& wheel : m.wheels) rows.push_back(wheel_row(m, wheel).C);
  // Union-find over the rows (0 .. rows-1) and the coordinates (rows + j).
  const int count = static_cast<int>(rows.size()) + n;
  std::vector<int> parent(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) parent[static_cast<std::size_t>(i)] = i;
  const std::function<int(int)> root = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  };
  const int R = static_cast<int>(rows.size());
  for (int r = 0; r < R; ++r)
    for (int j = 0; j < n; ++j)
      if (dense(j) && !rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(j)].is_zero()) parent[static_cast<std::size_t>(root(r))] = root(R + j);
  std::map<int, std::set<int>> block_speeds;
  std::set<int> blocks_with_rows;
  for (int r = 0; r < R; ++r) {
    blocks_with_rows.insert(root(r));
    for (int j = 0; j < n; ++j)
      if (speed_of[static_cast<std::size_t>(j)] >= 0 && !rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(j)].is_zero())
        block_speeds[root(r)].insert(speed_of[static_cast<std::size_t>(j)]);
  }
  const int nu = static_cast<int>(std::count_if(speed_of.begin(), speed_of.end(), [](int k) { return k >= 0; }));
  std::vector<std::vector<int>> out(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    auto& speeds = out[static_cast<std::size_t>(j)];
    if (speed_of[static_cast<std::size_t>(j)] >= 0) {
      speeds = {speed_of[static_cast<std::size_t>(j)]};
    } else if (dense(j)) {
      const int b = root(R + j);
      if (!blocks_with_rows.count(b)) {  // no row fixes it (the solve would fail): assume every speed
        for (int k = 0; k < nu; ++k) speeds.push_back(k);
      } else {
        speeds.assign(block_speeds[b].begin(), block_speeds[b].end());
      }
    }
  }
  return out;
}

std::array<ex, 6> spatial_axis(const JointRecord& joint) {
  const Vec3 linear = joint.revolute ? cross(joint.origin, joint.axis) : joint.axis;
  std::array<ex, 6> S;
  for (int c = 0; c < 3; ++c) {
    S[static_cast<std::size_t>(c)] = joint.revolute ? joint.axis[c] : ex(0);
    S[static_cast<std::size_t>(c + 3)] = linear[c];
  }
  return S;
}

TwistTree twist_tree(const Model& m, const RateRoles& roles) {
  TwistTree tree;
  std::vector<int> roots;  // the nodes next to K0
  tree.body_node.assign(m.bodies.size(), -1);
  tree.body_R.assign(m.bodies.size(), Mat3::identity());
  tree.body_r.assign(m.bodies.size(), Vec3());
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    int at = -1;
    // The placement since the last moving joint: the held joints' in between, composed.
    Mat3 held_R = Mat3::identity();
    Vec3 held_r;
    for (const JointRecord& joint : m.bodies[i].com_frame.joints) {
      if (!roles.moves(joint.coordinate)) {
        held_r = held_r + held_R * joint.placement_r;
        held_R = held_R * joint.placement_R;
        continue;
      }
      std::vector<int>& siblings = at < 0 ? roots : tree.nodes[static_cast<std::size_t>(at)].children;
      int next = -1;
      for (int c : siblings)
        if (same_joint(*tree.nodes[static_cast<std::size_t>(c)].joint, joint)) next = c;
      if (next < 0) {
        next = static_cast<int>(tree.nodes.size());
        siblings.push_back(next);  // before nodes grows: `siblings` may live in it
        tree.nodes.push_back({&joint, at, {}, {}, held_R * joint.placement_R, held_r + held_R * joint.placement_r});
      }
      at = next;
      held_R = Mat3::identity();
      held_r = Vec3();
    }
    tree.body_node[i] = at;
    tree.body_r[i] = held_r + held_R * m.bodies[i].com_frame.local_r;
    tree.body_R[i] = held_R * m.bodies[i].com_frame.local_R;
    if (at >= 0) tree.nodes[static_cast<std::size_t>(at)].bodies.push_back(static_cast<int>(i));
  }
  return tree;
}

}  // namespace derivation

std::vector<std::vector<int>> rate_basis_pattern(const Model& m) {
  const int n = derivation::coordinate_count(m);
  if (!m.dynamics) return std::vector<std::vector<int>>(static_cast<std::size_t>(n));
  return derivation::rate_speeds(m, derivation::rate_roles(m));
}

}  // namespace wlx::codegen
