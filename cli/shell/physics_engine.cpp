// MuJoCo behind PhysicsEngine (physics_engine.hpp). Without MuJoCo (WLX_HAVE_MUJOCO undefined) only
// the message of why remains.
#include "physics_engine.hpp"

#include <wlx/error.hpp>

#ifdef WLX_HAVE_MUJOCO

#include "bounded_input.hpp"
#include "mjcf_export.hpp"
#include "mujoco_model.hpp"

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <fmt/format.h>
#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace wlx::cli {

std::string physics_engine_missing() { return {}; }

namespace {

using Json = nlohmann::json;

using FreeBase = EngineFreeBase;

int index_of(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

// The frames MuJoCo moves by a free joint (the export decides which: a free joint named as the
// frame) with their coordinates, from the frames' chains: slides along x, y, z, then three turns.
std::vector<FreeBase> read_free_bases(const Json& d, const std::vector<std::string>& coordinates, const mjModel* m) {
  std::vector<FreeBase> bases;
  for (const Json& f : d.at("frames")) {
    const std::string name = f.at("name");
    const int joint = mj_name2id(m, mjOBJ_JOINT, name.c_str());
    if (joint < 0 || m->jnt_type[joint] != mjJNT_FREE) continue;
    const auto refuse = [&](const std::string& why) {
      return Error("frames", fmt::format("frame {}: MuJoCo moves it by a free joint, but {}", name, why));
    };
    if (!f.contains("chain") || f.at("chain").size() != 6) throw refuse("its chain is not six steps");
    FreeBase b;
    b.frame = name;
    for (std::size_t i = 0; i < 6; ++i) {
      const Json& step = f.at("chain")[i];
      const char* kind = i < 3 ? "prismatic" : "revolute";
      if (!step.contains(kind) || !step.contains("coordinate")) throw refuse(fmt::format("its step {} is not a {} joint", i + 1, kind));
      const int c = index_of(coordinates, step.at("coordinate"));
      if (c < 0) throw refuse(fmt::format("its coordinate {} is not the model's", step.at("coordinate").dump()));
      const std::string axis = step.at(kind);
      const int a = axis == "x" ? 0 : axis == "y" ? 1 : axis == "z" ? 2 : -1;
      if (a < 0 || (i < 3 && a != static_cast<int>(i))) throw refuse(fmt::format("its step {} is along '{}'", i + 1, axis));
      (i < 3 ? b.position : b.angle)[i % 3] = c;
      if (i >= 3) b.axis[i - 3] = a;
    }
    bases.push_back(b);
  }
  return bases;
}

Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d H;
  H << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return H;
}

// The angle nearest `near` among a + 2 pi k: a free joint's angles read back without jumps.
double unwrap(double a, double near) {
  constexpr double kTurn = 2 * std::numbers::pi;
  return a + kTurn * std::round((near - a) / kTurn);
}

}  // namespace

struct PhysicsEngine::Impl {
  MjModelPtr m;
  MjDataPtr d;
  int coordinate_count = 0;
  std::vector<FreeBase> bases;
  std::vector<int> joint_coordinate;  // per MuJoCo joint: its coordinate, or -1 (a free joint, a wheel's spin)
  std::vector<int> joint_base;        // per MuJoCo joint: its floating base in `bases` (a free joint), or -1
  std::vector<int> motors;            // per actuator in the description's order: MuJoCo's actuator
  std::vector<std::string> contact_names;
  std::vector<int> contact_geoms;  // per contact: its geom
  std::vector<int> spin_joints;    // the wheels' spinning joints
  int ground = -1;                 // the ground plane's geom

  const FreeBase& base_of(int joint) const { return bases[static_cast<std::size_t>(joint_base[static_cast<std::size_t>(joint)])]; }

