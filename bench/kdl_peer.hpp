// Orocos KDL as a peer: the model's open tree (every frame of interest, the bodies' inertias,
// gravity) built as a KDL::Tree from the generated tables and the generated forward kinematics
// alone, for the benchmarks (wlx_bench) and for the test that an independent library computes what
// the generated functions compute (tests/bench/test_kdl_peer.cpp, for every built-in model).
//
// Nothing here names a coordinate, frame or body of a model. What the generated tables give:
// each frame's parent (gen::kFrameParent), the frames' and bodies' poses (gen::kinematics,
// gen::bodies) and the bodies' mass parameters (gen::kBodyMass). What they do not give, each
// frame's chain of elementary transforms and its joints' axes, is recovered from the generated FK:
//   1. the joints of a frame's chain: the coordinates that move the frame relative to its parent;
//   2. each joint's screw (a revolute axis and a point on it, or a prismatic direction) in the
//      parent's axes: with every other coordinate at zero, T_rel(q_j = t) T_rel(0)^-1 = exp(xi_j t)
//      exactly (a finite motion, no differentiation);
//   3. their order along the chain: i precedes j when exp(xi_i a) exp(xi_j b) T_rel(0) reproduces
//      T_rel(a e_i + b e_j) and the reverse product does not; screws that commute may go in either
//      order (the product of exponentials is the same).
// The chain is then T_rel(q) = exp(xi_1 q_1) ... exp(xi_k q_k) T_rel(0), one KDL segment per
// factor. A body belongs to the first frame in which its CoM and orientation stay fixed.
// Whatever the derivation assumes (a coordinate moves one frame only, with unit rate about or along
// one axis) is checked, and a model that breaks it throws std::runtime_error saying what is missing.
#pragma once

#include "open_tree.hpp"

#include <wlx/gen/all.hpp>
#include <wlx/model_namespace.hpp>

#include <Eigen/Dense>
#include <kdl/chain.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/rigidbodyinertia.hpp>
#include <kdl/segment.hpp>
#include <kdl/tree.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

// Debian's KDL is built for plain x86-64 (Eigen aligned to 16 bytes); with AVX (-march=native)
// Eigen would align to 32 here and KDL's library would free our matrices with the other allocator
// (a crash in the first Jacobian). CMakeLists.txt then defines EIGEN_MAX_ALIGN_BYTES=16.
#if EIGEN_MAX_ALIGN_BYTES > 16
#error "KDL needs Eigen's 16-byte alignment here: compile with -DEIGEN_MAX_ALIGN_BYTES=16"
#endif

WLX_MODEL_NAMESPACE_BEGIN
namespace kdl_peer {

using Transform = Eigen::Isometry3d;

// The root segment of the tree (the model's ground frame K0).
inline const std::string kRootName = "K0";
inline std::string frame_name(int f) { return std::string(gen::kFrameNames[static_cast<std::size_t>(f)]); }
inline std::string body_com_name(int b) { return std::string(gen::kBodyNames[static_cast<std::size_t>(b)]) + "_com"; }

inline KDL::Vector to_kdl(const Eigen::Vector3d& v) { return KDL::Vector(v.x(), v.y(), v.z()); }
inline KDL::Rotation to_kdl(const Eigen::Matrix3d& R) {
  return KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2));
}
inline KDL::Frame to_kdl(const Transform& T) { return KDL::Frame(to_kdl(Eigen::Matrix3d(T.linear())), to_kdl(Eigen::Vector3d(T.translation()))); }

// Every frame's pose in K0 from the generated FK.
inline std::vector<Transform> frame_poses(const gen::Params& p, const gen::Coordinates& s) {
  gen::FramePositions positions;
  gen::FrameRotations rotations;
  gen::kinematics(s, p, {.positions = &positions, .rotations = &rotations});
  std::vector<Transform> T(gen::kFrameCount, Transform::Identity());
  for (int f = 0; f < gen::kFrameCount; ++f) {
    T[static_cast<std::size_t>(f)].linear() = rotations[static_cast<std::size_t>(f)];
    T[static_cast<std::size_t>(f)].translation() = positions.col(f);
  }
  return T;
}

