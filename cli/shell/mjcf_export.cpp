// MJCF from a model's description (mjcf_export.hpp says what is written and why).
#include "mjcf_export.hpp"

#include "bounded_input.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <wlx/error.hpp>
#include <wlx/support/text.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace wlx::cli {

namespace {

using Json = nlohmann::json;
using Transform = Eigen::Isometry3d;

// Text of the description quoted for an XML attribute: HTML's rules are XML's (text.hpp; control
// characters and ill-formed UTF-8 are dropped or replaced there).
std::string xml(const std::string& text) { return ::wlx::text::html(text); }
// Text for an XML comment ("--" may not appear in one).
std::string comment(const std::string& raw) {
  std::string text = ::wlx::text::html(raw);
  for (std::size_t at; (at = text.find("--")) != std::string::npos;) text.replace(at, 2, "- -");
  return text;
}
std::string num(double x) { return fmt::format("{:.17g}", x == 0 ? 0.0 : x); }
std::string vec(const Eigen::Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); }
std::string quat(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return num(q.w()) + " " + num(q.x()) + " " + num(q.y()) + " " + num(q.z());
}

// The description's members, each checked for its type, named in errors as model.json's field.
const Json& member(const Json& object, const std::string& key, const std::string& where) {
  if (!object.is_object() || !object.contains(key)) throw Error(where + "." + key, "missing (regenerate the model with this wlx-gen)");
  return object.at(key);
}
std::string text(const Json& object, const std::string& key, const std::string& where) {
  const Json& v = member(object, key, where);
  if (!v.is_string()) throw Error(where + "." + key, "is not a string");
  return v.get<std::string>();
}
double number(const Json& v, const std::string& where) {
  if (!v.is_number()) throw Error(where, "is not a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw Error(where, "is not finite");
  return x;
}
Eigen::Vector3d vector3(const Json& v, const std::string& where) {
  if (!v.is_array() || v.size() != 3) throw Error(where, "is not a list of 3 numbers");
  return {number(v[0], where), number(v[1], where), number(v[2], where)};
}
int axis_index(const std::string& a, const std::string& where) {
  if (a == "x") return 0;
  if (a == "y") return 1;
  if (a == "z") return 2;
  throw Error(where, fmt::format("'{}' is not an axis (x, y or z)", a));
}
Eigen::Vector3d unit(int axis) { return Eigen::Vector3d::Unit(axis); }

struct Joint {
  std::string name;  // the coordinate
  bool revolute = true;
  Eigen::Vector3d axis, anchor;  // in the body's axes at zero joint values
};

struct Inertial {
  double mass = 0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // about com, in the body's axes
  void add(double m, const Eigen::Vector3d& c, const Eigen::Matrix3d& I_about_c) {
    if (m <= 0) return;
    const double total = mass + m;
    const Eigen::Vector3d C = (mass * com + m * c) / total;
    const auto shift = [](double mm, const Eigen::Vector3d& d) {
      return Eigen::Matrix3d(mm * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
    };
    inertia = inertia + shift(mass, com - C) + I_about_c + shift(m, c - C);
    com = C;
    mass = total;
  }
};

struct Frame {
  std::string name, parent, meaning;
  bool derived = false;  // a contact frame wlx-gen derives for a wheel on a hub: no body
  bool free = false;
  Transform placement = Transform::Identity();  // in the parent's body, at zero joint values
  std::vector<Joint> joints;
  Inertial inertial;
  std::vector<std::string> geoms;  // XML lines
  std::vector<std::string> children;
  std::string extra;  // a wheel's spinning body, XML
  bool placeholder = false;
};

// A frame's chain: its placement and its joints in the body's axes. With F_i the fixed steps and
// J_j the joints, F0 J1 F1 J2 F2 = (F0 F1 F2) (G1^-1 J1 G1) (G2^-1 J2 G2), G_j the fixed steps after
// joint j: each joint is a motion about (along) an axis through a point of the body's axes.
void place(Frame& f, const Json& chain, const std::string& where) {
  if (!chain.is_array()) throw Error(where, "is not a list");
  std::vector<Transform> fixed;  // fixed[i]: step i as a transform (identity for a joint)
  std::vector<int> joint_axis(chain.size(), -1), joint_sign(chain.size(), 1);
  std::vector<std::string> joint_name(chain.size());
  std::vector<bool> revolute(chain.size(), true);
  for (std::size_t i = 0; i < chain.size(); ++i) {
    const Json& step = chain[i];
    const std::string at = fmt::format("{}[{}]", where, i);
    Transform T = Transform::Identity();
    if (step.contains("translate")) {
      T.translation() = vector3(step["translate"], at + ".translate");
    } else if (step.contains("turn")) {
      T.linear() = Eigen::AngleAxisd(number(member(step, "angle", at), at + ".angle"), unit(axis_index(text(step, "turn", at), at + ".turn")))
                       .toRotationMatrix();
    } else if (step.contains("revolute") || step.contains("prismatic")) {
      revolute[i] = step.contains("revolute");
      joint_axis[i] = axis_index(text(step, revolute[i] ? "revolute" : "prismatic", at), at);
      joint_name[i] = text(step, "coordinate", at);
      const Json& sign = member(step, "sign", at);
      if (!sign.is_number_integer() || (sign.get<int>() != 1 && sign.get<int>() != -1)) throw Error(at + ".sign", "is not 1 or -1");
      joint_sign[i] = sign.get<int>();
    } else {
      throw Error(at, "is no chain step (translate, turn, revolute, prismatic)");
    }
    fixed.push_back(T);
  }
  // A floating base: x, y, z slides, then three rotations about different axes, under K0.
  if (f.parent == "K0" && chain.size() == 6) {
    bool free = true;
    for (int i = 0; i < 3; ++i) free = free && !revolute[static_cast<std::size_t>(i)] && joint_axis[static_cast<std::size_t>(i)] == i;
    std::set<int> axes;
    for (std::size_t i = 3; i < 6; ++i) free = free && revolute[i] && joint_axis[i] >= 0 && axes.insert(joint_axis[i]).second;
    for (std::size_t i = 0; i < 6; ++i) free = free && joint_sign[i] == 1;
    if (free) {
      f.free = true;
      return;
    }
  }
  Transform after = Transform::Identity();  // the fixed steps after step i
  std::vector<Joint> joints;
  for (std::size_t i = chain.size(); i-- > 0;) {
    if (joint_axis[i] < 0) {
      after = fixed[i] * after;
      continue;
    }
    const Eigen::Matrix3d Rt = after.linear().transpose();
    joints.push_back({joint_name[i], revolute[i], Rt * (joint_sign[i] * unit(joint_axis[i])), -(Rt * after.translation())});
  }
  std::reverse(joints.begin(), joints.end());
  f.joints = std::move(joints);
  Transform P = Transform::Identity();
  for (const auto& T : fixed) P = P * T;
  f.placement = P;
}

std::string inertial_xml(const Inertial& in) {
  const Eigen::Matrix3d& I = in.inertia;
  return fmt::format("<inertial pos=\"{}\" mass=\"{}\" fullinertia=\"{} {} {} {} {} {}\"/>", vec(in.com), num(in.mass), num(I(0, 0)),
                     num(I(1, 1)), num(I(2, 2)), num(I(0, 1)), num(I(0, 2)), num(I(1, 2)));
}

// The machine as the description gives it: parameters, frames placed and linked to their
// children, and each frame's bodies.
struct Machine {
  std::map<std::string, double> params;
  std::vector<Frame> frames;
  std::map<std::string, std::size_t> frame_index;
  std::map<std::string, std::vector<Inertial>> bodies_of;  // by frame
  double total_mass = 0;

  double param(const std::string& name, const std::string& where) const {
    const auto it = params.find(name);
    if (it == params.end()) throw Error(where, fmt::format("names no parameter ('{}')", name));
    return it->second;
  }
  Frame& frame(const std::string& name, const std::string& where) {
    const auto it = frame_index.find(name);
    if (it == frame_index.end()) throw Error(where, fmt::format("names no frame ('{}')", name));
    return frames[it->second];
  }
  const Frame& frame(const std::string& name, const std::string& where) const { return const_cast<Machine&>(*this).frame(name, where); }
};

Machine read_machine(const Json& d) {
  Machine m;
  for (const Json& p : member(d, "parameters", "model.json"))
    m.params[text(p, "name", "parameters")] = number(member(p, "value", "parameters"), "parameters.value");
  for (const Json& j : member(d, "frames", "model.json")) {
    Frame f;
    f.name = text(j, "name", "frames");
    f.parent = text(j, "parent", "frames." + f.name);
    f.meaning = j.value("meaning", "");
    if (j.contains("derived_from_wheel")) f.derived = true;
    else place(f, member(j, "chain", "frames." + f.name), "frames." + f.name + ".chain");
    if (!m.frame_index.emplace(f.name, m.frames.size()).second) throw Error("frames." + f.name, "is given twice");
    m.frames.push_back(std::move(f));
  }
  for (auto& f : m.frames)
    if (!f.derived && f.parent != "K0") m.frame(f.parent, "frames." + f.name + ".parent").children.push_back(f.name);
  for (const Json& b : member(d, "bodies", "model.json")) {
    const std::string name = text(b, "name", "bodies"), where = "bodies." + name;
    Inertial in;
    in.mass = m.param(text(b, "mass", where), where + ".mass");
    const Json& moments = member(b, "inertia", where);
    if (!moments.is_array() || moments.size() != 3) throw Error(where + ".inertia", "is not a list of 3 parameters");
    Eigen::Vector3d D;
    for (int k = 0; k < 3; ++k) D(k) = m.param(moments[static_cast<std::size_t>(k)].get<std::string>(), where + ".inertia");
    const Json& axes = member(b, "principal_axes", where);
    Eigen::Matrix3d R;
    if (!axes.is_array() || axes.size() != 3) throw Error(where + ".principal_axes", "is not a 3 x 3 matrix");
    for (int r = 0; r < 3; ++r) R.row(r) = vector3(axes[static_cast<std::size_t>(r)], where + ".principal_axes").transpose();
    in.com = vector3(member(b, "com", where), where + ".com");
    in.inertia = R * D.asDiagonal() * R.transpose();
    m.total_mass += in.mass;
    const std::string on = text(b, "frame", where);
    if (m.frame(on, where + ".frame").derived) throw Error(where + ".frame", "is a derived contact frame, which is no rigid body's");
    m.bodies_of[on].push_back(in);
  }
  return m;
}

// The contact geoms: named as their contact frames, with their friction.
class ContactGeoms {
 public:
  explicit ContactGeoms(const Json& d) : contacts_(member(d, "contacts", "model.json")) {
    const Json& friction = member(member(d, "settings", "model.json"), "friction", "settings");
    if (!friction.is_array() || friction.size() != contacts_.size())
      throw Error("settings.friction", "does not list one coefficient per contact");
    for (std::size_t k = 0; k < contacts_.size(); ++k) friction_[text(contacts_[k], "frame", "contacts")] = number(friction[k], "settings.friction");
  }
  const Json& contacts() const { return contacts_; }
  bool is_contact(const std::string& frame) const { return friction_.count(frame) > 0; }
  std::string geom(const std::string& frame, const std::string& shape) const {
    const auto mu = friction_.find(frame);
    // mass 0: a geom adds no mass (the inertials hold the model's), whatever body it is on.
    return fmt::format("<geom name=\"{}\" {} mass=\"0\" friction=\"{} 0.005 0.0001\"/>", xml(frame), shape,
                       num(mu != friction_.end() ? mu->second : 1.0));
  }

 private:
  const Json& contacts_;
  std::map<std::string, double> friction_;
};

// A wheel on a hub spins with the hub's bodies where they are the wheel's alone: their CoM on the
// axle through `centre` and their inertia the same about every axis across it (spinning moves
// no mass then).
bool spins_with_wheel(const Inertial& hub, const Eigen::Vector3d& a, const Eigen::Vector3d& centre, double r) {
  if (hub.mass <= 0) return false;
  const Eigen::Vector3d off_axle = (hub.com - centre) - a * a.dot(hub.com - centre);
  const Eigen::Matrix3d& I = hub.inertia;
  const Eigen::Vector3d Ia = I * a;
  const Eigen::Matrix3d across = I - Ia * a.transpose() - a * Ia.transpose() + a.dot(Ia) * a * a.transpose();
  const double scale = I.norm();
  const Eigen::Matrix3d plane = Eigen::Matrix3d::Identity() - a * a.transpose();
  const double symmetric = (across - 0.5 * across.trace() * plane).norm();
  return off_axle.norm() <= 1e-12 * std::max(1.0, r) && (Ia - a.dot(Ia) * a).norm() <= 1e-12 * scale && symmetric <= 1e-12 * scale;
}

// The wheels: a spinning body on a hub, or a cylinder on the file's contact frame; the feet's
// spheres. Returns each spinning wheel's joint (wheel, joint name); placeholders are said.
std::vector<std::pair<std::string, std::string>> place_contacts(Machine& m, const Json& d, const ContactGeoms& geoms, double placeholder_mass,
                                                                std::string& placeholders) {
  std::map<std::string, std::string> drive_of_wheel;
  for (const Json& a : member(d, "actuated", "model.json"))
    if (a.contains("wheel")) drive_of_wheel[text(a, "wheel", "actuated")] = text(a, "name", "actuated");
  std::set<std::string> wheel_bodies;
  std::vector<std::pair<std::string, std::string>> spin_joints;
  for (const Json& w : member(d, "wheels", "model.json")) {
    const std::string name = text(w, "name", "wheels"), where = "wheels." + name;
    const double r = m.param(text(w, "radius", where), where + ".radius");
    const Eigen::Vector3d a = unit(axis_index(text(w, "axle", where), where + ".axle"));
    const std::string hub = text(w, "hub", where), contact = text(w, "contact", where);
    if (hub.empty()) {  // the file's contact frame, on the rim's lowest point: the centre is r above it
      const Eigen::Vector3d forward = unit(axis_index(text(w, "forward", where), where + ".forward"));
      const Eigen::Vector3d lateral = unit(axis_index(text(w, "lateral", where), where + ".lateral"));
      m.frame(contact, where + ".contact").geoms.push_back(geoms.geom(
          contact, fmt::format("type=\"cylinder\" size=\"{} {}\" pos=\"{}\" zaxis=\"{}\"", num(r), num(0.2 * r), vec(r * forward.cross(lateral)), vec(lateral))));
      continue;
    }
    Frame& h = m.frame(hub, where + ".hub");
    const double offset = w["offset"].is_string() ? m.param(w["offset"].get<std::string>(), where + ".offset") : 0.0;
    const Eigen::Vector3d centre = offset * a;
    Inertial spinning;
    for (const Inertial& in : m.bodies_of[hub]) spinning.add(in.mass, in.com, in.inertia);
    if (spins_with_wheel(spinning, a, centre, r)) {
      spinning.com -= centre;
      m.bodies_of[hub].clear();
    } else {
      spinning = Inertial{placeholder_mass, Eigen::Vector3d::Zero(), placeholder_mass * Eigen::Matrix3d::Identity()};
      placeholders += fmt::format("wheel {}: its spinning body holds a placeholder of {} kg (the hub's bodies are not the wheel's alone)\n",
                                  name, num(placeholder_mass));
    }
    const std::string joint = drive_of_wheel.count(name) ? drive_of_wheel[name] : "spin_" + name;
    spin_joints.emplace_back(name, joint);
    const std::string body = "spin_" + name;
    if (!wheel_bodies.insert(body).second || m.frame_index.count(body))
      throw Error(where, fmt::format("its spinning body's name '{}' is taken", body));
    h.extra += fmt::format(
        "<body name=\"{}\" pos=\"{}\">\n  <joint name=\"{}\" type=\"hinge\" axis=\"{}\"/>\n  {}\n  {}\n</body>\n", xml(body), vec(centre),
        xml(joint), vec(a), inertial_xml(spinning),
        geoms.geom(contact, fmt::format("type=\"cylinder\" size=\"{} {}\" zaxis=\"{}\"", num(r), num(0.2 * r), vec(a))));
  }
  for (const Json& c : geoms.contacts())
    if (text(c, "kind", "contacts") == "foot") {
      const std::string f = text(c, "frame", "contacts");
      m.frame(f, "contacts.frame").geoms.push_back(geoms.geom(f, "type=\"sphere\" size=\"0.02\""));
    }
  return spin_joints;
}

// Each frame's inertial from its bodies; a moving frame without mass in it or in the frames
// welded to it (MuJoCo refuses a moving body without mass) gets a placeholder, said.
void gather_inertials(Machine& m, double placeholder_mass, std::string& placeholders) {
  for (auto& f : m.frames)
    for (const Inertial& in : m.bodies_of[f.name]) f.inertial.add(in.mass, in.com, in.inertia);
  std::function<double(const Frame&)> welded = [&](const Frame& f) {
    double mass = f.inertial.mass;
    for (const auto& c : f.children) {
      const Frame& child = m.frame(c, "frames");
      if (child.joints.empty() && !child.free) mass += welded(child);
    }
    return mass;
  };
  for (auto& f : m.frames)
    if (!f.derived && (f.free || !f.joints.empty()) && welded(f) <= 0) {
      f.inertial.mass = placeholder_mass;
      f.inertial.inertia = placeholder_mass * Eigen::Matrix3d::Identity();
      f.placeholder = true;
      placeholders += fmt::format("frame {}: moves but carries no body; a placeholder of {} kg\n", f.name, num(placeholder_mass));
    }
}

// The closure: rows on contacts are the contacts; sums become joint equalities (two coordinates)
// or a fixed tendon held at zero (more); anything else is an error naming the row.
struct Constraints {
  std::string tendons, equalities;
};
Constraints closure_xml(const Json& d, const Machine& m, const ContactGeoms& geoms) {
  std::set<std::string> joint_names;
  for (const auto& f : m.frames)
    for (const auto& j : f.joints) joint_names.insert(j.name);
  Constraints out;
  for (const Json& c : member(d, "closure", "model.json")) {
    const std::string name = text(c, "name", "closure"), type = text(c, "type", "closure." + name);
    if (type == "point" || type == "level") {
      const std::string f = text(c, "frame", "closure." + name);
      if (!geoms.is_contact(f))
        throw Error("closure." + name, fmt::format("holds frame {} inside the machine ({} row), which the export cannot express", f, type));
    } else if (type == "sum") {
      const Json& cs = member(c, "coordinates", "closure." + name);
      if (!cs.is_array() || cs.size() < 2) throw Error("closure." + name, "is a sum of fewer than two coordinates");
      std::vector<std::string> terms;
      for (const Json& term : cs) {
        if (!term.is_string() || !joint_names.count(term.get<std::string>()))
          throw Error("closure." + name, "sums a coordinate that is no joint of the tree, which the export cannot express");
        terms.push_back(term.get<std::string>());
      }
      if (terms.size() == 2) {  // q1 = -q2
        out.equalities += fmt::format("    <joint name=\"{}\" joint1=\"{}\" joint2=\"{}\" polycoef=\"0 -1 0 0 0\"/>\n", xml(name),
                                      xml(terms[0]), xml(terms[1]));
      } else {  // more: a fixed tendon, the sum, held at its length at zero joint values (0)
        out.tendons += fmt::format("    <fixed name=\"{}\">\n", xml(name));
        for (const auto& term : terms) out.tendons += fmt::format("      <joint joint=\"{}\" coef=\"1\"/>\n", xml(term));
        out.tendons += "    </fixed>\n";
        out.equalities += fmt::format("    <tendon name=\"{}\" tendon1=\"{}\"/>\n", xml(name), xml(name));
      }
    } else {
      throw Error("closure." + name, fmt::format("has type '{}', which the export does not know", type));
    }
  }
  return out;
}

// MuJoCo's names are unique per kind: joints (coordinates, free bases, wheels' spins) and geoms.
void check_unique_names(const Machine& m, const std::vector<std::pair<std::string, std::string>>& spin_joints, const ContactGeoms& geoms) {
  std::set<std::string> joints_seen, geoms_seen{"ground"};
  for (const auto& f : m.frames) {
    if (f.free && !joints_seen.insert(f.name).second) throw Error("frames." + f.name, "names a free joint that another joint's name takes");
    for (const auto& j : f.joints)
      if (!joints_seen.insert(j.name).second) throw Error("frames." + f.name, fmt::format("joint '{}' is named twice", j.name));
  }
  for (const auto& [wheel, joint] : spin_joints)
    if (!joints_seen.insert(joint).second) throw Error("wheels." + wheel, fmt::format("its spin joint's name '{}' is taken", joint));
  for (const Json& c : geoms.contacts())
    if (!geoms_seen.insert(text(c, "frame", "contacts")).second)
      throw Error("contacts", fmt::format("two contact geoms would be named '{}'", text(c, "frame", "contacts")));
}

// The body tree, from K0 down, each joint with its limits where both bounds are given.
std::string tree_xml(const Machine& m, const Json& settings) {
  std::map<std::string, std::pair<double, double>> range;
  for (const Json& l : member(settings, "limits", "settings")) {
    const Json &lo = member(l, "lower", "settings.limits"), &hi = member(l, "upper", "settings.limits");
    if (lo.is_number() && hi.is_number()) range[text(l, "coordinate", "settings.limits")] = {lo.get<double>(), hi.get<double>()};
  }
  std::string out;
  std::function<void(const Frame&, int)> write = [&](const Frame& f, int depth) {
    const std::string in(static_cast<std::size_t>(2 * depth), ' ');
    if (!f.meaning.empty()) out += in + "<!-- " + comment(f.meaning) + " -->\n";
    out += fmt::format("{}<body name=\"{}\" pos=\"{}\" quat=\"{}\">\n", in, xml(f.name), vec(f.placement.translation()), quat(f.placement.linear()));
    if (f.free) out += fmt::format("{}  <freejoint name=\"{}\"/>\n", in, xml(f.name));
    for (const auto& j : f.joints) {
      std::string limits;
      if (const auto r = range.find(j.name); r != range.end())
        limits = fmt::format(" limited=\"true\" range=\"{} {}\"", num(r->second.first), num(r->second.second));
      out += fmt::format("{}  <joint name=\"{}\" type=\"{}\" axis=\"{}\" pos=\"{}\"{}/>\n", in, xml(j.name), j.revolute ? "hinge" : "slide",
                         vec(j.axis), vec(j.anchor), limits);
    }
    if (f.inertial.mass > 0) out += in + "  " + inertial_xml(f.inertial) + (f.placeholder ? "  <!-- placeholder: no body -->" : "") + "\n";
    for (const auto& g : f.geoms) out += in + "  " + g + "\n";
    for (std::size_t at = 0; at < f.extra.size();) {  // the spinning wheels' lines, indented
      const std::size_t end = f.extra.find('\n', at);
      out += in + "  " + f.extra.substr(at, end - at) + "\n";
      at = end + 1;
    }
    for (const auto& c : f.children) write(m.frame(c, "frames"), depth + 1);
    out += in + "</body>\n";
  };
  for (const auto& f : m.frames)
    if (!f.derived && f.parent == "K0") write(f, 2);
  return out;
}

// A motor per actuator, named as the actuator, limited by its torque limit where it has one.
std::string motors_xml(const Json& d, const Json& settings) {
  std::string out;
  const Json& actuated = member(d, "actuated", "model.json");
  const Json& limits = member(settings, "torque_limits", "settings");
  for (std::size_t k = 0; k < actuated.size(); ++k) {
    const Json& a = actuated[k];
    const std::string name = text(a, "name", "actuated");
    const std::string joint = a.contains("coordinate") ? text(a, "coordinate", "actuated." + name) : name;
    std::string control;
    if (limits.is_array() && k < limits.size() && limits[k].is_number())
      control = fmt::format(" ctrllimited=\"true\" ctrlrange=\"{} {}\"", num(-limits[k].get<double>()), num(limits[k].get<double>()));
    out += fmt::format("    <motor name=\"{}\" joint=\"{}\" gear=\"1\"{}/>\n", xml(name), xml(joint), control);
  }
  return out;
}

}  // namespace

MjcfExport mjcf_of_description(const std::string& description_json) {
  const Json d = parse_json_bounded(description_json, "model.json");
  MjcfExport out;
  out.model = text(d, "model", "model.json");
  Machine m = read_machine(d);
  const double placeholder_mass = kPlaceholderMassRatio * std::max(m.total_mass, 1.0);
  const Json& settings = member(d, "settings", "model.json");
  const ContactGeoms geoms(d);
  const auto spin_joints = place_contacts(m, d, geoms, placeholder_mass, out.placeholders);
  gather_inertials(m, placeholder_mass, out.placeholders);
  const Constraints constraints = closure_xml(d, m, geoms);
  check_unique_names(m, spin_joints, geoms);
  const std::string bodies = tree_xml(m, settings);
  const std::string motors = motors_xml(d, settings);
  const Json& gravity_name = member(d, "gravity", "model.json");
  const double g = gravity_name.is_string() ? m.param(gravity_name.get<std::string>(), "gravity") : 9.81;
  out.xml = fmt::format(
      "<!-- Written by wlx export mjcf from the description of model {} ({}). Do not edit: export again. -->\n"
      "<mujoco model=\"{}\">\n"
      "  <compiler angle=\"radian\"/>\n"
      "  <option gravity=\"0 0 {}\" timestep=\"0.001\"/>\n"
      "  <worldbody>\n"
      "    <geom name=\"ground\" type=\"plane\" size=\"0 0 1\" friction=\"0 0 0\"/>\n"
      "{}"
      "  </worldbody>\n"
      "{}{}{}"
      "</mujoco>\n",
      comment(out.model), comment(text(d, "source", "model.json")), xml(out.model), num(-g), bodies,
      constraints.tendons.empty() ? "" : "  <tendon>\n" + constraints.tendons + "  </tendon>\n",
      constraints.equalities.empty() ? "" : "  <equality>\n" + constraints.equalities + "  </equality>\n",
      motors.empty() ? "" : "  <actuator>\n" + motors + "  </actuator>\n");
  return out;
}

}  // namespace wlx::cli
