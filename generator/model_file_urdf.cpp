// A URDF written into the model file that reads it (`urdf:`): its links become frames and bodies,
// its moving joints dependent coordinates, its numbers parameters, for the parser to read as if
// the file had been written by hand.
#include "model_file_internal.hpp"

#include "urdf_import.hpp"

#include <Eigen/Eigenvalues>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>

namespace wlx::codegen::model_file_detail {

// What the file says about the URDF's joints, read before the sections are built: the names of
// its parameters and inputs (an input that names a URDF joint makes that joint an input), and
// the hubs of its wheels (a wheel's continuous joint is its spin, not a coordinate).
struct UrdfFileFacts {
  std::set<std::string> parameters, inputs;
  std::map<std::string, Item> hubs;
  std::set<std::string> hubs_with_radius;  // the wheels that give their radius themselves
};

namespace {

// Messages about the URDF's elements: they point at its lines (`urdf` as the user named it), and
// a name it cannot use gets the rename the model file (`model_file`) can give.
struct UrdfMessages {
  std::string urdf, model_file;

  [[noreturn]] void fail(int line, const std::string& element, const std::string& reason) const {
    throw ModelFileError(fmt::format("{}:{}: {}: {}", urdf, line, element, reason));
  }
  // `suffix` makes a name that is already an identifier (but taken or reserved) a new one.
  std::string rename_hint(const std::string& n, const std::string& suffix) const {
    std::string fixed;
    for (char c : n) fixed += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    if (fixed.empty() || std::isdigit(static_cast<unsigned char>(fixed[0])) || fixed[0] == '_') fixed = "n" + fixed;
    while (fixed.find("__") != std::string::npos) fixed.replace(fixed.find("__"), 2, "_");
    if (fixed == n) fixed += suffix;
    return fmt::format("rename it in the URDF, or in {}: `rename: {{\"{}\": {}}}`", model_file, excerpt(n), fixed);
  }
};

// ---- YAML nodes -------------------------------------------------------------------------------

// The shortest decimal within two units in the last place: an angle that went through
// urdfdom's quaternion (0.2 comes back as 0.20000000000000004) or a diagonalised moment reads
// as it was written; exact values are kept exactly.
std::string shortest_decimal(double x) {
  if (x == 0) return std::string("0");
  for (int digits = 1; digits < 17; ++digits) {
    const double y = std::stod(fmt::format("{:.{}g}", x, digits));
    if (std::abs(y - x) <= 4.5e-16 * std::abs(x)) return fmt::format("{}", y);
  }
  return fmt::format("{}", x);
}

YAML::Node chain_step(const char* op, const std::string& arg) {
  YAML::Node n(YAML::NodeType::Map);
  n[op] = arg;
  return n;
}

YAML::Node flow(YAML::Node n) {
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}

const char* const axis_letters[] = {"x", "y", "z"};

// The principal axis a unit vector lies along (-1 if none), and its sign.
int principal_axis(const std::array<double, 3>& a, int& sign) {
  for (int i = 0; i < 3; ++i)
    if (std::abs(std::abs(a[i]) - 1) < 1e-12 && std::abs(a[(i + 1) % 3]) < 1e-12 && std::abs(a[(i + 2) % 3]) < 1e-12) {
      sign = a[i] > 0 ? 1 : -1;
      return i;
    }
  return -1;
}

// Fixed turns rz, ry, rx (URDF's rpy: roll about x, pitch about y, yaw about z, fixed axes)
// for a rotation matrix; angles below 1e-12 rad are the rounding of a quaternion, left out.
// `argument` writes the angle (a number, or the name of a parameter it makes).
void append_turns(YAML::Node& chain, const Matrix3Rows& R, const std::function<std::string(const char*, double)>& argument) {
  double yaw, pitch, roll;
  const double s = std::clamp(-R[6], -1.0, 1.0);
  pitch = std::asin(s);
  if (std::abs(s) < 1 - 1e-12) {
    yaw = std::atan2(R[3], R[0]);
    roll = std::atan2(R[7], R[8]);
  } else {
    yaw = 0;
    roll = std::atan2(-R[5], R[4]);
  }
  for (const auto& [op, which, angle] : {std::tuple{"rz", "yaw", yaw}, std::tuple{"ry", "pitch", pitch}, std::tuple{"rx", "roll", roll}})
    if (std::abs(angle) > 1e-12) chain.push_back(flow(chain_step(op, argument(which, angle))));
}

// ---- the URDF's links and joints --------------------------------------------------------------

void apply_renames(const Item& rename, UrdfRobot& robot) {
  if (!rename.is_map()) rename.fail("must map URDF link or joint names to new names {old: new}");
  std::vector<std::string> names;
  for (const auto& l : robot.links) names.push_back(l.name);
  for (const auto& j : robot.joints) names.push_back(j.name);
  for (const auto& kv : rename.node()) {
    const std::string from = kv.first.Scalar();
    const Item to_item = rename.child(from);
    const std::string to = to_item.name();
    if (std::find(names.begin(), names.end(), from) == names.end())
      Item(rename.source(), kv.first, rename.path(), {}).fail(fmt::format("the URDF has no link or joint '{}'{}", excerpt(from), suggestion(from, names)));
    for (auto& l : robot.links)
      if (l.name == from) l.name = to;
    for (auto& j : robot.joints) {
      if (j.name == from) j.name = to;
      if (j.parent == from) j.parent = to;
      if (j.child == from) j.child = to;
    }
  }
}

std::map<std::string, int> link_indices(const UrdfRobot& robot) {
  std::map<std::string, int> link_of;  // name -> index
  for (std::size_t k = 0; k < robot.links.size(); ++k) link_of[robot.links[k].name] = static_cast<int>(k);
  return link_of;
}

// Wheels: their hubs are the child links of continuous joints. Returns those joints; `axles`
// gets each hub's axle.
std::set<int> wheel_joints(const UrdfRobot& robot, const std::map<std::string, int>& link_of, const std::map<std::string, Item>& hubs,
                           const UrdfMessages& messages, std::map<std::string, UrdfAxle>& axles) {
  std::set<int> joints;
  for (const auto& [hub, item] : hubs) {
    const auto l = link_of.find(hub);
    if (l == link_of.end()) continue;  // a frame of the file's own: checked with the wheels
    const int j = robot.links[static_cast<std::size_t>(l->second)].parent_joint;
    if (j < 0 || robot.joints[static_cast<std::size_t>(j)].type != UrdfJoint::Type::Continuous)
      item.fail(fmt::format("URDF link '{}' {}: a wheel's hub is the child link of the wheel's continuous joint", hub,
                            j < 0 ? "is the root link" : fmt::format("hangs on joint '{}', which is not continuous", robot.joints[static_cast<std::size_t>(j)].name)));
    const UrdfJoint& joint = robot.joints[static_cast<std::size_t>(j)];
    int sign = 1;
    const int axis = principal_axis(joint.axis, sign);
    if (axis < 0)
      messages.fail(joint.line, fmt::format("joint '{}' axis", joint.name),
                    "a wheel turns about an axis of its joint frame (x, y or z, either sign): turn the joint's origin (rpy) so "
                    "that the axle lies along one");
    joints.insert(j);
    axles[hub] = {static_cast<Axis>(axis), fmt::format("{}:{}", messages.urdf, joint.line), joint.name};
  }
  return joints;
}

// Names: C++ identifiers; joints (coordinates) share a namespace with the parameters.
void check_names(const UrdfRobot& robot, const std::set<int>& wheel_joints, const std::set<std::string>& file_parameters,
                 const UrdfMessages& messages) {
  for (const auto& l : robot.links) {
    if (!is_identifier(l.name) || l.name == "K0")
      messages.fail(l.line, fmt::format("link '{}'", excerpt(l.name)),
                    fmt::format("'{}' cannot name a frame (a C++ identifier, not K0): {}", excerpt(l.name), messages.rename_hint(l.name, "_link")));
  }
  for (std::size_t k = 0; k < robot.joints.size(); ++k) {
    const UrdfJoint& j = robot.joints[k];
    if (j.type == UrdfJoint::Type::Fixed || wheel_joints.count(static_cast<int>(k))) continue;
    const std::string element = fmt::format("joint '{}'", excerpt(j.name));
    if (!is_identifier(j.name))
      messages.fail(j.line, element, fmt::format("'{}' cannot name a coordinate (a C++ identifier): {}", excerpt(j.name), messages.rename_hint(j.name, "_joint")));
    if (const std::string why = reserved_reason(j.name); !why.empty())
      messages.fail(j.line, element, fmt::format("'{}' cannot name a coordinate: {}; {}", j.name, why, messages.rename_hint(j.name, "_joint")));
    if (file_parameters.count(j.name))
      messages.fail(j.line, element, fmt::format("'{}' is also the name of a parameter in {}: {}", j.name, messages.model_file, messages.rename_hint(j.name, "_joint")));
  }
}

// The joints' <limit>s, by their (renamed) names: the `limits` section reads them, and the file's
// own entries take precedence (limits()); a wheel's continuous joint gives its drive's effort.
std::map<std::string, UrdfLimit> joint_limits(const UrdfRobot& robot, const std::string& shown) {
  std::map<std::string, UrdfLimit> limits;
  for (const UrdfJoint& j : robot.joints)
    if (j.type != UrdfJoint::Type::Fixed && (j.lower || j.effort || j.velocity))
      limits[j.name] = {j.lower, j.upper, j.effort, j.velocity, fmt::format("{}:{}", shown, j.limit_line)};
  return limits;
}

// Rigid groups: a link and the links fixed to it (fixed joints collapse). Each moving joint's
// child (and the root) starts a group; its body carries the group's mass.
struct RigidGroups {
  std::vector<int> group;          // each link's group: the index of its root link
  std::vector<RigidPose> in_group;  // the link's pose in its group's root frame
};

RigidGroups rigid_groups(const UrdfRobot& robot, const std::map<std::string, int>& link_of) {
  const std::size_t n = robot.links.size();
  RigidGroups groups{std::vector<int>(n, -1), std::vector<RigidPose>(n)};
  for (std::size_t k = 0; k < n; ++k) {
    const int pj = robot.links[k].parent_joint;
    if (pj < 0 || robot.joints[static_cast<std::size_t>(pj)].type != UrdfJoint::Type::Fixed) {
      groups.group[k] = static_cast<int>(k);
      continue;
    }
    const UrdfJoint& j = robot.joints[static_cast<std::size_t>(pj)];
    const int parent = link_of.at(j.parent);  // earlier in the depth-first order
    groups.group[k] = groups.group[static_cast<std::size_t>(parent)];
    const RigidPose& p = groups.in_group[static_cast<std::size_t>(parent)];
    RigidPose& q = groups.in_group[k];
    for (int r = 0; r < 3; ++r) {
      q.translation[r] = p.translation[r];
      for (int c = 0; c < 3; ++c) {
        q.translation[r] += p.rotation[3 * r + c] * j.origin.translation[c];
        double sum = 0;
        for (int a = 0; a < 3; ++a) sum += p.rotation[3 * r + a] * j.origin.rotation[3 * a + c];
        q.rotation[3 * r + c] = sum;
      }
    }
  }
  return groups;
}

// ---- bodies -----------------------------------------------------------------------------------

// A rigid group's mass, its centre of mass and its inertia about it, in the group's root frame
// (the parallel-axis theorem moves every member's tensor to the group's centre of mass), and the
// names of the links fixed to the root.
struct GroupInertia {
  double mass = 0;
  Eigen::Vector3d com;
  Eigen::Matrix3d inertia;
  std::vector<std::string> members;
};

// The group of root link g; none when it has no mass.
std::optional<GroupInertia> group_inertia(const UrdfRobot& robot, const RigidGroups& groups, std::size_t g) {
  const std::size_t n = robot.links.size();
  const auto massive_member = [&](std::size_t k) {
    return groups.group[k] == static_cast<int>(g) && robot.links[k].inertial && robot.links[k].inertial->mass > 0;
  };
  GroupInertia out;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < n; ++k)
    if (massive_member(k)) {
      const auto& i = *robot.links[k].inertial;
      const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(groups.in_group[k].rotation.data());
      const Eigen::Vector3d c = Eigen::Vector3d(groups.in_group[k].translation.data()) + R * Eigen::Vector3d(i.com.data());
      out.mass += i.mass;
      moment += i.mass * c;
      if (k != g) out.members.push_back(robot.links[k].name);
    }
  if (!(out.mass > 0)) return std::nullopt;
  out.com = moment / out.mass;
  out.inertia = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < n; ++k)
    if (massive_member(k)) {
      const auto& i = *robot.links[k].inertial;
      const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(groups.in_group[k].rotation.data());
      const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(i.inertia.data());
      const Eigen::Vector3d d = Eigen::Vector3d(groups.in_group[k].translation.data()) + R * Eigen::Vector3d(i.com.data()) - out.com;
      out.inertia += R * J * R.transpose() + i.mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
    }
  return out;
}