// Frame f relative to its parent (K0 for -1).
inline Transform relative_pose(const std::vector<Transform>& T, int f) {
  const int parent = gen::kFrameParent[static_cast<std::size_t>(f)];
  const Transform& own = T[static_cast<std::size_t>(f)];
  return parent < 0 ? own : Transform(T[static_cast<std::size_t>(parent)].inverse() * own);
}

// One joint of a frame's chain: the screw of coordinate `coordinate` in the parent's axes at zero.
struct Screw {
  int coordinate = -1;
  bool revolute = true;
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();   // unit
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // on the axis (revolute), perpendicular to it
  // exp(xi t): rotation by t about the axis through point, or translation by t along the axis.
  Transform motion(double t) const {
    Transform M = Transform::Identity();
    if (revolute) {
      M.linear() = Eigen::AngleAxisd(t, axis).toRotationMatrix();
      M.translation() = point - M.linear() * point;
    } else {
      M.translation() = t * axis;
    }
    return M;
  }
};

struct FrameChain {
  std::vector<Screw> joints;  // in chain order
  Transform at_zero = Transform::Identity();  // T_rel with every coordinate zero
};

inline double max_difference(const Transform& a, const Transform& b) {
  return std::max((a.linear() - b.linear()).cwiseAbs().maxCoeff(), (a.translation() - b.translation()).cwiseAbs().maxCoeff());
}

// The wheel whose derived contact frame f is (a wheel on a hub: wlx-gen places it at the rim point
// nearest the ground, level, so it is no rigid link of the tree), or -1.
inline int wheel_of_contact(int f) {
  for (std::size_t w = 0; w < gen::kWheels.size(); ++w)
    if (gen::kWheels[w].hub_frame >= 0 && gen::kWheels[w].contact_frame == f) return static_cast<int>(w);
  return -1;
}

// A derived contact frame from its hub's pose and, optionally, the hub's 6 x n Jacobian (rows
// v, omega): written here from the definition (docs/model-format.md, "Wheels"), not from the
// generator. With a the axle in K0, sigma = |(a_x, a_y)|, n = (a_x, a_y, 0) / sigma (lateral),
// t = (n_y, -n_x, 0) (forward), u = (-a_z n_x, -a_z n_y, sigma): c = h - r u, axes (t, n, e_z).
struct ContactFromHub {
  Eigen::Vector3d position;
  Eigen::Matrix3d rotation;
  Eigen::Matrix<double, 3, Eigen::Dynamic> jacobian;  // dc/dq, the columns of the hub's Jacobian
};
inline ContactFromHub contact_from_hub(const gen::Params& p, int w, const Eigen::Vector3d& hub_position,
                                       const Eigen::Matrix3d& hub_rotation,
                                       const Eigen::Matrix<double, 6, Eigen::Dynamic>* hub_jacobian = nullptr) {
  const gen::WheelInfo& wheel = gen::kWheels[static_cast<std::size_t>(w)];
  const double r = p.*wheel.radius;
  const Eigen::Vector3d a = hub_rotation.col(wheel.axle_axis);
  const double sigma = std::hypot(a.x(), a.y());
  const Eigen::Vector3d n(a.x() / sigma, a.y() / sigma, 0);
  ContactFromHub out;
  out.position = hub_position - r * Eigen::Vector3d(-a.z() * n.x(), -a.z() * n.y(), sigma);
  out.rotation.col(0) = Eigen::Vector3d(n.y(), -n.x(), 0);
  out.rotation.col(1) = n;
  out.rotation.col(2) = Eigen::Vector3d::UnitZ();
  if (hub_jacobian != nullptr) {
    const auto& J = *hub_jacobian;
    out.jacobian.resize(3, J.cols());
    for (Eigen::Index c = 0; c < J.cols(); ++c) {
      // a' = omega_c x a; u' from u(a) by the chain rule, written out: with s = sigma,
      // s' = (a_x a_x' + a_y a_y') / s and (a_z a_i / s)' = (a_z' a_i + a_z a_i') / s - a_z a_i s' / s^2.
      const Eigen::Vector3d da = Eigen::Vector3d(J.col(c).tail<3>()).cross(a);
      const double ds = (a.x() * da.x() + a.y() * da.y()) / sigma;
      Eigen::Vector3d du;
      for (int i = 0; i < 2; ++i) du(i) = -((da.z() * a(i) + a.z() * da(i)) / sigma - a.z() * a(i) * ds / (sigma * sigma));
      du.z() = ds;
      out.jacobian.col(c) = J.col(c).head<3>() - r * du;
    }
  }
  return out;
}

