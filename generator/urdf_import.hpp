// Reading a URDF robot description (liburdfdom) into plain data: the links with their inertials,
// the joints with their origins and axes, in tree order, every one with its line in the file.
// model_file_urdf.cpp turns this, with the small YAML file that says what URDF cannot (the base's
// inputs, wheels, closures, limbs, dynamics), into the same Model a model file gives.
//
// The subset read: joints of type revolute, continuous, prismatic and fixed; <origin xyz rpy>;
// <axis>; <limit> (lower, upper, effort, velocity); link <inertial> (mass, origin with rpy, the six
// inertia values) and the first <collision> cylinder or sphere (a wheel's radius). Visuals, other
// collisions, dynamics, materials, transmissions and gazebo tags are read past. Anything that changes
// the kinematics and wlx cannot represent (mimic joints, floating and planar joints, xacro that was
// not expanded) is an error that says so: `file:line: element: reason`.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace wlx::codegen {

using Matrix3Rows = std::array<double, 9>;  // row-major 3x3

// A rigid transform: x_parent = rotation * x_child + translation.
struct RigidPose {
  std::array<double, 3> translation{0, 0, 0};
  Matrix3Rows rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};
};

struct UrdfInertial {
  double mass = 0;
  std::array<double, 3> com{0, 0, 0};  // in the link's axes
  Matrix3Rows inertia{};               // about the centre of mass, in the link's axes
};

// The first <collision> cylinder or sphere of a link, in the link's axes: what a wheel's rolling
// radius and the offset of its rolling plane along the axle are read from.
struct UrdfRoundShape {
  bool cylinder = true;                   // else a sphere
  double radius = 0;                      // m
  std::array<double, 3> center{0, 0, 0};  // the shape's centre (its <origin xyz>)
  std::array<double, 3> axis{0, 0, 1};    // a cylinder's axis (z of its <origin rpy>)
  int line = 0;                           // of its <collision>
};

struct UrdfLink {
  std::string name;
  int line = 0;
  std::optional<UrdfInertial> inertial;
  std::optional<UrdfRoundShape> round_shape;
  int parent_joint = -1;  // index into UrdfRobot::joints; -1 for the root
};

struct UrdfJoint {
  enum class Type { Revolute, Continuous, Prismatic, Fixed };
  std::string name;
  int line = 0;
  Type type = Type::Fixed;
  std::string parent, child;  // link names
  RigidPose origin;           // the joint frame in the parent link's frame
  std::array<double, 3> axis{1, 0, 0};  // unit, in the joint frame (moving joints)
  // <limit>: the joint's range (revolute and prismatic joints whose lower and upper differ: URDF's
  // defaults for absent attributes are 0 and 0, which would lock the joint, so a range of zero
  // width counts as none), the largest effort (N m or N) and speed (rad/s or m/s); absent: none.
  std::optional<double> lower, upper, effort, velocity;
  int limit_line = 0;
};

struct UrdfRobot {
  std::string file;  // as messages name it
  std::string name;
  std::vector<UrdfLink> links;    // the root first, then depth first, children in the file's order
  std::vector<UrdfJoint> joints;  // the same order: joints[links[k].parent_joint].child == links[k].name
  int link_index(const std::string& name) const;   // -1 if absent
  int joint_index(const std::string& name) const;  // -1 if absent
};

// False when wlx-gen was built without liburdfdom.
bool urdf_import_available();

// Reads and checks the URDF at `path`; messages call it `shown_name`. Throws ModelFileError.
UrdfRobot read_urdf(const std::string& path, const std::string& shown_name);
// The same for a URDF's text (the fuzz target's way in).
UrdfRobot read_urdf_text(const std::string& text, const std::string& shown_name);

}  // namespace wlx::codegen
