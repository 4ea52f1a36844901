// MuJoCo as an independent check of `wlx export mjcf`: the model's description exported as MJCF
// (cli/shell/mjcf_export.hpp), loaded by MuJoCo 2.2.2, computes at random states what the generated
// functions compute: every frame's pose (mj_kinematics), the machine's centre of mass, the total
// mass, the open tree's mass matrix (mj_fullM) and its inverse dynamics with gravity (mj_rne,
// contacts off). Compiled once per built-in model.
//
// Coordinates: each hinge and slide joint is the coordinate of its name. A floating base is
// MuJoCo's free joint: qpos = (x, y, z, quaternion of R = R_a1(q1) R_a2(q2) R_a3(q3)), qvel =
// (world velocity, body-frame angular velocity) = G(s) s'. So M_wlx = G^T M_mj G, and
// Q_wlx(s, s', s'') = G^T rne(q, G s', G s'' + G' s'). A wheel's spin (no coordinate of wlx's:
// its rate follows from rolling) is held at 0.
//
// Tolerance: 1e-10 relative to the largest entry of the compared quantity. Both sides are exact
// formulas in double precision (MuJoCo's recursive CRBA and RNE, wlx's Kane's sums) and differ by
// rounding, some 1e-15 relative; MuJoCo stores each full inertia as principal moments and a
// quaternion (an eigen-decomposition, good to about 1e-15 relative), and the export's placeholders
// (a moving frame without mass gets 1e-13 of the machine's, MuJoCo refusing a massless moving body)
// change entries by at most that much. 1e-10 leaves margin for cancellation, and a wrong offset,
// axis, mass or inertia shows far above it: the second test changes one inertia by 1% and sees it
// (5e-5 relative on the wheeled quadruped's mass matrix, 5e-3 on the excavator's).
#include "../support/random.hpp"
#include "open_tree.hpp"
#include "mjcf_export.hpp"

#include <doctest/doctest.h>
#include <fmt/format.h>
#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>
#include <wlx/gen/all.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

using namespace wlx;

namespace {

constexpr int kStates = 1000;
constexpr double kRelativeTolerance = 1e-10;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  REQUIRE_MESSAGE(in.good(), "cannot read " << path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// MuJoCo's model of an MJCF text (written to a temporary file: 2.2.2 loads XML from files).
struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
std::unique_ptr<mjModel, MjModelDeleter> load(const std::string& xml) {
  char path[] = "/tmp/wlx-mjcf-XXXXXX";
  const int fd = mkstemp(path);
  REQUIRE(fd >= 0);
  REQUIRE(write(fd, xml.data(), xml.size()) == static_cast<ssize_t>(xml.size()));
  close(fd);
  char error[1000] = "";
  mjModel* m = mj_loadXML(path, nullptr, error, sizeof error);
  std::remove(path);
  REQUIRE_MESSAGE(m != nullptr, "MuJoCo refuses the export: " << error);
  return std::unique_ptr<mjModel, MjModelDeleter>(m);
}

int coordinate_index(const std::string& name) {
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

Eigen::Matrix3d axis_rotation(int axis, double angle) { return Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)).toRotationMatrix(); }
Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d H;
  H << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return H;
}