// An inertia's principal moments and axes (the columns of `axes`, a proper rotation), by
// diagonalisation; `scale` is its largest diagonal moment, for the tolerances.
struct PrincipalAxes {
  Eigen::Vector3d moments;
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  double scale = 0;
};

PrincipalAxes principal_axes(const Eigen::Matrix3d& I) {
  PrincipalAxes out;
  out.scale = I.diagonal().cwiseAbs().maxCoeff();
  const double off = std::max({std::abs(I(0, 1)), std::abs(I(0, 2)), std::abs(I(1, 2))});
  out.moments = I.diagonal();
  Eigen::Matrix3d& V = out.axes;
  if (off > 1e-12 * out.scale) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(I);
    // The permutation and signs of the eigenvectors nearest the link's own axes, so that a
    // slightly turned inertial reads as small turns.
    const Eigen::Matrix3d E = solver.eigenvectors();
    const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    double best = -1;
    for (const auto& p : perms) {
      const double score = std::abs(E(0, p[0])) + std::abs(E(1, p[1])) + std::abs(E(2, p[2]));
      if (score > best) {
        best = score;
        for (int c = 0; c < 3; ++c) {
          V.col(c) = E.col(p[c]) * (E(c, p[c]) < 0 ? -1.0 : 1.0);
          out.moments[c] = solver.eigenvalues()[p[c]];
        }
      }
    }
    if (V.determinant() < 0) {  // a proper rotation: flip the axis that is least like its own
      int worst = 0;
      for (int c = 1; c < 3; ++c)
        if (std::abs(V(c, c)) < std::abs(V(worst, worst))) worst = c;
      V.col(worst) *= -1;
    }
  }
  return out;
}

