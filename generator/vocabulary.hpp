// The modelling vocabulary of wlx-gen (thesis chapter 2): 3-vectors and rotation matrices over
// GiNaC expressions, coordinates, and frames that move with the mechanism.
//
// A Frame carries, besides its pose in K0, its angular velocity, the velocity of its origin and
// the acceleration "bias" terms (the accelerations obtained with all coordinate accelerations set
// to zero), plus the list of joints that move it. Jacobians then follow geometrically
// (a_k x (p - o_k) for a revolute joint, a_k for a prismatic one) and convective terms
// Jdot*s' are the propagated bias accelerations: both reuse the forward-kinematics
// subexpressions instead of differentiating them again.
#pragma once

#include <ginac/ginac.h>

#include <array>
#include <string>
#include <vector>

namespace wlx::codegen {

using GiNaC::ex;

struct Vec3 {
  std::array<ex, 3> e{0, 0, 0};
  Vec3() = default;
  Vec3(ex x, ex y, ex z) : e{std::move(x), std::move(y), std::move(z)} {}
  ex& operator[](int i) { return e[static_cast<std::size_t>(i)]; }
  const ex& operator[](int i) const { return e[static_cast<std::size_t>(i)]; }
};

Vec3 operator+(const Vec3& a, const Vec3& b);
Vec3 operator-(const Vec3& a, const Vec3& b);
Vec3 operator*(const ex& s, const Vec3& a);
ex dot(const Vec3& a, const Vec3& b);
Vec3 cross(const Vec3& a, const Vec3& b);

struct Mat3 {
  std::array<ex, 9> e{0, 0, 0, 0, 0, 0, 0, 0, 0};  // row-major
  ex& operator()(int r, int c) { return e[static_cast<std::size_t>(3 * r + c)]; }
  const ex& operator()(int r, int c) const { return e[static_cast<std::size_t>(3 * r + c)]; }
  Vec3 col(int c) const { return {(*this)(0, c), (*this)(1, c), (*this)(2, c)}; }
  static Mat3 identity();
};

Mat3 operator*(const Mat3& a, const Mat3& b);
Vec3 operator*(const Mat3& a, const Vec3& v);

enum class Axis { X = 0, Y = 1, Z = 2 };
inline const char* axis_name(Axis a) { return a == Axis::X ? "x" : a == Axis::Y ? "y" : "z"; }
Vec3 unit(Axis axis);
// Elementary rotation, right-handed: Ry(a)*(1,0,0) = (cos a, 0, -sin a).
Mat3 rot(Axis axis, const ex& angle);
// R_axis(sign q) written with cos(q) and sign sin(q): GiNaC keeps sin(-q) and cos(-q) as they are,
// and a step about a negative axis would then need its own sine and cosine, outside the batched
// pass that every generated function computes for its angles.
Mat3 signed_rot(Axis axis, int sign, const ex& q);

// One generalized coordinate of the model: a position symbol and its rate symbol.
struct Coordinate {
  std::string name;
  int index = -1;  // position in the coordinate vector s
  GiNaC::realsymbol q;
  GiNaC::realsymbol qdot;
  std::string unit;  // "m" or "rad"
  std::string meaning;
};

// A named model parameter (geometry or mass), with its default from the model file.
struct Parameter {
  std::string name;
  double default_value = 0;
  std::string unit;
  std::string meaning;
  GiNaC::realsymbol symbol;
};

struct JointRecord {
  int coordinate = -1;
  bool revolute = true;
  Vec3 axis;    // unit joint axis in K0
  Vec3 origin;  // a point on the axis, in K0
  // The same joint in local terms, for recursions in the joints' own frames: the frame just after
  // it (moved by its coordinate) in the frame just after the joint before it in the chain (K0 for
  // the first): orientation and origin; and its axis in that frame, sign * unit(local_axis).
  Mat3 placement_R = Mat3::identity();
  Vec3 placement_r;
  Axis local_axis = Axis::X;
  int sign = 1;
};

class Frame {
 public:
  Mat3 R = Mat3::identity();  // orientation in K0
  Vec3 r;                     // origin in K0
  Vec3 omega;                 // angular velocity in K0 (in terms of coordinate rates)
  Vec3 v;                     // origin velocity in K0
  Vec3 alpha_bias;            // angular acceleration with all coordinate accelerations zero
  Vec3 a_bias;                // origin acceleration with all coordinate accelerations zero
  std::vector<JointRecord> joints;  // every joint between K0 and this frame
  // This frame in the frame just after the last of `joints` (K0 when there is none).
  Mat3 local_R = Mat3::identity();
  Vec3 local_r;
  // The origin's velocity Jacobian, one column per coordinate, for a point that is not fixed in the
  // chain (a wheel's contact point slides round the rim); empty for a rigidly attached frame, whose
  // columns follow from `joints`.
  std::vector<Vec3> linear_columns;

  static Frame ground() { return {}; }
  // A rigid offset, given in this frame's coordinates.
  Frame translated(const Vec3& local_offset) const;
  // A revolute joint about this frame's `axis` (its negative for sign -1), angle = coordinate.
  Frame rotated(Axis axis, const Coordinate& c, int sign = 1) const;
  // A prismatic joint along this frame's `axis` (its negative for sign -1), displacement = coordinate.
  Frame slid(Axis axis, const Coordinate& c, int sign = 1) const;
  // A fixed rotation about this frame's `axis` by an angle that depends on parameters only.
  Frame turned(Axis axis, const ex& angle) const;
};

// The contact frame of a wheel of radius `radius` on `hub` (the wheel's centre, not spinning) that
// turns about the hub's `axle`: origin at the rim point nearest the ground, c = h - r u with a the
// axle in K0 and u = (e_z - a_z a) / |e_z - a_z a| the upward direction in the wheel's plane; axes
// x = forward t = (a x e_z) / |a x e_z|, y = lateral n = e_z x t, z = e_z (level by construction).
// The point slides round the rim as the hub tilts, so its velocity Jacobian (one column per
// coordinate of `coordinates`) is carried explicitly; omega is the heading's rate about e_z.
// Undefined (division by zero) when the axle is vertical.
// `offset` moves the rolling plane along the axle (c = h + offset a - r u): a wheel whose rim is
// not centred on the hub frame's origin.
Frame wheel_contact_frame(const Frame& hub, Axis axle, const ex& radius, const ex& offset, const std::vector<Coordinate>& coordinates);

// Jacobian columns of the frame origin's velocity, one per coordinate (n in all).
std::vector<Vec3> linear_jacobian(const Frame& f, int n);
// Jacobian columns of the frame's angular velocity.
std::vector<Vec3> angular_jacobian(const Frame& f, int n);
// d(e . u)/ds for a unit vector u attached to frame f (fixed in it) and a constant vector e.
std::vector<ex> attached_direction_gradient(const Frame& f, const Vec3& u, const Vec3& e, int n);
// (d/dt d(e.u)/ds) s' for the same u and e.
ex attached_direction_convective(const Frame& f, const Vec3& u, const Vec3& e);

}  // namespace wlx::codegen