  void map_state(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& sdot, Eigen::MatrixXd& G,
                 Eigen::VectorXd& Gdot_sdot, Eigen::VectorXd& qpos) const {
    const int n = coordinate_count;
    G = Eigen::MatrixXd::Zero(m->nv, n);
    Gdot_sdot = Eigen::VectorXd::Zero(m->nv);
    qpos = Eigen::VectorXd::Zero(m->nq);
    for (int j = 0; j < m->njnt; ++j) {
      const int qa = m->jnt_qposadr[j], va = m->jnt_dofadr[j];
      if (m->jnt_type[j] == mjJNT_FREE) {
        const FreeBase& b = base_of(j);
        std::array<Eigen::Matrix3d, 3> R;
        for (std::size_t i = 0; i < 3; ++i) {
          qpos(qa + static_cast<int>(i)) = s(b.position[i]);
          G(va + static_cast<int>(i), b.position[i]) = 1;
          R[i] = Eigen::AngleAxisd(s(b.angle[i]), Eigen::Vector3d::Unit(b.axis[i])).toRotationMatrix();
        }
        const Eigen::Quaterniond q(R[0] * R[1] * R[2]);
        qpos.segment<4>(qa + 3) << q.w(), q.x(), q.y(), q.z();
        // omega_body = sum_i B_i e_i q_i' with B_i = (R_{i+1} ... R_3)^T, from B_3 = I by
        // B_i = B_{i+1} R_{i+1}^T; and B_i' likewise, with R_k^T' = -[e_k q_k']x R_k^T.
        Eigen::Matrix3d B = Eigen::Matrix3d::Identity(), Bdot = Eigen::Matrix3d::Zero();
        for (int i = 2; i >= 0; --i) {
          if (i < 2) {
            const std::size_t k = static_cast<std::size_t>(i + 1);
            const Eigen::Matrix3d Rt = R[k].transpose();
            const Eigen::Matrix3d Rt_dot = -hat(Eigen::Vector3d::Unit(b.axis[k]) * sdot(b.angle[k])) * Rt;
            Bdot = Bdot * Rt + B * Rt_dot;
            B = B * Rt;
          }
          const std::size_t u = static_cast<std::size_t>(i);
          const Eigen::Vector3d e = Eigen::Vector3d::Unit(b.axis[u]);
          G.block<3, 1>(va + 3, b.angle[u]) = B * e;
          Gdot_sdot.segment<3>(va + 3) += Bdot * e * sdot(b.angle[u]);
        }
        continue;
      }
      const int c = joint_coordinate[static_cast<std::size_t>(j)];
      if (c < 0) continue;  // a wheel's spin
      qpos(qa) = s(c);
      G(va, c) = 1;
    }
  }
};

PhysicsEngine::PhysicsEngine(const std::string& description_json, const std::vector<std::string>& coordinates)
    : impl_(std::make_unique<Impl>()) {
  Impl& e = *impl_;
  e.m = load_mjcf(mjcf_of_description(description_json).xml);
  e.d.reset(mj_makeData(e.m.get()));
  if (!e.d) throw Error("physics engine", "MuJoCo could not allocate its data");
  e.coordinate_count = static_cast<int>(coordinates.size());
  const Json d = parse_json_bounded(description_json, "model.json");
  e.bases = read_free_bases(d, coordinates, e.m.get());
  for (int j = 0; j < e.m->njnt; ++j) {
    const char* name = mj_id2name(e.m.get(), mjOBJ_JOINT, j);
    const bool free = e.m->jnt_type[j] == mjJNT_FREE;
    e.joint_coordinate.push_back(free || name == nullptr ? -1 : index_of(coordinates, name));
    int base = -1;
    for (std::size_t b = 0; free && b < e.bases.size(); ++b)
      if (name != nullptr && e.bases[b].frame == name) base = static_cast<int>(b);
    if (free && base < 0) throw Error("frames", fmt::format("MuJoCo's free joint {} is no frame's floating base", name == nullptr ? "" : name));
    e.joint_base.push_back(base);
  }
  for (const Json& a : d.at("actuated")) {
    const std::string name = a.at("name");
    const int id = mj_name2id(e.m.get(), mjOBJ_ACTUATOR, name.c_str());
    if (id < 0) throw Error("actuated", fmt::format("the exported model has no motor {}", name));
    e.motors.push_back(id);
  }
  // A wheel on a hub spins in a body of its own, spin_<wheel>, about the body's one hinge.
  for (const Json& w : d.at("wheels")) {
    const int body = mj_name2id(e.m.get(), mjOBJ_BODY, ("spin_" + w.at("name").get<std::string>()).c_str());
    if (body >= 0 && e.m->body_jntnum[body] == 1) {
      e.spin_joints.push_back(e.m->body_jntadr[body]);
      e.joint_coordinate[static_cast<std::size_t>(e.m->body_jntadr[body])] = -1;  // whatever its name: no coordinate
    }
  }
  e.ground = mj_name2id(e.m.get(), mjOBJ_GEOM, "ground");
  if (e.ground < 0) throw Error("physics engine", "the exported model has no ground plane");
  for (const Json& c : d.at("contacts")) {
    const std::string name = c.at("name"), frame = c.at("frame");
    const int geom = mj_name2id(e.m.get(), mjOBJ_GEOM, frame.c_str());
    if (geom < 0) throw Error("contacts", fmt::format("contact {}: the exported model has no geom {}", name, frame));
    e.contact_names.push_back(name);
    e.contact_geoms.push_back(geom);
  }
}

PhysicsEngine::~PhysicsEngine() = default;

double PhysicsEngine::timestep() const { return impl_->m->opt.timestep; }