// ---- the sections the URDF writes into --------------------------------------------------------

// The file's own parameters, frames and bodies (their nodes keep their places for messages),
// then what the URDF gives: its numbers as parameters, its links as frames and bodies, its
// moving joints as dependent coordinates.
class UrdfSections {
 public:
  UrdfSections(const Fields& f, const UrdfRobot& robot, const UrdfFileFacts& file, const UrdfMessages& messages)
      : robot_(robot), file_(file), messages_(messages) {
    if (auto list = f.optional("parameters"))
      for (const auto& e : list->node()) parameters_.push_back(e);
    if (auto list = f.optional("frames"))
      for (const auto& e : list->node()) frames_.push_back(e);
    if (auto list = f.optional("bodies"))
      for (const auto& e : list->node()) bodies_.push_back(e);
  }

  // `owner` is the link or joint whose number it is ("link", "base"), for the message.
  void add_parameter(int line, const char* kind_of_owner, const std::string& owner, const std::string& name, double value,
                     const char* kind, const char* unit, const std::string& meaning) {
    const auto fail = [&](const std::string& problem) {
      messages_.fail(line, fmt::format("{} '{}'", kind_of_owner, owner),
                     fmt::format("{}{}", problem, messages_.rename_hint(owner, std::string("_") + kind_of_owner)));
    };
    if (file_.parameters.count(name) || file_.inputs.count(name) || generated_parameters_.count(name) || robot_.joint_index(name) >= 0)
      fail(fmt::format("its parameter '{}' is already a name in the model: ", name));
    if (const std::string why = reserved_reason(name); !why.empty())
      fail(fmt::format("its parameter '{}' cannot be used as a name: {}; ", name, why));
    generated_parameters_.insert(name);
    YAML::Node p(YAML::NodeType::Map);
    p["name"] = name;
    p["value"] = shortest_decimal(value);
    p["unit"] = unit;
    p["kind"] = kind;
    p["meaning"] = meaning;
    parameters_.push_back(flow(p));
  }