// The structure recovered from the generated functions (geometry at the given parameters).
struct DerivedStructure {
  std::array<FrameChain, gen::kFrameCount> chains;
  std::array<int, gen::kBodyCount> body_frame{};
  std::array<Transform, gen::kBodyCount> body_in_frame{};  // CoM position and body axes in its frame
};

inline DerivedStructure derive_structure(const gen::Params& p) {
  // The finite motions are exact, so only rounding separates "moves" from "does not move";
  // 1e-9 is far above the ~1e-15 rounding and far below any real offset or angle.
  constexpr double kMoves = 1e-9;
  constexpr double kProbe = 1.0;  // the finite motion's coordinate value (rad or m)
  DerivedStructure out;
  const gen::Coordinates zero = gen::Coordinates::Zero();
  const std::vector<Transform> T0 = frame_poses(p, zero);
  std::array<int, gen::kCoordinateCount> owner;
  owner.fill(-1);
  for (int j = 0; j < gen::kCoordinateCount; ++j) {
    gen::Coordinates s = zero;
    s(j) = kProbe;
    const std::vector<Transform> T = frame_poses(p, s);
    for (int f = 0; f < gen::kFrameCount; ++f) {
      if (wheel_of_contact(f) >= 0) continue;  // derived from its hub, not a link
      const Transform rel0 = relative_pose(T0, f), rel = relative_pose(T, f);
      if (max_difference(rel, rel0) <= kMoves) continue;
      if (owner[static_cast<std::size_t>(j)] >= 0)
        throw std::runtime_error("kdl_peer: coordinate " + std::string(gen::kCoordinateNames[static_cast<std::size_t>(j)]) +
                                 " moves two frames relative to their parents; the generated tables would need each frame's chain");
      owner[static_cast<std::size_t>(j)] = f;
      Screw xi;
      xi.coordinate = j;
      const Transform M = rel * rel0.inverse();  // exp(xi * kProbe)
      const Eigen::Matrix3d R = M.linear();
      if ((R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= kMoves) {
        xi.revolute = false;
        xi.axis = M.translation() / kProbe;
      } else {
        const Eigen::AngleAxisd aa(R);
        xi.axis = aa.axis();
        if (std::abs(aa.angle() - kProbe) > kMoves)
          throw std::runtime_error("kdl_peer: coordinate " + std::string(gen::kCoordinateNames[static_cast<std::size_t>(j)]) +
                                   " does not rotate its frame by its own value");
        // M.translation() = (I - R) point with point perpendicular to the axis: the minimum-norm solution.
        xi.point = (Eigen::Matrix3d::Identity() - R).completeOrthogonalDecomposition().solve(Eigen::Vector3d(M.translation()));
        if ((M.translation() - (xi.point - R * xi.point)).cwiseAbs().maxCoeff() > kMoves)
          throw std::runtime_error("kdl_peer: coordinate " + std::string(gen::kCoordinateNames[static_cast<std::size_t>(j)]) +
                                   " moves its frame along its rotation axis (a screw joint)");
      }
      if (std::abs(xi.axis.norm() - 1) > kMoves)
        throw std::runtime_error("kdl_peer: coordinate " + std::string(gen::kCoordinateNames[static_cast<std::size_t>(j)]) +
                                 " moves its frame at a rate other than 1");
      out.chains[static_cast<std::size_t>(f)].joints.push_back(xi);
    }
  }
  // The order along each chain: a topological order of "must precede" (non-commuting pairs).
  for (int f = 0; f < gen::kFrameCount; ++f) {
    FrameChain& chain = out.chains[static_cast<std::size_t>(f)];
    chain.at_zero = relative_pose(T0, f);
    const std::size_t n = chain.joints.size();
    std::vector<std::vector<bool>> before(n, std::vector<bool>(n, false));
    std::vector<int> pending(n, 0);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = i + 1; k < n; ++k) {
        const double a = 0.7, b = -1.3;  // generic values: no accidental commuting
        gen::Coordinates s = zero;
        s(chain.joints[i].coordinate) = a;
        s(chain.joints[k].coordinate) = b;
        const Transform actual = relative_pose(frame_poses(p, s), f);
        const Transform ik = chain.joints[i].motion(a) * chain.joints[k].motion(b) * chain.at_zero;
        const Transform ki = chain.joints[k].motion(b) * chain.joints[i].motion(a) * chain.at_zero;
        const bool i_first = max_difference(ik, actual) <= kMoves, k_first = max_difference(ki, actual) <= kMoves;
        if (!i_first && !k_first)
          throw std::runtime_error("kdl_peer: frame " + frame_name(f) + " is not a product of its joints' screws");
        if (i_first && !k_first) before[i][k] = true, ++pending[k];
        if (k_first && !i_first) before[k][i] = true, ++pending[i];
      }
    std::vector<Screw> ordered;
    std::vector<bool> placed(n, false);
    while (ordered.size() < n) {
      std::size_t next = n;
      for (std::size_t i = 0; i < n && next == n; ++i)
        if (!placed[i] && pending[i] == 0) next = i;
      if (next == n) throw std::runtime_error("kdl_peer: frame " + frame_name(f) + "'s joints have no consistent order");
      placed[next] = true;
      ordered.push_back(chain.joints[next]);
      for (std::size_t k = 0; k < n; ++k)
        if (before[next][k]) --pending[k];
    }
    chain.joints = ordered;
  }
  // Each body's frame: the first in which its CoM and axes stay where they are, over a few poses.
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<double> value(-1.5, 1.5);
  std::array<std::vector<Transform>, 3> frames;
  std::array<std::array<Transform, gen::kBodyCount>, 3> bodies;
  for (std::size_t trial = 0; trial < frames.size(); ++trial) {
    const gen::Coordinates s = gen::Coordinates::NullaryExpr([&] { return value(rng); });
    frames[trial] = frame_poses(p, s);
    gen::BodyVectors com;
    gen::BodyRotations rotations;
    gen::bodies(s, zero, p, {.com = &com, .rotations = &rotations});
    for (int b = 0; b < gen::kBodyCount; ++b) {
      Transform& B = bodies[trial][static_cast<std::size_t>(b)];
      B.setIdentity();
      B.linear() = rotations[static_cast<std::size_t>(b)];
      B.translation() = com.col(b);
    }
  }
  for (int b = 0; b < gen::kBodyCount; ++b) {
    int found = -1;
    for (int f = 0; f < gen::kFrameCount && found < 0; ++f) {
      if (wheel_of_contact(f) >= 0) continue;
      const auto in_frame = [&](std::size_t trial) {
        return Transform(frames[trial][static_cast<std::size_t>(f)].inverse() * bodies[trial][static_cast<std::size_t>(b)]);
      };
      bool fixed = true;
      for (std::size_t trial = 1; trial < frames.size(); ++trial) fixed = fixed && max_difference(in_frame(trial), in_frame(0)) <= kMoves;
      if (fixed) {
        found = f;
        out.body_in_frame[static_cast<std::size_t>(b)] = in_frame(0);
      }
    }
    if (found < 0)
      throw std::runtime_error("kdl_peer: body " + std::string(gen::kBodyNames[static_cast<std::size_t>(b)]) +
                               " is fixed in no frame of interest; the generated tables would need its frame");
    out.body_frame[static_cast<std::size_t>(b)] = found;
  }
  return out;
}

