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
  const Item& where = urdf_item ? *urdf_item : top;
  std::string path = urdf_override_;
  if (path.empty()) {
    path = urdf_item->text();
    if (!directory_.empty() && !std::filesystem::path(path).is_absolute()) path = (std::filesystem::path(directory_) / path).string();
  }
  const std::string shown = urdf_override_.empty() ? urdf_item->text() : urdf_override_;
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
  {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    urdf_fingerprint_ = fmt::format("{}, fingerprint {:016x}", shown, fingerprint(text.str()));
  }
  const auto urdf_fail = [&](int line, const std::string& element, const std::string& reason) {
    throw ModelFileError(fmt::format("{}:{}: {}: {}", shown, line, element, reason));
  };

  // Renames first: every later check and every generated name sees the new names.
  if (auto rename = f.optional("rename")) {
    if (!rename->is_map()) rename->fail("must map URDF link or joint names to new names {old: new}");
    std::vector<std::string> names;
    for (const auto& l : robot.links) names.push_back(l.name);
    for (const auto& j : robot.joints) names.push_back(j.name);
    for (const auto& kv : rename->node()) {
      const std::string from = kv.first.Scalar();
      const Item to_item = rename->child(from);
      const std::string to = to_item.name();
      if (std::find(names.begin(), names.end(), from) == names.end())
        Item(src_, kv.first, rename->path(), {}).fail(fmt::format("the URDF has no link or joint '{}'{}", excerpt(from), suggestion(from, names)));
      for (auto& l : robot.links)
        if (l.name == from) l.name = to;
      for (auto& j : robot.joints) {
        if (j.name == from) j.name = to;
        if (j.parent == from) j.parent = to;
        if (j.child == from) j.child = to;
      }
    }
  }
  // `suffix` makes a name that is already an identifier (but taken or reserved) a new one.
  const auto rename_hint = [&](const std::string& n, const std::string& suffix) {
    std::string fixed;
    for (char c : n) fixed += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    if (fixed.empty() || std::isdigit(static_cast<unsigned char>(fixed[0])) || fixed[0] == '_') fixed = "n" + fixed;
    while (fixed.find("__") != std::string::npos) fixed.replace(fixed.find("__"), 2, "_");
    if (fixed == n) fixed += suffix;
    return fmt::format("rename it in the URDF, or in {}: `rename: {{\"{}\": {}}}`", src_.name, excerpt(n), fixed);
  };

  // What the file says about the URDF's joints, read before the sections are built: the names of
  // its parameters and inputs (an input that names a URDF joint makes that joint an input), and
  // the hubs of its wheels (a wheel's continuous joint is its spin, not a coordinate).
  std::set<std::string> file_parameters, file_inputs;
  std::map<std::string, Item> hubs;
  std::set<std::string> hubs_with_radius;  // the wheels that give their radius themselves
  if (auto list = f.optional("parameters"))
    each(*list, [&](const Item& it) { if (it.has("name")) file_parameters.insert(it.child("name").text()); });
  if (auto c = f.optional("coordinates")) {
    const Fields cf(*c, {"inputs", "dependent"});
    if (auto d = cf.optional("dependent"))
      d->fail("with a URDF the dependent joints are the URDF's moving joints (those not listed as inputs): leave "
              "`dependent` out");
    each(cf["inputs"], [&](const Item& it) { if (it.has("name")) file_inputs.insert(it.child("name").text()); });
  }
  if (auto w = f.optional("wheels"))
    each(*w, [&](const Item& it) {
      if (!it.has("hub")) return;
      hubs.emplace(it.child("hub").text(), it.child("hub"));
      if (it.has("radius")) hubs_with_radius.insert(it.child("hub").text());
    });

  // The shortest decimal within two units in the last place: an angle that went through
  // urdfdom's quaternion (0.2 comes back as 0.20000000000000004) or a diagonalised moment reads
  // as it was written; exact values are kept exactly.
  const auto number = [](double x) {
    if (x == 0) return std::string("0");
    for (int digits = 1; digits < 17; ++digits) {
      const double y = std::stod(fmt::format("{:.{}g}", x, digits));
      if (std::abs(y - x) <= 4.5e-16 * std::abs(x)) return fmt::format("{}", y);
    }
    return fmt::format("{}", x);
  };
  const auto step = [](const char* op, const std::string& arg) {
    YAML::Node n(YAML::NodeType::Map);
    n[op] = arg;
    return n;
  };
  const auto flow = [](YAML::Node n) {
    n.SetStyle(YAML::EmitterStyle::Flow);
    return n;
  };
  const char* letters[] = {"x", "y", "z"};
  // The principal axis a unit vector lies along (-1 if none), and its sign.
  const auto principal = [](const std::array<double, 3>& a, int& sign) {
    for (int i = 0; i < 3; ++i)
      if (std::abs(std::abs(a[i]) - 1) < 1e-12 && std::abs(a[(i + 1) % 3]) < 1e-12 && std::abs(a[(i + 2) % 3]) < 1e-12) {
        sign = a[i] > 0 ? 1 : -1;
        return i;
      }
    return -1;
  };
  // Fixed turns rz, ry, rx (URDF's rpy: roll about x, pitch about y, yaw about z, fixed axes)
  // for a rotation matrix; angles below 1e-12 rad are the rounding of a quaternion, left out.
  // Fixed turns rz, ry, rx (URDF's rpy: roll about x, pitch about y, yaw about z, fixed axes)
  // for a rotation matrix; angles below 1e-12 rad are the rounding of a quaternion, left out.
  // `argument` writes the angle (a number, or the name of a parameter it makes).
  const auto turns = [&](YAML::Node& chain, const Matrix3Rows& R, const std::function<std::string(const char*, double)>& argument) {
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
      if (std::abs(angle) > 1e-12) chain.push_back(flow(step(op, argument(which, angle))));
  };

  std::map<std::string, int> link_of;  // name -> index
  for (std::size_t k = 0; k < robot.links.size(); ++k) link_of[robot.links[k].name] = static_cast<int>(k);
  // Wheels: their hubs are the child links of continuous joints.
  std::set<int> wheel_joints;
  for (const auto& [hub, item] : hubs) {
    const auto l = link_of.find(hub);
    if (l == link_of.end()) continue;  // a frame of the file's own: checked with the wheels
    const int j = robot.links[static_cast<std::size_t>(l->second)].parent_joint;
    if (j < 0 || robot.joints[static_cast<std::size_t>(j)].type != UrdfJoint::Type::Continuous)
      item.fail(fmt::format("URDF link '{}' {}: a wheel's hub is the child link of the wheel's continuous joint", hub,
                            j < 0 ? "is the root link" : fmt::format("hangs on joint '{}', which is not continuous", robot.joints[static_cast<std::size_t>(j)].name)));
    const UrdfJoint& joint = robot.joints[static_cast<std::size_t>(j)];
    int sign = 1;
    const int axis = principal(joint.axis, sign);
    if (axis < 0)
      urdf_fail(joint.line, fmt::format("joint '{}' axis", joint.name),
                "a wheel turns about an axis of its joint frame (x, y or z, either sign): turn the joint's origin (rpy) so "
                "that the axle lies along one");
    wheel_joints.insert(j);
    urdf_axle_[hub] = {static_cast<Axis>(axis), fmt::format("{}:{}", shown, joint.line), joint.name};
  }

  // Names: C++ identifiers; joints (coordinates) share a namespace with the parameters.
  std::set<std::string> generated_parameters;
  for (const auto& l : robot.links) {
    if (!is_identifier(l.name) || l.name == "K0")
      urdf_fail(l.line, fmt::format("link '{}'", excerpt(l.name)),
                fmt::format("'{}' cannot name a frame (a C++ identifier, not K0): {}", excerpt(l.name), rename_hint(l.name, "_link")));
  }
  for (std::size_t k = 0; k < robot.joints.size(); ++k) {
    const UrdfJoint& j = robot.joints[k];
    if (j.type == UrdfJoint::Type::Fixed || wheel_joints.count(static_cast<int>(k))) continue;
    const std::string element = fmt::format("joint '{}'", excerpt(j.name));
    if (!is_identifier(j.name))
      urdf_fail(j.line, element, fmt::format("'{}' cannot name a coordinate (a C++ identifier): {}", excerpt(j.name), rename_hint(j.name, "_joint")));
    if (const std::string why = reserved_reason(j.name); !why.empty())
      urdf_fail(j.line, element, fmt::format("'{}' cannot name a coordinate: {}; {}", j.name, why, rename_hint(j.name, "_joint")));
    if (file_parameters.count(j.name))
      urdf_fail(j.line, element, fmt::format("'{}' is also the name of a parameter in {}: {}", j.name, src_.name, rename_hint(j.name, "_joint")));
  }

  // The joints' <limit>s, by their (renamed) names: the `limits` section reads them, and the file's
  // own entries take precedence (limits() below); a wheel's continuous joint gives its drive's effort.
  for (const UrdfJoint& j : robot.joints)
    if (j.type != UrdfJoint::Type::Fixed && (j.lower || j.effort || j.velocity))
      urdf_limits_[j.name] = {j.lower, j.upper, j.effort, j.velocity, fmt::format("{}:{}", shown, j.limit_line)};

  // Rigid groups: a link and the links fixed to it (fixed joints collapse). Each moving joint's
  // child (and the root) starts a group; its body carries the group's mass.
  const std::size_t n = robot.links.size();
  std::vector<int> group(n, -1);
  std::vector<RigidPose> in_group(n);  // the link's pose in its group's root frame
  for (std::size_t k = 0; k < n; ++k) {
    const int pj = robot.links[k].parent_joint;
    if (pj < 0 || robot.joints[static_cast<std::size_t>(pj)].type != UrdfJoint::Type::Fixed) {
      group[k] = static_cast<int>(k);
      continue;
    }
    const UrdfJoint& j = robot.joints[static_cast<std::size_t>(pj)];
    const int parent = link_of.at(j.parent);  // earlier in the depth-first order
    group[k] = group[static_cast<std::size_t>(parent)];
    const RigidPose& p = in_group[static_cast<std::size_t>(parent)];
    RigidPose& q = in_group[k];
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

  YAML::Node parameters(YAML::NodeType::Sequence), dependent(YAML::NodeType::Sequence), frames(YAML::NodeType::Sequence),
      bodies(YAML::NodeType::Sequence);
  if (auto list = f.optional("parameters"))
    for (const auto& e : list->node()) parameters.push_back(e);
  if (auto list = f.optional("frames"))
    for (const auto& e : list->node()) frames.push_back(e);
  if (auto list = f.optional("bodies"))
    for (const auto& e : list->node()) bodies.push_back(e);
  // `owner` is the link or joint whose number it is ("link", "base"), for the message.
  const auto add_parameter = [&](int line, const char* kind_of_owner, const std::string& owner, const std::string& name, double value,
                                 const char* kind, const char* unit, const std::string& meaning) {
    if (file_parameters.count(name) || file_inputs.count(name) || generated_parameters.count(name) || robot.joint_index(name) >= 0)
      urdf_fail(line, fmt::format("{} '{}'", kind_of_owner, owner),
                fmt::format("its parameter '{}' is already a name in the model: {}", name, rename_hint(owner, std::string("_") + kind_of_owner)));
    if (const std::string why = reserved_reason(name); !why.empty())
      urdf_fail(line, fmt::format("{} '{}'", kind_of_owner, owner),
                fmt::format("its parameter '{}' cannot be used as a name: {}; {}", name, why, rename_hint(owner, std::string("_") + kind_of_owner)));
    generated_parameters.insert(name);
    YAML::Node p(YAML::NodeType::Map);
    p["name"] = name;
    p["value"] = number(value);
    p["unit"] = unit;
    p["kind"] = kind;
    p["meaning"] = meaning;
    parameters.push_back(flow(p));
  };

  for (std::size_t k = 0; k < n; ++k) {
    const UrdfLink& l = robot.links[k];
    YAML::Node frame(YAML::NodeType::Map);
    frame["name"] = l.name;
    YAML::Node chain(YAML::NodeType::Sequence);
    if (l.parent_joint < 0) {
      frame["meaning"] = fmt::format("URDF root link {}", l.name);
      frame["parent"] = "K0";
      if (auto base = f.optional("base")) {
        const Fields bf(*base, {"chain"});
        chain = bf["chain"].node();  // the file's own steps, with their places
      }
    } else {
      const UrdfJoint& j = robot.joints[static_cast<std::size_t>(l.parent_joint)];
      const bool wheel = wheel_joints.count(l.parent_joint) != 0;
      const bool moving = j.type != UrdfJoint::Type::Fixed && !wheel;
      frame["meaning"] = fmt::format("URDF link {} ({} joint {})", l.name,
                                     wheel ? "wheel hub, not spinning, of" : moving ? "after" : "fixed by", j.name);
      frame["parent"] = j.parent;
      // The origin's numbers become parameters (kinds offset and angle), as a hand-written
      // model names its geometry: symbols keep GiNaC from distributing numbers over sums (about
      // 13% fewer operations), and the geometry stays adjustable at run time, or --bake-defaults.
      const auto& t = j.origin.translation;
      if (t[0] != 0 || t[1] != 0 || t[2] != 0) {
        YAML::Node v(YAML::NodeType::Sequence);
        for (int a = 0; a < 3; ++a) {
          if (t[a] == 0) {
            v.push_back("0");
            continue;
          }
          const std::string p = fmt::format("{}_{}", j.name, letters[a]);
          add_parameter(j.line, "joint", j.name, p, t[a], "offset", "m",
                        fmt::format("origin of joint {}: {} in link {}", j.name, letters[a], j.parent));
          v.push_back(p);
        }
        YAML::Node s(YAML::NodeType::Map);
        s["translate"] = flow(v);
        chain.push_back(flow(s));
      }
      turns(chain, j.origin.rotation, [&](const char* which, double angle) {
        const std::string p = fmt::format("{}_{}", j.name, which);
        add_parameter(j.line, "joint", j.name, p, angle, "angle", "rad", fmt::format("origin of joint {}: rpy {}", j.name, which));
        return p;
      });
      if (moving) {
        const char* kind = j.type == UrdfJoint::Type::Prismatic ? "t" : "r";
        int sign = 1;
        const int axis = principal(j.axis, sign);
        const std::string q = (sign < 0 ? "-" : "") + j.name;
        if (axis >= 0) {
          chain.push_back(flow(step(fmt::format("{}{}", kind, letters[axis]).c_str(), q)));
        } else {
          // An oblique axis: turn z onto it, move about (along) z, turn back, so that the
          // child link keeps URDF's axes.
          const double theta = std::acos(std::clamp(j.axis[2], -1.0, 1.0));
          const double phi = std::atan2(j.axis[1], j.axis[0]);
          if (std::abs(phi) > 1e-12) chain.push_back(flow(step("rz", number(phi))));
          chain.push_back(flow(step("ry", number(theta))));
          chain.push_back(flow(step(fmt::format("{}z", kind).c_str(), j.name)));
          chain.push_back(flow(step("ry", number(-theta))));
          if (std::abs(phi) > 1e-12) chain.push_back(flow(step("rz", number(-phi))));
        }
        if (!file_inputs.count(j.name)) {
          YAML::Node c(YAML::NodeType::Map);
          c["name"] = j.name;
          c["unit"] = j.type == UrdfJoint::Type::Prismatic ? "m" : "rad";
          c["meaning"] = fmt::format("URDF {} joint {}", j.type == UrdfJoint::Type::Prismatic ? "prismatic" : "revolute", j.name);
          dependent.push_back(flow(c));
        }
      }
    }
    frame["chain"] = flow(chain);
    frames.push_back(frame);
  }

  // A wheel without `radius` rolls on its hub link's collision cylinder (about the axle) or sphere:
  // parameters <hub>_radius and <hub>_offset (the centre's place along the axle, which moves the
  // rolling plane), which the wheel then takes (wheels() below).
  for (const auto& [hub, item] : hubs) {
    const auto l = link_of.find(hub);
    if (l == link_of.end() || hubs_with_radius.count(hub)) continue;
    const UrdfLink& link = robot.links[static_cast<std::size_t>(l->second)];
    const UrdfAxle& axle = urdf_axle_.at(hub);
    if (!link.round_shape)
      item.fail(fmt::format("the wheel on '{}' has no `radius`, and the URDF's link '{}' has no collision cylinder or sphere to "
                            "read one from (a mesh has none): give `radius: PARAMETER`",
                            hub, hub));
    const UrdfRoundShape& shape = *link.round_shape;
    const auto a = static_cast<std::size_t>(axle.axis);
    if (shape.cylinder && !(std::abs(shape.axis[a]) >= 1 - 1e-9))
      urdf_fail(shape.line, fmt::format("link '{}' collision", hub),
                fmt::format("the cylinder's axis ({:.6g}, {:.6g}, {:.6g}) is not the wheel's axle ({} of the link): it gives no "
                            "rolling radius; turn its <origin rpy>, or give the wheel a `radius`",
                            shape.axis[0], shape.axis[1], shape.axis[2], "xyz"[a]));
    const std::string place = fmt::format("{}:{}", shown, shape.line);
    add_parameter(shape.line, "link", hub, hub + "_radius", shape.radius, "length", "m",
                  fmt::format("rolling radius of the wheel on {} (its collision {}, {})", hub, shape.cylinder ? "cylinder" : "sphere", place));
    add_parameter(shape.line, "link", hub, hub + "_offset", shape.center[a], "offset", "m",
                  fmt::format("the wheel's rolling plane along the axle {} of {} (its collision {}'s centre, {})", "xyz"[a], hub,
                              shape.cylinder ? "cylinder" : "sphere", place));
    urdf_wheel_shape_[hub] = {hub + "_radius", hub + "_offset"};
  }

  // Bodies: each group's mass, centre of mass and inertia (the parallel-axis theorem moves every
  // member's tensor to the group's centre of mass), its principal axes by diagonalisation.
  for (std::size_t g = 0; g < n; ++g) {
    if (group[g] != static_cast<int>(g)) continue;
    double mass = 0;
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();
    std::vector<std::string> members;
    for (std::size_t k = 0; k < n; ++k)
      if (group[k] == static_cast<int>(g) && robot.links[k].inertial && robot.links[k].inertial->mass > 0) {
        const auto& i = *robot.links[k].inertial;
        const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(in_group[k].rotation.data());
        const Eigen::Vector3d c = Eigen::Vector3d(in_group[k].translation.data()) + R * Eigen::Vector3d(i.com.data());
        mass += i.mass;
        moment += i.mass * c;
        if (k != g) members.push_back(robot.links[k].name);
      }
    if (!(mass > 0)) continue;
    const Eigen::Vector3d com = moment / mass;
    Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
    for (std::size_t k = 0; k < n; ++k)
      if (group[k] == static_cast<int>(g) && robot.links[k].inertial && robot.links[k].inertial->mass > 0) {
        const auto& i = *robot.links[k].inertial;
        const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(in_group[k].rotation.data());
        const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(i.inertia.data());
        const Eigen::Vector3d d = Eigen::Vector3d(in_group[k].translation.data()) + R * Eigen::Vector3d(i.com.data()) - com;
        I += R * J * R.transpose() + i.mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
      }
    const UrdfLink& root_link = robot.links[g];
    const double scale = I.diagonal().cwiseAbs().maxCoeff();
    const double off = std::max({std::abs(I(0, 1)), std::abs(I(0, 2)), std::abs(I(1, 2))});
    Eigen::Vector3d principal_moments = I.diagonal();
    Eigen::Matrix3d V = Eigen::Matrix3d::Identity();
    if (off > 1e-12 * scale) {
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
            principal_moments[c] = solver.eigenvalues()[p[c]];
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
    const std::string members_text = members.empty() ? "" : fmt::format(" (with {})", fmt::join(members, ", "));
    const std::string body_name = root_link.name;
    if (principal_moments.minCoeff() <= 1e-12 * std::max(scale, 1e-300))
      urdf_fail(root_link.line, fmt::format("link '{}' inertial", root_link.name),
                fmt::format("the principal moments of inertia{} are {}, {}, {} kg*m^2: wlx's bodies need every one positive "
                            "(give a point mass a small inertia about each axis)",
                            members_text, principal_moments[0], principal_moments[1], principal_moments[2]));
    add_parameter(root_link.line, "link", root_link.name, "m_" + body_name, mass, "mass", "kg", fmt::format("mass of URDF link {}{}", body_name, members_text));
    for (int a = 0; a < 3; ++a)
      add_parameter(root_link.line, "link", root_link.name, fmt::format("I{}_{}", a + 1, body_name), principal_moments[a], "inertia", "kg*m^2",
                    fmt::format("principal moment {} of URDF link {}{}", a + 1, body_name, members_text));
    YAML::Node b(YAML::NodeType::Map);
    b["name"] = body_name;
    b["meaning"] = fmt::format("URDF link {}{}", body_name, members_text);
    b["frame"] = root_link.name;
    YAML::Node c(YAML::NodeType::Sequence);
    for (int a = 0; a < 3; ++a) c.push_back(number(std::abs(com[a]) < 1e-15 ? 0.0 : com[a]));
    b["com"] = flow(c);
    if (!V.isIdentity(0)) {
      Matrix3Rows Vr;
      for (int r = 0; r < 3; ++r)
        for (int cc = 0; cc < 3; ++cc) Vr[3 * r + cc] = V(r, cc);
      YAML::Node rotation(YAML::NodeType::Sequence);
      turns(rotation, Vr, [&](const char*, double angle) { return number(angle); });
      if (rotation.size() > 0) b["rotation"] = flow(rotation);
    }
    b["mass"] = "m_" + body_name;
    YAML::Node inertia(YAML::NodeType::Sequence);
    for (int a = 0; a < 3; ++a) inertia.push_back(fmt::format("I{}_{}", a + 1, body_name));
    b["inertia"] = flow(inertia);
    bodies.push_back(flow(b));
  }

  YAML::Node merged(YAML::NodeType::Map);
  for (const char* key : {"model", "description", "repeat"})
    if (root[key].IsDefined()) merged[key] = root[key];
  merged["parameters"] = parameters;
  YAML::Node coordinates(YAML::NodeType::Map);
  if (root["coordinates"].IsMap() && root["coordinates"]["inputs"].IsDefined()) coordinates["inputs"] = root["coordinates"]["inputs"];
  if (dependent.size() > 0) coordinates["dependent"] = dependent;
  merged["coordinates"] = coordinates;
  merged["frames"] = frames;
  if (bodies.size() > 0) merged["bodies"] = bodies;
  for (const char* key : {"wheels", "closure", "limbs", "nonholonomic", "dynamics", "clearance", "contacts", "nominal",
                          "ik_sweeps", "limits"})
    if (root[key].IsDefined()) merged[key] = root[key];
  return merged;
}

}  // namespace wlx::codegen::model_file_detail