  // A frame per link; the root link's chain is the file's `base`.
  void add_frames(const std::set<int>& wheel_joints, const std::optional<Item>& base) {
    for (const UrdfLink& l : robot_.links) {
      YAML::Node frame(YAML::NodeType::Map);
      frame["name"] = l.name;
      YAML::Node chain(YAML::NodeType::Sequence);
      if (l.parent_joint < 0) {
        frame["meaning"] = fmt::format("URDF root link {}", l.name);
        frame["parent"] = "K0";
        if (base) {
          const Fields bf(*base, {"chain"});
          chain = bf["chain"].node();  // the file's own steps, with their places
        }
      } else {
        const UrdfJoint& j = robot_.joints[static_cast<std::size_t>(l.parent_joint)];
        const bool wheel = wheel_joints.count(l.parent_joint) != 0;
        const bool moving = j.type != UrdfJoint::Type::Fixed && !wheel;
        frame["meaning"] = fmt::format("URDF link {} ({} joint {})", l.name,
                                       wheel ? "wheel hub, not spinning, of" : moving ? "after" : "fixed by", j.name);
        frame["parent"] = j.parent;
        add_origin(chain, j);
        if (moving) add_motion(chain, j);
      }
      frame["chain"] = flow(chain);
      frames_.push_back(frame);
    }
  }