EngineMapping PhysicsEngine::mapping(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& sdot) const {
  EngineMapping out;
  impl_->map_state(s, sdot, out.G, out.Gdot_sdot, out.qpos);
  return out;
}

const std::vector<EngineFreeBase>& PhysicsEngine::free_bases() const { return impl_->bases; }

void PhysicsEngine::set_state(const Eigen::Ref<const Eigen::VectorXd>& s, const Eigen::Ref<const Eigen::VectorXd>& sdot) {
  const Impl& e = *impl_;
  const mjModel* m = e.m.get();
  mjData* d = e.d.get();
  Eigen::MatrixXd G;
  Eigen::VectorXd Gdot_sdot, qpos;
  e.map_state(s, sdot, G, Gdot_sdot, qpos);
  const Eigen::VectorXd qvel = G * sdot;
  mj_resetData(m, d);
  std::copy(qpos.data(), qpos.data() + m->nq, d->qpos);
  std::copy(qvel.data(), qvel.data() + m->nv, d->qvel);
  mj_forward(m, d);
  // Each spinning wheel: the spin rate w that minimises the horizontal speed of its lowest point,
  // v0 + w a x (p - c), the wheel's centre c on its axle a, p a radius below it.
  for (const int j : e.spin_joints) {
    const int body = m->jnt_bodyid[j];
    int geom = -1;
    for (int g = 0; g < m->ngeom; ++g)
      if (m->geom_bodyid[g] == body) geom = g;
    if (geom < 0) continue;
    const Eigen::Vector3d a(d->xaxis[3 * j], d->xaxis[3 * j + 1], d->xaxis[3 * j + 2]);
    const Eigen::Vector3d r(0, 0, -m->geom_size[3 * geom]);
    mjtNum v[6];
    mj_objectVelocity(m, d, mjOBJ_XBODY, body, v, 0);
    const Eigen::Vector3d v0 = Eigen::Vector3d(v[3], v[4], v[5]) + Eigen::Vector3d(v[0], v[1], v[2]).cross(r);
    const Eigen::Vector3d w = a.cross(r);
    const double ww = w.head<2>().squaredNorm();
    if (ww > 0) d->qvel[m->jnt_dofadr[j]] = -v0.head<2>().dot(w.head<2>()) / ww;
  }
  mj_forward(m, d);
}

void PhysicsEngine::read_state(Eigen::Ref<Eigen::VectorXd> s, Eigen::Ref<Eigen::VectorXd> sdot) const {
  const Impl& e = *impl_;
  const mjModel* m = e.m.get();
  const mjData* d = e.d.get();
  for (int j = 0; j < m->njnt; ++j) {
    const int qa = m->jnt_qposadr[j];
    if (m->jnt_type[j] == mjJNT_FREE) {
      const FreeBase& b = e.base_of(j);
      for (std::size_t i = 0; i < 3; ++i) s(b.position[i]) = d->qpos[qa + static_cast<int>(i)];
      const Eigen::Matrix3d R = Eigen::Quaterniond(d->qpos[qa + 3], d->qpos[qa + 4], d->qpos[qa + 5], d->qpos[qa + 6]).normalized().toRotationMatrix();
      // R = R_a(q1) R_b(q2) R_c(q3) about three different axes: sin q2 = eps R(a, c), with eps
      // +1 for a cyclic order of (a, b, c) and -1 otherwise.
      const int a = b.axis[0], bb = b.axis[1], c = b.axis[2];
      const double eps = (bb - a + 3) % 3 == 1 ? 1.0 : -1.0;
      const double q2 = std::asin(std::clamp(eps * R(a, c), -1.0, 1.0));
      const double q1 = std::atan2(-eps * R(bb, c), R(c, c));
      const double q3 = std::atan2(-eps * R(a, bb), R(a, a));
      s(b.angle[0]) = unwrap(q1, s(b.angle[0]));
      s(b.angle[1]) = unwrap(q2, s(b.angle[1]));
      s(b.angle[2]) = unwrap(q3, s(b.angle[2]));
      continue;
    }
    const int c = e.joint_coordinate[static_cast<std::size_t>(j)];
    if (c >= 0) s(c) = d->qpos[qa];
  }
  Eigen::MatrixXd G;
  Eigen::VectorXd Gdot_sdot, qpos;
  e.map_state(s, Eigen::VectorXd::Zero(s.size()), G, Gdot_sdot, qpos);
  const Eigen::Map<const Eigen::VectorXd> qvel(d->qvel, m->nv);
  const Eigen::VectorXd rates = G.colPivHouseholderQr().solve(qvel);
  for (int k = 0; k < G.cols(); ++k)
    if (!G.col(k).isZero()) sdot(k) = rates(k);
}

