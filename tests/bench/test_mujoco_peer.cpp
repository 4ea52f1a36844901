// MuJoCo as an independent check of `wlx export mjcf`: the model's description exported as MJCF
// (cli/shell/mjcf_export.hpp), loaded by MuJoCo 2.2.2, computes at random states what the generated
// functions compute: every frame's pose (mj_kinematics), the machine's centre of mass, the total
// mass, the open tree's mass matrix (mj_fullM) and its inverse dynamics with gravity (mj_rne,
// contacts off). Compiled once per built-in model.
//
// Coordinates as the physics engine maps them (cli/shell/physics_engine.hpp), qvel = G(s) s': so M_wlx = G^T M_mj G, and
// Q_wlx(s, s', s'') = G^T rne(q, G s', G s'' + G' s').
//
// Tolerance: 1e-10 relative to the largest entry of the compared quantity. Both sides are exact
// formulas in double precision (MuJoCo's recursive CRBA and RNE, wlx's generated passes) and differ by
// rounding, some 1e-15 relative; MuJoCo stores each full inertia as principal moments and a
// quaternion (an eigen-decomposition, good to about 1e-15 relative), and the export's placeholders
// (a moving frame without mass gets 1e-13 of the machine's, MuJoCo refusing a massless moving body)
// change entries by at most that much. 1e-10 leaves margin for cancellation, and a wrong offset,
// axis, mass or inertia shows far above it: the second test changes one inertia by 1% and sees it
// (5e-5 relative on the wheeled quadruped's mass matrix, 5e-3 on the excavator's).
#include "../helpers/random.hpp"
#include "mjcf_export.hpp"
#include "mujoco_model.hpp"
#include "open_tree.hpp"
#include "physics_engine.hpp"

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
#include <numbers>
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

struct Worst {
  double mass = 0, positions = 0, rotations = 0, com = 0, mass_matrix = 0, torques = 0;
};