  // A wheel without `radius` rolls on its hub link's collision cylinder (about the axle) or sphere:
  // parameters <hub>_radius and <hub>_offset (the centre's place along the axle, which moves the
  // rolling plane), which the wheel then takes (wheels()). Returns them by hub.
  std::map<std::string, UrdfWheelShape> add_wheel_shapes(const std::map<std::string, int>& link_of,
                                                         const std::map<std::string, UrdfAxle>& axles) {
    std::map<std::string, UrdfWheelShape> shapes;
    for (const auto& [hub, item] : file_.hubs) {
      const auto l = link_of.find(hub);
      if (l == link_of.end() || file_.hubs_with_radius.count(hub)) continue;
      const UrdfLink& link = robot_.links[static_cast<std::size_t>(l->second)];
      const UrdfAxle& axle = axles.at(hub);
      if (!link.round_shape)
        item.fail(fmt::format("the wheel on '{}' has no `radius`, and the URDF's link '{}' has no collision cylinder or sphere to "
                              "read one from (a mesh has none): give `radius: PARAMETER`",
                              hub, hub));
      const UrdfRoundShape& shape = *link.round_shape;
      const auto a = static_cast<std::size_t>(axle.axis);
      if (shape.cylinder && !(std::abs(shape.axis[a]) >= 1 - 1e-9))
        messages_.fail(shape.line, fmt::format("link '{}' collision", hub),
                       fmt::format("the cylinder's axis ({:.6g}, {:.6g}, {:.6g}) is not the wheel's axle ({} of the link): it gives no "
                                   "rolling radius; turn its <origin rpy>, or give the wheel a `radius`",
                                   shape.axis[0], shape.axis[1], shape.axis[2], "xyz"[a]));
      const std::string place = fmt::format("{}:{}", messages_.urdf, shape.line);
      const char* shape_kind = shape.cylinder ? "cylinder" : "sphere";
      add_parameter(shape.line, "link", hub, hub + "_radius", shape.radius, "length", "m",
                    fmt::format("rolling radius of the wheel on {} (its collision {}, {})", hub, shape_kind, place));
      add_parameter(shape.line, "link", hub, hub + "_offset", shape.center[a], "offset", "m",
                    fmt::format("the wheel's rolling plane along the axle {} of {} (its collision {}'s centre, {})", "xyz"[a], hub,
                                shape_kind, place));
      shapes[hub] = {hub + "_radius", hub + "_offset"};
    }
    return shapes;
  }

