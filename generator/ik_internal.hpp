// What the closed-form inverse kinematics' three parts share: the canonical chains (ik_chains.cpp),
// the patterns' planning (ik_patterns.cpp) and the printing of the planned solves (emit_ik.cpp).
// Internal to the generator.
#pragma once

#include "model.hpp"

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace wlx::codegen::ik {

using GiNaC::realsymbol;

// Why a limb matches no pattern (wlx-gen reports every pattern's reason).
struct Unsolvable {
  std::string reason;
};

// ---- chains (ik_chains.cpp) ---------------------------------------------------------------------

// Every step from K0 to the frame, parents first.
std::vector<ChainStep> full_chain(const Model& m, const std::string& frame);
Frame apply(const Model& m, const Frame& f, const ChainStep& st);
bool driven(const ChainStep& st);
// The patterns read joint steps as turns about +x, +y or +z; a chain with a negated joint
// (`ry: -q`) or a wheel's derived contact frame is not theirs.
void require_plain_chain(const Model& m, const std::string& frame, const std::vector<ChainStep>& chain, const char* pattern);

// A rotation whose angle is an expression, for reducing orientation chains.
struct Rot {
  Axis axis;
  ex angle;
};
// Adjacent rotations about the same axis add up; zero angles vanish (so a coupling q4 = -q5 between
// Rz(q5) Rz(q4) leaves nothing, and the rotations on both sides may then merge).
std::vector<Rot> merge(const std::vector<Rot>& seq);
Mat3 product(const std::vector<Rot>& seq);

// A rigid transform that depends on parameters only: T(offset), then the turns in order.
struct Rigid {
  Vec3 offset;
  std::vector<Rot> turns;
};

// A chain in the canonical form the patterns match on (ik_chains.cpp explains it).
struct CanonicalChain {
  std::vector<ChainStep> prefix;  // the steps before the first dependent joint, as written
  std::vector<ChainStep> joints;  // every joint step from the first dependent one on
  std::vector<Rigid> fixed;       // fixed[k] before joints[k]; fixed[joints.size()] after the last
};
CanonicalChain canonical_chain(const Model& m, const std::vector<ChainStep>& chain);
// The frame before the first dependent joint: the prefix and the fixed transform after it.
Frame base_frame(const Model& m, const CanonicalChain& c);
// The transform as the model file would write it, for messages.
std::string describe(const Rigid& r);

bool identically_zero(const ex& e);
bool identically_zero(const Vec3& v);
// e at the parameters' defaults (for messages and for telling "not identically" from "not at all").
double at_defaults(const Model& m, const ex& e);
Vec3 expanded(const Vec3& v);

// ---- planned solves (ik_patterns.cpp) -----------------------------------------------------------

// The generated code of one limb's solve: stages of named values (expressions of the inputs, the
// parameters and earlier stages' results) each followed by code calling a solver.
struct Stage {
  std::vector<std::pair<realsymbol, ex>> locals;
  std::string code;
  std::vector<std::string> defines;  // the variables its code computes (usable from the next stage on)
};

struct SolvedJoint {
  int coordinate;
  realsymbol q, c, s;  // value, cosine, sine in the generated code
};

struct Solve {
  std::string pattern;
  std::string summary;  // one line for wlx-gen's report
  std::vector<std::string> doc;
  int branches = 1;
  std::vector<std::string> bits;  // meaning of each branch bit
  std::vector<std::string> failures;  // message template of each failing stage (1-based in IkDiagnostics)
  std::vector<Stage> stages;
  std::vector<SolvedJoint> joints;
  std::vector<std::pair<int, ex>> coupled;  // joints fixed by a sum row: coordinate, value
};

SolvedJoint joint_symbols(const Model& m, int coordinate);
// An expression in the model's symbols, rewritten in the solve's results: sines and cosines of the
// solved joints by their computed values, the joints themselves by theirs, coupled joints by
// their expressions.
ex in_results(const Model& m, ex e, const Solve& solve);

// The planning tools the patterns share (ik_patterns.cpp).
// a cos q + b sin q + c = e, for e linear in cos q and sin q; throws Unsolvable otherwise.
struct Sinusoid {
  ex a, b, c;
};
Sinusoid sinusoid(const ex& e, const realsymbol& q, const std::string& what);
// |p + M R_axis(sign q) t|^2 = K + A cos q + B sin q (K in c), for p, t and M free of the joint's q.
Sinusoid distance_squared(const Vec3& p, const Mat3& M, const ChainStep& joint, const Vec3& t);
// The targets seen from `base` (from its origin, in its axes): the stage's locals ik_d0, ik_d1, ik_d2.
Vec3 targets_from(const Model& m, const Frame& base, const std::array<int, 3>& target, Stage& stage);
// A point row of a limb's three (x, y, z of one frame): its frame checked against the others' and
// its target put in `target`; throws Unsolvable naming `pattern` when it does not fit.
void add_point_row(const ClosureCondition& row, const std::string& pattern, std::string& frame, std::array<int, 3>& target);
// The wheel whose derived contact frame `frame` is, or nullptr for any other frame.
const NonholonomicWheel* wheel_of_contact(const Model& m, const std::string& frame);
// a and b parallel, identically or at the parameters' defaults (a geometry that moves no plane).
bool parallel_at_defaults(const Model& m, const Vec3& a, const Vec3& b);
// R^T v: v in the axes of a frame turned by R.
Vec3 in_axes(const Mat3& R, const Vec3& v);
// Code making sin and cos of the joint from those of theta = sign q that a solver computed.
std::string unsign(const ChainStep& j, const SolvedJoint& s);

// The steps a leg's patterns share (a hip that swings the plane of parallel joints through the
// target, then a planar two-link chain in it; ik_leg_steps.cpp).
// The code that solves K + A cos q + B sin q = |v|^2 for a joint, v the stage's ik_<v>0..2 (a
// distance fixes a knee): `bit` of the branch picks the root, `stage` is the failure's number.
std::string distance_solve_code(const std::string& v, int bit, int stage, const SolvedJoint& s);
// The hip from its plane's offset: alpha cos q1 + beta sin q1 = plane - first.c, with `first` the
// target's component along the turned normal (branch bit 0 picks the root); into `stage`.
void add_plane_offset_solve(Stage& stage, const Sinusoid& first, const ex& plane, const SolvedJoint& s1);
// The knee from the distance |w| of the point it moves from the second joint's origin (w, in the
// frame before the second joint, the stage's ik_w0..2): |p2 + R2 R_3(q3) p3|^2 = |w|^2 (bit 1).
Stage two_link_distance_stage(const Model& m, const Solve& solve, const Vec3& w, const Vec3& p2, const Mat3& R2,
                              const ChainStep& j3, const Vec3& p3, const SolvedJoint& s3);
// The second joint: the rotation about its axis that takes v = p2 + R2 R_3(q3) p3 onto w.
Stage two_link_rotation_stage(const Model& m, const Solve& solve, const Vec3& p2, const Mat3& R2, const ChainStep& j2,
                              const ChainStep& j3, const Vec3& p3, const SolvedJoint& s2);

// The patterns, in the order they are tried; each throws Unsolvable when the limb is not its.
Solve plan_point3(const Model& m, const Limb& limb);
Solve plan_wheel_leg(const Model& m, const Limb& limb);
Solve plan_lever(const Model& m, const Limb& limb);
Solve plan_steering_leg(const Model& m, const Limb& limb);  // ik_steering_leg.cpp

}  // namespace wlx::codegen::ik