Eigen::VectorXd PhysicsEngine::set_torques(const Eigen::Ref<const Eigen::VectorXd>& tau) {
  const Impl& e = *impl_;
  if (tau.size() != static_cast<Eigen::Index>(e.motors.size()))
    throw Error("tau", fmt::format("{} values for {} actuators", tau.size(), e.motors.size()));
  Eigen::VectorXd applied = tau;
  for (std::size_t k = 0; k < e.motors.size(); ++k) {
    const int id = e.motors[k];
    double& value = applied(static_cast<Eigen::Index>(k));
    // MuJoCo would zero such a control with only a warning and step on: the run would go on
    // under torques nobody asked for.
    if (!std::isfinite(value) || std::abs(value) > mjMAXVAL) {
      const char* name = mj_id2name(e.m.get(), mjOBJ_ACTUATOR, id);
      throw Error("tau", fmt::format("actuator {}'s torque {:g} is not finite or beyond MuJoCo's bound of {:g}",
                                     name == nullptr ? std::to_string(k) : std::string(name), value, mjMAXVAL));
    }
    if (e.m->actuator_ctrllimited[id]) value = std::clamp(value, e.m->actuator_ctrlrange[2 * id], e.m->actuator_ctrlrange[2 * id + 1]);
    e.d->ctrl[id] = value;
  }
  return applied;
}

void PhysicsEngine::step() { mj_step(impl_->m.get(), impl_->d.get()); }

std::string PhysicsEngine::trouble() const {
  const mjData* d = impl_->d.get();
  for (const auto& [warning, what] : {std::pair{mjWARN_BADQACC, "accelerations"}, std::pair{mjWARN_BADQVEL, "velocities"},
                                      std::pair{mjWARN_BADQPOS, "positions"}, std::pair{mjWARN_BADCTRL, "controls"}})
    if (d->warning[warning].number > 0) {
      const std::string& said = mujoco_last_warning();
      return fmt::format("MuJoCo's simulation met {} that were not finite or too large and reset itself{}", what,
                         said.empty() ? "" : " (" + said + ")");
    }
  return {};
}

std::vector<EngineContact> PhysicsEngine::contacts() const {
  const Impl& e = *impl_;
  const mjModel* m = e.m.get();
  mjData* d = e.d.get();
  std::vector<EngineContact> out;
  for (std::size_t k = 0; k < e.contact_geoms.size(); ++k) {
    const int geom = e.contact_geoms[k];
    EngineContact c{e.contact_names[k], 0, 0};
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& con = d->contact[i];
      if (!((con.geom1 == geom && con.geom2 == e.ground) || (con.geom2 == geom && con.geom1 == e.ground))) continue;  // the ground's force only
      mjtNum f[6];
      mj_contactForce(m, d, i, f);
      c.normal += f[0] * std::abs(con.frame[2]);  // the normal's part along z: the plane's is z itself
    }
    // The material point a radius below the geom's centre (a wheel's rim, a foot's sphere).
    mjtNum v[6];
    mj_objectVelocity(m, d, mjOBJ_GEOM, geom, v, 0);
    const Eigen::Vector3d point = Eigen::Vector3d(v[3], v[4], v[5]) + Eigen::Vector3d(v[0], v[1], v[2]).cross(Eigen::Vector3d(0, 0, -m->geom_size[3 * geom]));
    c.slip = std::hypot(point.x(), point.y());
    out.push_back(c);
  }
  return out;
}

}  // namespace wlx::cli

#else  // no MuJoCo

namespace wlx::cli {

std::string physics_engine_missing() { return "wlx was built without MuJoCo (Debian's libmujoco-dev: tools/setup.sh installs it)"; }

struct PhysicsEngine::Impl {};
PhysicsEngine::PhysicsEngine(const std::string&, const std::vector<std::string>&) { throw Error("physics engine", physics_engine_missing()); }
PhysicsEngine::~PhysicsEngine() = default;
double PhysicsEngine::timestep() const { return 0; }
EngineMapping PhysicsEngine::mapping(const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>&) const { return {}; }
const std::vector<EngineFreeBase>& PhysicsEngine::free_bases() const {
  static const std::vector<EngineFreeBase> none;
  return none;
}
void PhysicsEngine::set_state(const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>&) {}
void PhysicsEngine::read_state(Eigen::Ref<Eigen::VectorXd>, Eigen::Ref<Eigen::VectorXd>) const {}
Eigen::VectorXd PhysicsEngine::set_torques(const Eigen::Ref<const Eigen::VectorXd>& tau) { return tau; }
void PhysicsEngine::step() {}
std::string PhysicsEngine::trouble() const { return physics_engine_missing(); }
std::vector<EngineContact> PhysicsEngine::contacts() const { return {}; }

}  // namespace wlx::cli

#endif