  // Bodies: each group's mass, centre of mass and inertia, its principal axes by diagonalisation.
  void add_bodies(const RigidGroups& groups) {
    for (std::size_t g = 0; g < robot_.links.size(); ++g) {
      if (groups.group[g] != static_cast<int>(g)) continue;
      const std::optional<GroupInertia> inertia = group_inertia(robot_, groups, g);
      if (inertia) add_body(robot_.links[g], *inertia, principal_axes(inertia->inertia));
    }
  }

  // The file with the URDF's sections in place of its `urdf`, `rename` and `base`.
  YAML::Node merged(const YAML::Node& root) const {
    YAML::Node merged(YAML::NodeType::Map);
    for (const char* key : {"model", "description", "repeat"})
      if (root[key].IsDefined()) merged[key] = root[key];
    merged["parameters"] = parameters_;
    YAML::Node coordinates(YAML::NodeType::Map);
    if (root["coordinates"].IsMap() && root["coordinates"]["inputs"].IsDefined()) coordinates["inputs"] = root["coordinates"]["inputs"];
    if (dependent_.size() > 0) coordinates["dependent"] = dependent_;
    merged["coordinates"] = coordinates;
    merged["frames"] = frames_;
    if (bodies_.size() > 0) merged["bodies"] = bodies_;
    for (const char* key : {"wheels", "closure", "limbs", "nonholonomic", "dynamics", "clearance", "contacts", "nominal",
                            "ik_sweeps", "limits"})
      if (root[key].IsDefined()) merged[key] = root[key];
    return merged;
  }

 private:
  // The joint's origin. Its numbers become parameters (kinds offset and angle), as a hand-written
  // model names its geometry: symbols keep GiNaC from distributing numbers over sums (about 13%
  // fewer operations), and the geometry stays adjustable at run time, or --bake-defaults.
  void add_origin(YAML::Node& chain, const UrdfJoint& j) {
    const auto& t = j.origin.translation;
    if (t[0] != 0 || t[1] != 0 || t[2] != 0) {
      YAML::Node v(YAML::NodeType::Sequence);
      for (int a = 0; a < 3; ++a) {
        if (t[a] == 0) {
          v.push_back("0");
          continue;
        }
        const std::string p = fmt::format("{}_{}", j.name, axis_letters[a]);
        add_parameter(j.line, "joint", j.name, p, t[a], "offset", "m",
                      fmt::format("origin of joint {}: {} in link {}", j.name, axis_letters[a], j.parent));
        v.push_back(p);
      }
      YAML::Node s(YAML::NodeType::Map);
      s["translate"] = flow(v);
      chain.push_back(flow(s));
    }
    append_turns(chain, j.origin.rotation, [&](const char* which, double angle) {
      const std::string p = fmt::format("{}_{}", j.name, which);
      add_parameter(j.line, "joint", j.name, p, angle, "angle", "rad", fmt::format("origin of joint {}: rpy {}", j.name, which));
      return p;
    });
  }

  // The moving joint's step, and its coordinate unless the file names it as an input.
  void add_motion(YAML::Node& chain, const UrdfJoint& j) {
    const char* kind = j.type == UrdfJoint::Type::Prismatic ? "t" : "r";
    int sign = 1;
    const int axis = principal_axis(j.axis, sign);
    const std::string q = (sign < 0 ? "-" : "") + j.name;
    if (axis >= 0) {
      chain.push_back(flow(chain_step(fmt::format("{}{}", kind, axis_letters[axis]).c_str(), q)));
    } else {
      // An oblique axis: turn z onto it, move about (along) z, turn back, so that the
      // child link keeps URDF's axes.
      const double theta = std::acos(std::clamp(j.axis[2], -1.0, 1.0));
      const double phi = std::atan2(j.axis[1], j.axis[0]);
      if (std::abs(phi) > 1e-12) chain.push_back(flow(chain_step("rz", shortest_decimal(phi))));
      chain.push_back(flow(chain_step("ry", shortest_decimal(theta))));
      chain.push_back(flow(chain_step(fmt::format("{}z", kind).c_str(), j.name)));
      chain.push_back(flow(chain_step("ry", shortest_decimal(-theta))));
      if (std::abs(phi) > 1e-12) chain.push_back(flow(chain_step("rz", shortest_decimal(-phi))));
    }
    if (!file_.inputs.count(j.name)) {
      YAML::Node c(YAML::NodeType::Map);
      c["name"] = j.name;
      c["unit"] = j.type == UrdfJoint::Type::Prismatic ? "m" : "rad";
      c["meaning"] = fmt::format("URDF {} joint {}", j.type == UrdfJoint::Type::Prismatic ? "prismatic" : "revolute", j.name);
      dependent_.push_back(flow(c));
    }
  }

