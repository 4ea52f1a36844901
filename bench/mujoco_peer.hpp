// MuJoCo as a peer (Debian's libmujoco-dev, 2.2.2): a model exported by `wlx export mjcf`
// (cli/shell/mjcf_export.hpp) loaded into MuJoCo, and wlx's coordinates mapped onto MuJoCo's, for
// the check (tests/bench/test_mujoco_peer.cpp) and the benchmarks (bench/bench_any_model.cpp).
//
// Each hinge and slide joint is the coordinate of its name. A floating base is MuJoCo's free
// joint: qpos = (x, y, z, quaternion of R = R_a1(q1) R_a2(q2) R_a3(q3)), qvel = (world velocity,
// body-frame angular velocity) = G(s) s'. A wheel's spin (no coordinate of wlx's) is held at 0.
#pragma once

#include <wlx/gen/all.hpp>
#include <wlx/model_namespace.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

WLX_MODEL_NAMESPACE_BEGIN
namespace mujoco_peer {

// MuJoCo's model of an MJCF text (written to a temporary file: 2.2.2 loads XML from files).
struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
inline std::unique_ptr<mjModel, MjModelDeleter> load(const std::string& xml) {
  char path[] = "/tmp/wlx-mjcf-XXXXXX";
  const int fd = mkstemp(path);
  if (fd < 0) throw std::runtime_error("cannot create a temporary file for MuJoCo's MJCF");
  const bool written = write(fd, xml.data(), xml.size()) == static_cast<ssize_t>(xml.size());
  close(fd);
  if (!written) throw std::runtime_error(std::string("cannot write ") + path);
  char error[1000] = "";
  mjModel* m = mj_loadXML(path, nullptr, error, sizeof error);
  std::remove(path);
  if (m == nullptr) throw std::runtime_error(std::string("MuJoCo refuses the export: ") + error);
  return std::unique_ptr<mjModel, MjModelDeleter>(m);
}

inline int coordinate_index(const std::string& name) {
  for (int k = 0; k < gen::kCoordinateCount; ++k)
    if (gen::kCoordinateNames[static_cast<std::size_t>(k)] == name) return k;
  return -1;
}

// The floating base: the free joint's frame and its six coordinates with the rotation axes.
struct FreeBase {
  std::string frame;
  std::array<int, 3> position{}, angle{};
  std::array<int, 3> axis{};
};

// G (MuJoCo's dofs x wlx's coordinates), its time derivative times s', and qpos, for a state.
struct Mapping {
  Eigen::MatrixXd G;
  Eigen::VectorXd Gdot_sdot, qpos;
};

inline Eigen::Matrix3d axis_rotation(int axis, double angle) { return Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)).toRotationMatrix(); }
inline Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d H;
  H << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return H;
}

inline Mapping map_state(const mjModel* m, const std::vector<FreeBase>& bases, const gen::Coordinates& s, const gen::Coordinates& sdot) {
  Mapping out;
  out.G = Eigen::MatrixXd::Zero(m->nv, gen::kCoordinateCount);
  out.Gdot_sdot = Eigen::VectorXd::Zero(m->nv);
  out.qpos = Eigen::VectorXd::Zero(m->nq);
  for (int j = 0; j < m->njnt; ++j) {
    const int qa = m->jnt_qposadr[j], va = m->jnt_dofadr[j];
    const std::string name = mj_id2name(m, mjOBJ_JOINT, j);
    if (m->jnt_type[j] == mjJNT_FREE) {
      const auto base = std::find_if(bases.begin(), bases.end(), [&](const FreeBase& b) { return b.frame == name; });
      if (base == bases.end()) throw std::runtime_error("free joint " + name + " is no frame's floating base");
      for (int i = 0; i < 3; ++i) {
        out.qpos(qa + i) = s(base->position[static_cast<std::size_t>(i)]);
        out.G(va + i, base->position[static_cast<std::size_t>(i)]) = 1;
      }
      std::array<Eigen::Matrix3d, 3> R;
      for (int i = 0; i < 3; ++i) R[static_cast<std::size_t>(i)] = axis_rotation(base->axis[static_cast<std::size_t>(i)], s(base->angle[static_cast<std::size_t>(i)]));
      const Eigen::Quaterniond q(R[0] * R[1] * R[2]);
      out.qpos.segment<4>(qa + 3) << q.w(), q.x(), q.y(), q.z();
      // omega_body = sum_i B_i e_i q_i' with B_i = (R_{i+1} ... R_3)^T, built from B_3 = I by
      // B_i = B_{i+1} R_{i+1}^T; and B_i' likewise, R_k^T' = -[e_k q_k']x R_k^T.
      Eigen::Matrix3d B = Eigen::Matrix3d::Identity(), Bdot = Eigen::Matrix3d::Zero();
      for (int i = 2; i >= 0; --i) {
        if (i < 2) {
          const std::size_t k = static_cast<std::size_t>(i + 1);
          const Eigen::Matrix3d Rt = R[k].transpose();
          const Eigen::Matrix3d Rt_dot = -hat(Eigen::Vector3d::Unit(base->axis[k]) * sdot(base->angle[k])) * Rt;
          Bdot = Bdot * Rt + B * Rt_dot;
          B = B * Rt;
        }
        const Eigen::Vector3d e = Eigen::Vector3d::Unit(base->axis[static_cast<std::size_t>(i)]);
        const int c = base->angle[static_cast<std::size_t>(i)];
        out.G.block<3, 1>(va + 3, c) = B * e;
        out.Gdot_sdot.segment<3>(va + 3) += Bdot * e * sdot(c);
      }
      continue;
    }
    const int c = coordinate_index(name);
    if (c < 0) continue;  // a wheel's spin: held at 0
    out.qpos(qa) = s(c);
    out.G(va, c) = 1;
  }
  return out;
}

// The floating bases (frames MuJoCo moves by a free joint), from the description's chains.
inline std::vector<FreeBase> free_bases(const std::string& description) {
  const nlohmann::json desc = nlohmann::json::parse(description);
  std::vector<FreeBase> bases;
  for (const auto& f : desc["frames"]) {
    if (!f.contains("chain") || f["parent"] != "K0" || f["chain"].size() != 6) continue;
    FreeBase b;
    b.frame = f["name"];
    bool slides = true;
    for (int i = 0; i < 3; ++i) {
      const auto& step = f["chain"][static_cast<std::size_t>(i)];
      slides = slides && step.contains("prismatic");
      if (slides) b.position[static_cast<std::size_t>(i)] = coordinate_index(step["coordinate"]);
    }
    for (int i = 0; i < 3 && slides; ++i) {
      const auto& step = f["chain"][static_cast<std::size_t>(i + 3)];
      if (!step.contains("revolute")) slides = false;
      else {
        b.angle[static_cast<std::size_t>(i)] = coordinate_index(step["coordinate"]);
        b.axis[static_cast<std::size_t>(i)] = std::string(step["revolute"]) == "x" ? 0 : std::string(step["revolute"]) == "y" ? 1 : 2;
      }
    }
    if (slides) bases.push_back(b);
  }

  return bases;
}

}  // namespace mujoco_peer
WLX_MODEL_NAMESPACE_END