Worst compare(const std::string& xml, const std::string& description, int states) {
  const cli::MjModelPtr model = cli::load_mjcf(xml);
  mjModel* m = model.get();
  m->opt.disableflags |= mjDSBL_CONTACT;  // the open tree: no contact
  const cli::MjDataPtr data(mj_makeData(m));
  mjData* d = data.get();
  const gen::Params p{};
  Worst worst;

  double mass = 0;
  for (int b = 0; b < gen::kBodyCount; ++b) mass += p.*gen::kBodyMass[static_cast<std::size_t>(b)].mass;
  worst.mass = std::abs(mj_getTotalmass(m) - mass) / mass;

  // The mapping of the description's machine (the same joints and dofs as `xml`, whose inertias
  // the negative test changes).
  const cli::PhysicsEngine engine(description, std::vector<std::string>(gen::kCoordinateNames.begin(), gen::kCoordinateNames.end()));
  std::mt19937_64 rng(20261206);
  open_tree::OpenTreeWorkspace w;
  gen::FramePositions positions;
  gen::FrameRotations rotations;
  gen::BodyVectors coms;
  Eigen::MatrixXd M_mj(m->nv, m->nv);
  Eigen::VectorXd rne(m->nv);
  for (int n = 0; n < states; ++n) {
    const gen::Coordinates s = test::random_coordinates(rng), sdot = test::random_rates(rng), sddot = test::random_rates(rng);
    const cli::EngineMapping map = engine.mapping(s, sdot);
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

TEST_CASE("The MuJoCo check sees the heaviest body's inertia changed by 1% in the exported file") {
  const std::string description = description_text();
  std::string xml = cli::mjcf_of_description(description).xml;
  // The heaviest body's full inertia (not a placeholder's): Ixx one percent larger.
  std::size_t heaviest = std::string::npos;
  double heaviest_mass = 0;
  for (std::size_t at = xml.find("<inertial "); at != std::string::npos; at = xml.find("<inertial ", at + 1)) {
    const std::size_t m = xml.find("mass=\"", at) + 6;
    const double mass = std::stod(xml.substr(m, xml.find('"', m) - m));
    if (mass > heaviest_mass) heaviest_mass = mass, heaviest = at;
  }
  REQUIRE(heaviest != std::string::npos);
  const std::string key = "fullinertia=\"";
  const std::size_t start = xml.find(key, heaviest) + key.size(), end = xml.find(' ', start);
  const double ixx = std::stod(xml.substr(start, end - start));
  xml.replace(start, end - start, fmt::format("{:.17g}", ixx * 1.01));
  const Worst worst = compare(xml, description, 50);
  MESSAGE("with Ixx of the heaviest body 1% larger: mass matrix " << worst.mass_matrix << ", torques " << worst.torques);
  // Far outside the tolerance the first test holds (1e-10): the check fails on such a file.
  CHECK(worst.mass_matrix > 1e3 * kRelativeTolerance);
  CHECK(worst.torques > 1e3 * kRelativeTolerance);
}

// The physics engine's way back (cli/shell/physics_engine.hpp), which the report's "In a physics
// engine" reads MuJoCo's state by: a state set into MuJoCo reads back as the same coordinates and
// rates where the tree has them, to rounding, the floating base's angles whatever their axes'
// order and near the angles the caller had (no jump of 2 pi); the other entries are left alone.
namespace {

struct RoundTrip {
  double s = 0, sdot = 0;
  int tree = 0;
};

RoundTrip engine_round_trip(const std::string& description, int states) {
  cli::PhysicsEngine engine(description, std::vector<std::string>(gen::kCoordinateNames.begin(), gen::kCoordinateNames.end()));
  std::mt19937_64 rng(20261207);
  std::uniform_real_distribution<double> middle(-1.4, 1.4);  // the base's second angle: R's Euler angles are unique within +-pi/2
  constexpr double kSentinel = 1234.5;
  double worst_s = 0, worst_sdot = 0;
  int tree = 0;
  for (int n = 0; n < states; ++n) {
    gen::Coordinates s = test::random_coordinates(rng);
    const gen::Coordinates sdot = test::random_rates(rng);
    for (const cli::EngineFreeBase& b : engine.free_bases()) s(b.angle[1]) = middle(rng);
    engine.set_state(s, sdot);
    const cli::EngineMapping map = engine.mapping(s, sdot);
    // What the caller had: the sentinel off the tree; on it, each base angle 2 pi away (plus a
    // little), which the reading must follow.
    gen::Coordinates read = gen::Coordinates::Constant(kSentinel), read_rates = gen::Coordinates::Constant(kSentinel);
    gen::Coordinates expected = s;
    for (int k = 0; k < gen::kCoordinateCount; ++k)
      if (!map.G.col(k).isZero()) read(k) = s(k);
    for (const cli::EngineFreeBase& b : engine.free_bases())
      for (int a : b.angle) {
        read(a) = s(a) + 2 * std::numbers::pi + 0.1;
        expected(a) = s(a) + 2 * std::numbers::pi;
      }
    engine.read_state(read, read_rates);
    tree = 0;
    for (int k = 0; k < gen::kCoordinateCount; ++k) {
      CAPTURE(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
      if (map.G.col(k).isZero()) {  // no coordinate of MuJoCo's: left alone
        CHECK(read(k) == kSentinel);
        CHECK(read_rates(k) == kSentinel);
        continue;
      }
      ++tree;
      worst_s = std::max(worst_s, std::abs(read(k) - expected(k)));
      worst_sdot = std::max(worst_sdot, std::abs(read_rates(k) - sdot(k)));
    }
  }
  return {worst_s, worst_sdot, tree};
}

}  // namespace

TEST_CASE("The physics engine reads a state it was given back as the model's coordinates and rates") {
  const RoundTrip r = engine_round_trip(description_text(), 200);
  MESSAGE(gen::kModelName << ": " << r.tree << " coordinates of the tree; worst |s - s_read| " << r.s << ", |s' - s'_read| " << r.sdot);
  CHECK(r.tree > 0);
  // Rounding: quaternions and their angles back (a few ulp of pi), least squares on G (rates of 2).
  CHECK(r.s <= 1e-12);
  CHECK(r.sdot <= 1e-11);
}

// The same for a floating base whose three rotations come in each of the six orders of x, y, z
// (the model's base with its chain's axes permuted): the angles of R = R_a R_b R_c read back for
// every order, not only the models' own.
TEST_CASE("The physics engine reads a floating base's angles back for every order of its axes") {
  nlohmann::json d = nlohmann::json::parse(description_text());
  nlohmann::json* base = nullptr;
  for (auto& f : d["frames"])
    if (f.contains("chain") && f["parent"] == "K0" && f["chain"].size() == 6 && f["chain"][3].contains("revolute")) base = &f;
  if (base == nullptr) return;  // a fixed base: nothing to permute
  std::array<std::string, 3> axes{"x", "y", "z"};
  int orders = 0;
  do {
    for (std::size_t i = 0; i < 3; ++i) (*base)["chain"][3 + i]["revolute"] = axes[i];
    const RoundTrip r = engine_round_trip(d.dump(), 50);
    CAPTURE(axes[0] + axes[1] + axes[2]);
    CHECK(r.s <= 1e-12);
    CHECK(r.sdot <= 1e-11);
    ++orders;
  } while (std::next_permutation(axes.begin(), axes.end()));
  CHECK(orders == 6);
}