  // The body of a rigid group, whose root link is `root_link`: its mass and principal moments
  // become parameters.
  void add_body(const UrdfLink& root_link, const GroupInertia& inertia, const PrincipalAxes& principal) {
    const std::string members_text = inertia.members.empty() ? "" : fmt::format(" (with {})", fmt::join(inertia.members, ", "));
    const std::string body_name = root_link.name;
    const Eigen::Vector3d& moments = principal.moments;
    if (moments.minCoeff() <= 1e-12 * std::max(principal.scale, 1e-300))
      messages_.fail(root_link.line, fmt::format("link '{}' inertial", root_link.name),
                     fmt::format("the principal moments of inertia{} are {}, {}, {} kg*m^2: wlx's bodies need every one positive "
                                 "(give a point mass a small inertia about each axis)",
                                 members_text, moments[0], moments[1], moments[2]));
    add_parameter(root_link.line, "link", root_link.name, "m_" + body_name, inertia.mass, "mass", "kg",
                  fmt::format("mass of URDF link {}{}", body_name, members_text));
    for (int a = 0; a < 3; ++a)
      add_parameter(root_link.line, "link", root_link.name, fmt::format("I{}_{}", a + 1, body_name), moments[a], "inertia", "kg*m^2",
                    fmt::format("principal moment {} of URDF link {}{}", a + 1, body_name, members_text));
    YAML::Node b(YAML::NodeType::Map);
    b["name"] = body_name;
    b["meaning"] = fmt::format("URDF link {}{}", body_name, members_text);
    b["frame"] = root_link.name;
    YAML::Node c(YAML::NodeType::Sequence);
    for (int a = 0; a < 3; ++a) c.push_back(shortest_decimal(std::abs(inertia.com[a]) < 1e-15 ? 0.0 : inertia.com[a]));
    b["com"] = flow(c);
    if (!principal.axes.isIdentity(0)) {
      Matrix3Rows Vr;
      for (int r = 0; r < 3; ++r)
        for (int cc = 0; cc < 3; ++cc) Vr[3 * r + cc] = principal.axes(r, cc);
      YAML::Node rotation(YAML::NodeType::Sequence);
      append_turns(rotation, Vr, [&](const char*, double angle) { return shortest_decimal(angle); });
      if (rotation.size() > 0) b["rotation"] = flow(rotation);
    }
    b["mass"] = "m_" + body_name;
    YAML::Node inertia_node(YAML::NodeType::Sequence);
    for (int a = 0; a < 3; ++a) inertia_node.push_back(fmt::format("I{}_{}", a + 1, body_name));
    b["inertia"] = flow(inertia_node);
    bodies_.push_back(flow(b));
  }

  const UrdfRobot& robot_;
  const UrdfFileFacts& file_;
  const UrdfMessages& messages_;
  std::set<std::string> generated_parameters_;
  YAML::Node parameters_{YAML::NodeType::Sequence}, dependent_{YAML::NodeType::Sequence}, frames_{YAML::NodeType::Sequence},
      bodies_{YAML::NodeType::Sequence};
};

}  // namespace

// ---- the parser's side ------------------------------------------------------------------------