// The model's open tree in KDL, and which coordinate each KDL joint is.
struct PeerTree {
  KDL::Tree tree{kRootName};
  std::vector<int> coordinate_of_joint;  // KDL q_nr -> index into s
  std::vector<int> end_frames;           // frames that are no frame's parent (leaves)
  KDL::Vector gravity;

  // s (and its rates) -> the tree's joint array.
  KDL::JntArray joints(const gen::Coordinates& s) const {
    KDL::JntArray q(static_cast<unsigned>(coordinate_of_joint.size()));
    for (std::size_t i = 0; i < coordinate_of_joint.size(); ++i) q(static_cast<unsigned>(i)) = s(coordinate_of_joint[i]);
    return q;
  }
};

inline PeerTree build_tree(const gen::Params& p) {
  const DerivedStructure d = derive_structure(p);
  PeerTree out;
  // Inertias attach to their frame's last segment (whose tip is the frame).
  std::array<KDL::RigidBodyInertia, gen::kFrameCount> inertia;
  for (int b = 0; b < gen::kBodyCount; ++b) {
    const auto& info = gen::kBodyMass[static_cast<std::size_t>(b)];
    const Transform& X = d.body_in_frame[static_cast<std::size_t>(b)];
    const Eigen::Matrix3d I = X.linear() * Eigen::Vector3d(p.*info.inertia[0], p.*info.inertia[1], p.*info.inertia[2]).asDiagonal() *
                              X.linear().transpose();
    const KDL::RotationalInertia Ic(I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2));
    inertia[static_cast<std::size_t>(d.body_frame[static_cast<std::size_t>(b)])] =
        inertia[static_cast<std::size_t>(d.body_frame[static_cast<std::size_t>(b)])] +
        KDL::RigidBodyInertia(p.*info.mass, to_kdl(Eigen::Vector3d(X.translation())), Ic);
  }
  std::vector<bool> added(gen::kFrameCount, false);
  for (int round = 0; round < gen::kFrameCount; ++round)
    for (int f = 0; f < gen::kFrameCount; ++f) {
      const int parent = gen::kFrameParent[static_cast<std::size_t>(f)];
      if (added[static_cast<std::size_t>(f)] || (parent >= 0 && !added[static_cast<std::size_t>(parent)])) continue;
      if (wheel_of_contact(f) >= 0) {  // computed from its hub (contact_from_hub), no segment
        added[static_cast<std::size_t>(f)] = true;
        continue;
      }
      const FrameChain& chain = d.chains[static_cast<std::size_t>(f)];
      std::string hook = parent < 0 ? kRootName : frame_name(parent);
      // exp(xi q) = Trans(point) Rot(axis, q) Trans(-point): KDL's RotAxis joint is
      // Trans(origin) Rot(axis, q), followed by the segment's tip Trans(-point); a TransAxis joint
      // is Trans(axis q). KDL's Segment takes the tip's pose at q = 0 (joint included): the
      // identity, and T_rel(0) for the chain's last segment.
      for (std::size_t k = 0; k < chain.joints.size(); ++k) {
        const Screw& xi = chain.joints[k];
        const std::string joint = std::string(gen::kCoordinateNames[static_cast<std::size_t>(xi.coordinate)]);
        const bool last = k + 1 == chain.joints.size();
        const KDL::Frame tip = last ? to_kdl(chain.at_zero) : KDL::Frame::Identity();
        const KDL::Joint kj = xi.revolute ? KDL::Joint(joint, to_kdl(xi.point), to_kdl(xi.axis), KDL::Joint::RotAxis)
                                          : KDL::Joint(joint, KDL::Vector::Zero(), to_kdl(xi.axis), KDL::Joint::TransAxis);
        const std::string name = last ? frame_name(f) : frame_name(f) + "/" + joint;
        out.tree.addSegment(KDL::Segment(name, kj, tip, last ? inertia[static_cast<std::size_t>(f)] : KDL::RigidBodyInertia::Zero()), hook);
        out.coordinate_of_joint.push_back(xi.coordinate);
        hook = name;
      }
      if (chain.joints.empty())
        out.tree.addSegment(KDL::Segment(frame_name(f), KDL::Joint(KDL::Joint::Fixed), to_kdl(chain.at_zero), inertia[static_cast<std::size_t>(f)]),
                            hook);
      added[static_cast<std::size_t>(f)] = true;
    }
  // A fixed segment at each body's CoM (massless: the inertia is on the frame), for its Jacobian.
  for (int b = 0; b < gen::kBodyCount; ++b)
    out.tree.addSegment(KDL::Segment(body_com_name(b), KDL::Joint(KDL::Joint::Fixed),
                                     KDL::Frame(to_kdl(Eigen::Vector3d(d.body_in_frame[static_cast<std::size_t>(b)].translation())))),
                        frame_name(d.body_frame[static_cast<std::size_t>(b)]));
  // KDL numbers the joints in the order segments were added; check that against the tree.
  for (const auto& [name, element] : out.tree.getSegments()) {
    const KDL::Joint& j = GetTreeElementSegment(element).getJoint();
    if (j.getType() == KDL::Joint::Fixed) continue;
    if (gen::kCoordinateNames[static_cast<std::size_t>(out.coordinate_of_joint.at(GetTreeElementQNr(element)))] != j.getName())
      throw std::runtime_error("kdl_peer: KDL numbered the joints in another order than they were added");
  }
  for (int f = 0; f < gen::kFrameCount; ++f)
    if (wheel_of_contact(f) < 0) {  // a leaf: no frame of the tree hangs from it (a hub's contact frame is not in the tree)
      bool leaf = true;
      for (int c = 0; c < gen::kFrameCount; ++c)
        leaf = leaf && !(gen::kFrameParent[static_cast<std::size_t>(c)] == f && wheel_of_contact(c) < 0);
      if (leaf) out.end_frames.push_back(f);
    }
  out.gravity = KDL::Vector(0, 0, -(p.*gen::kGravity));
  return out;
}