Mapping map_state(const mjModel* m, const std::vector<FreeBase>& bases, const gen::Coordinates& s, const gen::Coordinates& sdot) {
  Mapping out;
  out.G = Eigen::MatrixXd::Zero(m->nv, gen::kCoordinateCount);
  out.Gdot_sdot = Eigen::VectorXd::Zero(m->nv);
  out.qpos = Eigen::VectorXd::Zero(m->nq);
  for (int j = 0; j < m->njnt; ++j) {
    const int qa = m->jnt_qposadr[j], va = m->jnt_dofadr[j];
    const std::string name = mj_id2name(m, mjOBJ_JOINT, j);
    if (m->jnt_type[j] == mjJNT_FREE) {
      const auto base = std::find_if(bases.begin(), bases.end(), [&](const FreeBase& b) { return b.frame == name; });
      REQUIRE_MESSAGE(base != bases.end(), "free joint " << name << " is no frame's floating base");
      for (int i = 0; i < 3; ++i) {
        out.qpos(qa + i) = s(base->position[static_cast<std::size_t>(i)]);
        out.G(va + i, base->position[static_cast<std::size_t>(i)]) = 1;
      }
      std::array<Eigen::Matrix3d, 3> R;
      for (int i = 0; i < 3; ++i) R[static_cast<std::size_t>(i)] = axis_rotation(base->axis[static_cast<std::size_t>(i)], s(base->angle[static_cast<std::size_t>(i)]));
      const Eigen::Quaterniond q(R[0] * R[1] * R[2]);
      out.qpos.segment<4>(qa + 3) << q.w(), q.x(), q.y(), q.z();
      // omega_body = sum_i B_i e_i q_i', B_i = (R_{i+1} ... R_3)^T; B_i' from R_k' = R_k [e_k q_k']x.
      for (int i = 0; i < 3; ++i) {
        Eigen::Matrix3d B = Eigen::Matrix3d::Identity(), Bdot = Eigen::Matrix3d::Zero();
        // B_i = R_3^T ... R_{i+1}^T, written as a product from R_3^T down.
        std::vector<Eigen::Matrix3d> factors;  // R_3^T, R_2^T, ..., R_{i+1}^T
        std::vector<Eigen::Matrix3d> derivatives;
        for (int k = 2; k > i; --k) {
          const Eigen::Vector3d w = Eigen::Vector3d::Unit(base->axis[static_cast<std::size_t>(k)]) * sdot(base->angle[static_cast<std::size_t>(k)]);
          factors.push_back(R[static_cast<std::size_t>(k)].transpose());
          derivatives.push_back(-hat(w) * R[static_cast<std::size_t>(k)].transpose());
        }
        for (const auto& f : factors) B = B * f;
        for (std::size_t d = 0; d < factors.size(); ++d) {
          Eigen::Matrix3d term = Eigen::Matrix3d::Identity();
          for (std::size_t f = 0; f < factors.size(); ++f) term = term * (f == d ? derivatives[f] : factors[f]);
          Bdot += term;
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

struct Worst {
  double mass = 0, positions = 0, rotations = 0, com = 0, mass_matrix = 0, torques = 0;
};

Worst compare(const std::string& xml, const std::string& description, int states) {
  const auto model = load(xml);
  mjModel* m = model.get();
  m->opt.disableflags |= mjDSBL_CONTACT;  // the open tree: no contact
  const std::unique_ptr<mjData, MjDataDeleter> data(mj_makeData(m));
  mjData* d = data.get();
  const gen::Params p{};
  Worst worst;

  double mass = 0;
  for (int b = 0; b < gen::kBodyCount; ++b) mass += p.*gen::kBodyMass[static_cast<std::size_t>(b)].mass;
  worst.mass = std::abs(mj_getTotalmass(m) - mass) / mass;

  // The floating bases, from the description's chains.
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

  std::mt19937_64 rng(20261206);
  open_tree::OpenTreeWorkspace w;
  gen::FramePositions positions;
  gen::FrameRotations rotations;
  gen::BodyVectors coms;
  Eigen::MatrixXd M_mj(m->nv, m->nv);
  Eigen::VectorXd rne(m->nv);
  for (int n = 0; n < states; ++n) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng), sddot = test::random_rates(rng);
    const Mapping map = map_state(m, bases, s, sdot);
    for (int i = 0; i < m->nq; ++i) d->qpos[i] = map.qpos(i);
    const Eigen::VectorXd qvel = map.G * sdot, qacc = map.G * sddot + map.Gdot_sdot;
    for (int i = 0; i < m->nv; ++i) {
      d->qvel[i] = qvel(i);
      d->qacc[i] = qacc(i);
    }
    mj_fwdPosition(m, d);
    mj_fwdVelocity(m, d);

    // Frames: every body MuJoCo has that is a frame of wlx's.
    gen::kinematics(s, p, {.positions = &positions, .rotations = &rotations});
    double scale = 1e-300, position_diff = 0, rotation_diff = 0;
    for (int f = 0; f < gen::kFrameCount; ++f) {
      const int b = mj_name2id(m, mjOBJ_BODY, std::string(gen::kFrameNames[static_cast<std::size_t>(f)]).c_str());
      if (b < 0) continue;  // a derived contact frame: no body
      const Eigen::Vector3d x(d->xpos[3 * b], d->xpos[3 * b + 1], d->xpos[3 * b + 2]);
      const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(d->xmat + 9 * b);
      scale = std::max(scale, positions.col(f).cwiseAbs().maxCoeff());
      position_diff = std::max(position_diff, (x - positions.col(f)).cwiseAbs().maxCoeff());
      rotation_diff = std::max(rotation_diff, (R - rotations[static_cast<std::size_t>(f)]).cwiseAbs().maxCoeff());
    }
    worst.positions = std::max(worst.positions, position_diff / scale);
    worst.rotations = std::max(worst.rotations, rotation_diff);

    // The machine's centre of mass (MuJoCo's subtree of the world).
    gen::bodies(s, sdot, p, {.com = &coms}, false);
    Eigen::Vector3d com = Eigen::Vector3d::Zero();
    for (int b = 0; b < gen::kBodyCount; ++b) com += p.*gen::kBodyMass[static_cast<std::size_t>(b)].mass * coms.col(b);
    com /= mass;
    const Eigen::Vector3d com_mj(d->subtree_com[0], d->subtree_com[1], d->subtree_com[2]);
    worst.com = std::max(worst.com, (com_mj - com).cwiseAbs().maxCoeff() / std::max(1e-300, com.cwiseAbs().maxCoeff() + 1));

    // The mass matrix: wlx's column by column, Q(s, 0, e_c) - Q(s, 0, 0).
    mj_fullM(m, M_mj.data(), d->qM);  // symmetric: row- or column-major alike
    gen::Coordinates zero = gen::Coordinates::Zero(), Q0, Qc;
    open_tree::open_tree_inverse_dynamics(p, s, zero, zero, w, Q0);
    Eigen::MatrixXd M_wlx(gen::kCoordinateCount, gen::kCoordinateCount);
    for (int c = 0; c < gen::kCoordinateCount; ++c) {
      gen::Coordinates e = gen::Coordinates::Unit(c);
      open_tree::open_tree_inverse_dynamics(p, s, zero, e, w, Qc);
      M_wlx.col(c) = Qc - Q0;
    }
    const Eigen::MatrixXd M_mapped = map.G.transpose() * M_mj * map.G;
    worst.mass_matrix = std::max(worst.mass_matrix, (M_mapped - M_wlx).cwiseAbs().maxCoeff() / M_wlx.cwiseAbs().maxCoeff());

    // Open-tree inverse dynamics with gravity.
    mj_rne(m, d, 1, rne.data());
    gen::Coordinates Q;
    open_tree::open_tree_inverse_dynamics(p, s, sdot, sddot, w, Q);
    const Eigen::VectorXd Q_mapped = map.G.transpose() * rne;
    worst.torques = std::max(worst.torques, (Q_mapped - Q).cwiseAbs().maxCoeff() / std::max(1e-300, Q.cwiseAbs().maxCoeff()));
  }
  return worst;
}

std::string description_text() { return read_text(WLX_DESCRIPTION_FILE); }

}  // namespace

TEST_CASE("MuJoCo on the exported MJCF: frames, centre of mass, total mass, mass matrix and open-tree torques agree at 1000 random states") {
  const std::string description = description_text();
  const cli::MjcfExport mjcf = cli::mjcf_of_description(description);
  const Worst worst = compare(mjcf.xml, description, kStates);
  MESSAGE(gen::kModelName << ": mass " << worst.mass << ", frame positions " << worst.positions << ", rotations " << worst.rotations
                          << ", centre of mass " << worst.com << ", mass matrix " << worst.mass_matrix << ", torques " << worst.torques);
  CHECK(worst.mass <= 1e-12);
  CHECK(worst.positions <= kRelativeTolerance);
  CHECK(worst.rotations <= kRelativeTolerance);
  CHECK(worst.com <= kRelativeTolerance);
  CHECK(worst.mass_matrix <= kRelativeTolerance);
  CHECK(worst.torques <= kRelativeTolerance);
}

TEST_CASE("The MuJoCo check sees one inertia changed by 1% in the exported file") {
  const std::string description = description_text();
  std::string xml = cli::mjcf_of_description(description).xml;
  // The first body's full inertia: Ixx one percent larger.
  const std::string key = "fullinertia=\"";
  const std::size_t at = xml.find(key);
  REQUIRE(at != std::string::npos);
  const std::size_t start = at + key.size(), end = xml.find(' ', start);
  const double ixx = std::stod(xml.substr(start, end - start));
  xml.replace(start, end - start, fmt::format("{:.17g}", ixx * 1.01));
  const Worst worst = compare(xml, description, 50);
  MESSAGE("with Ixx of the first body 1% larger: mass matrix " << worst.mass_matrix << ", torques " << worst.torques);
  // Far outside the tolerance the first test holds (1e-10): the check fails on such a file.
  CHECK(worst.mass_matrix > 1e3 * kRelativeTolerance);
  CHECK(worst.torques > 1e3 * kRelativeTolerance);
}