YAML::Node Parser::with_urdf(const YAML::Node& root) {
  if (!(root.IsMap() && (root["urdf"].IsDefined() || !urdf_override_.empty()))) {
    if (root.IsMap())
      for (const char* key : {"rename", "base"})
        if (root[key].IsDefined())
          Item(src_, root[key], key, {}).fail("only a model file that reads a URDF (`urdf: robot.urdf`) has this field");
    return root;
  }
  const Item top(src_, root, "", {});
  const Fields f(top, {"model", "description", "urdf", "rename", "base", "repeat", "parameters", "coordinates", "frames",
                       "bodies", "closure", "limbs", "wheels", "nonholonomic", "dynamics", "clearance", "contacts",
                       "nominal", "ik_sweeps", "limits"});
  if (auto r = f.optional("repeat")) repeats(*r);
  // The inputs are the YAML file's to name (the URDF's moving joints become the dependent ones):
  // missing, they are said to be here, where the file is, not in the document made from it.
  static_cast<void>(Fields(f["coordinates"], {"inputs", "dependent"})["inputs"]);
  const std::optional<Item> urdf_item = f.optional("urdf");
  const UrdfMessages messages{urdf_override_.empty() ? urdf_item->text() : urdf_override_, src_.name};
  UrdfRobot robot = open_urdf(urdf_item ? *urdf_item : top, urdf_item, messages.urdf);

  // Renames first: every later check and every generated name sees the new names.
  if (auto rename = f.optional("rename")) apply_renames(*rename, robot);
  const UrdfFileFacts file = urdf_file_facts(f);
  const std::map<std::string, int> link_of = link_indices(robot);
  const std::set<int> wheels = wheel_joints(robot, link_of, file.hubs, messages, urdf_axle_);
  check_names(robot, wheels, file.parameters, messages);
  urdf_limits_ = joint_limits(robot, messages.urdf);
  const RigidGroups groups = rigid_groups(robot, link_of);

  UrdfSections sections(f, robot, file, messages);
  sections.add_frames(wheels, f.optional("base"));
  urdf_wheel_shape_ = sections.add_wheel_shapes(link_of, urdf_axle_);
  sections.add_bodies(groups);
  return sections.merged(root);
}

// The URDF the file names (or the one wlx-gen was given), checked before it is read; its path
// and fingerprint are kept for the model's banners. `where` is what a message points at.
UrdfRobot Parser::open_urdf(const Item& where, const std::optional<Item>& urdf_item, const std::string& shown) {
  std::string path = urdf_override_;
  if (path.empty()) {
    path = urdf_item->text();
    if (!directory_.empty() && !std::filesystem::path(path).is_absolute()) path = (std::filesystem::path(directory_) / path).string();
  }
  if (!urdf_import_available())
    where.fail("URDF import is unavailable: this wlx-gen was built without liburdfdom (install Debian's liburdfdom-dev "
               "and configure again), or write the model by hand (docs/model-format.md)");
  // Bounded before it is read: a regular file (not a device or a pipe) of at most 64 MB.
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error) || !std::ifstream(path))
    where.fail(fmt::format("cannot open the URDF file '{}'", excerpt(path)));
  if (std::filesystem::file_size(path, error) > (64u << 20)) where.fail(fmt::format("'{}' is larger than 64 MB", excerpt(path)));
  UrdfRobot robot = read_urdf(path, shown);
  urdf_file_ = path;
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  urdf_fingerprint_ = fmt::format("{}, fingerprint {:016x}", shown, fingerprint(text.str()));
  return robot;
}

UrdfFileFacts Parser::urdf_file_facts(const Fields& f) {
  UrdfFileFacts file;
  if (auto list = f.optional("parameters"))
    each(*list, [&](const Item& it) { if (it.has("name")) file.parameters.insert(it.child("name").text()); });
  if (auto c = f.optional("coordinates")) {
    const Fields cf(*c, {"inputs", "dependent"});
    if (auto d = cf.optional("dependent"))
      d->fail("with a URDF the dependent joints are the URDF's moving joints (those not listed as inputs): leave "
              "`dependent` out");
    each(cf["inputs"], [&](const Item& it) { if (it.has("name")) file.inputs.insert(it.child("name").text()); });
  }
  if (auto w = f.optional("wheels"))
    each(*w, [&](const Item& it) {
      if (!it.has("hub")) return;
      file.hubs.emplace(it.child("hub").text(), it.child("hub"));
      if (it.has("radius")) file.hubs_with_radius.insert(it.child("hub").text());
    });
  return file;
}

}  // namespace wlx::codegen::model_file_detail