// A chain from K0 to `end` with only the joints in `free_joints` (coordinates) left free: every
// other joint is frozen at its value in s (how a limb's IK sees the tree: cabin pose and the
// limb's own inputs given).
inline KDL::Chain frozen_chain(const PeerTree& peer, int end, const std::vector<int>& free_joints, const gen::Coordinates& s) {
  KDL::Chain full, out;
  if (!peer.tree.getChain(kRootName, frame_name(end), full)) throw std::runtime_error("kdl_peer: no chain to " + frame_name(end));
  for (const KDL::Segment& seg : full.segments) {
    const KDL::Joint& j = seg.getJoint();
    if (j.getType() == KDL::Joint::Fixed) {
      out.addSegment(seg);
      continue;
    }
    const auto name = std::find(gen::kCoordinateNames.begin(), gen::kCoordinateNames.end(), j.getName());
    const int coordinate = static_cast<int>(name - gen::kCoordinateNames.begin());
    if (std::find(free_joints.begin(), free_joints.end(), coordinate) != free_joints.end()) out.addSegment(seg);
    else out.addSegment(KDL::Segment(seg.getName(), KDL::Joint(KDL::Joint::Fixed), seg.pose(s(coordinate)), seg.getInertia()));
  }
  return out;
}

// Open-tree inverse dynamics from the generated body kinematics (open_tree.hpp), which KDL's
// TreeIdSolver_RNE computes on the tree.
using open_tree::OpenTreeWorkspace;
using open_tree::open_tree_inverse_dynamics;

}  // namespace kdl_peer
WLX_MODEL_NAMESPACE_END
