#include "urdf_import.hpp"

#include "model_file.hpp"

#include <fmt/format.h>
#include <wlx/support/text.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#ifdef WLX_HAVE_URDF
#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>
#endif

namespace wlx::codegen {

int UrdfRobot::link_index(const std::string& n) const {
  for (std::size_t k = 0; k < links.size(); ++k)
    if (links[k].name == n) return static_cast<int>(k);
  return -1;
}

int UrdfRobot::joint_index(const std::string& n) const {
  for (std::size_t k = 0; k < joints.size(); ++k)
    if (joints[k].name == n) return static_cast<int>(k);
  return -1;
}

#ifndef WLX_HAVE_URDF

bool urdf_import_available() { return false; }

UrdfRobot read_urdf(const std::string& path, const std::string& shown_name) { return read_urdf_text(path, shown_name); }

UrdfRobot read_urdf_text(const std::string&, const std::string& shown_name) {
  throw ModelFileError(fmt::format("{}: URDF import is unavailable: this wlx-gen was built without liburdfdom (install "
                                   "Debian's liburdfdom-dev and configure again), or write the model file by hand "
                                   "(docs/model-format.md)",
                                   shown_name));
}

#else

bool urdf_import_available() { return true; }

namespace {

std::string shown(const std::string& s) { return text::excerpt(s); }

// The first pass: TinyXML (what Debian's urdfdom parses with) keeps every element's line, which
// urdfdom's own messages lack, so the structure and the numbers are checked here, with places;
// urdfdom then reads what this pass accepted.
class Checker {
 public:
  explicit Checker(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(int line, const std::string& element, const std::string& reason) const {
    throw ModelFileError(fmt::format("{}:{}: {}: {}", file_, line, element, reason));
  }

  // Whitespace-separated finite numbers, exactly `count` of them.
  std::vector<double> numbers(const TiXmlElement* e, const char* attribute, std::size_t count, const std::string& element,
                              const std::vector<double>& fallback) const {
    const char* text = e ? e->Attribute(attribute) : nullptr;
    if (text == nullptr) return fallback;
    std::istringstream in{std::string(text)};
    std::vector<double> out;
    std::string word;
    while (in >> word) {
      char* end = nullptr;
      const double v = std::strtod(word.c_str(), &end);
      if (end != word.c_str() + word.size() || !std::isfinite(v))
        fail(e->Row(), element, fmt::format("{}=\"{}\": '{}' is not a finite number", attribute, shown(text), shown(word)));
      out.push_back(v);
    }
    if (out.size() != count)
      fail(e->Row(), element, fmt::format("{}=\"{}\" must be {} numbers", attribute, shown(text), count));
    return out;
  }

  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

std::string element_name(const char* kind, const std::string& name) { return fmt::format("{} '{}'", kind, shown(name)); }

// urdfdom reports through console_bridge: its messages are collected and the last error is quoted.
class Collector : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) last_error = text;
  }
  std::string last_error;
};

Matrix3Rows rotation_of(const urdf::Rotation& q) {
  const double x = q.x, y = q.y, z = q.z, w = q.w;
  return {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
          2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
          2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
}

}  // namespace

namespace {

// TinyXML (the pre-pass's and urdfdom's XML layer) steps over a UTF-8 lead byte by the length
// it announces without looking for the end of the text: a sequence cut short by the end of the
// file makes it read past the buffer (found by fuzz_urdf). XML's text is well-formed UTF-8 in
// any case, and a NUL would end TinyXML's reading early and drop the rest of the file unseen.
void check_encoding(const std::string& text, const Checker& check) {
  int line = 1;
  std::size_t line_start = 0;
  for (std::size_t k = 0; k < text.size();) {
    const std::size_t length = text::utf8_length(text, k);
    if (length == 0 || text[k] == '\0')
      check.fail(line, "XML",
                 fmt::format("{} at byte {} of the line: a URDF is UTF-8 text (save it as UTF-8)",
                             length == 0 ? "bytes that are not UTF-8" : "a NUL byte", k - line_start + 1));
    if (text[k] == '\n') {
      ++line;
      line_start = k + 1;
    }
    k += length;
  }
}

// TinyXML parses nested elements recursively: bound the depth before it sees the text (a URDF
// nests five levels; comments, declarations and quoted attribute values are skipped). The same
// pass counts the elements, and the links and joints among them, so that a file past the limits
// is refused with the line where it passes them, before anything is built from it (a 64 MB file
// of empty elements would otherwise take gigabytes in TinyXML's tree).
void check_xml_bounds(const std::string& text, const Checker& check) {
  int depth = 0, line = 1;
  std::size_t elements = 0, links = 0, joints = 0;
  const auto tag_is = [&](std::size_t at, const char* tag) {
    const std::size_t n = std::strlen(tag);
    return text.compare(at, n, tag) == 0 && at + n < text.size() && std::strchr(" \t\r\n/>", text[at + n]) != nullptr;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n') ++line;
    if (text[i] != '<') continue;
    const auto skip_to = [&](const char* end) {
      const std::size_t at = text.find(end, i);
      const std::size_t stop = at == std::string::npos ? text.size() : at;
      line += static_cast<int>(std::count(text.begin() + static_cast<std::ptrdiff_t>(i), text.begin() + static_cast<std::ptrdiff_t>(stop), '\n'));
      i = stop;
    };
    if (text.compare(i, 4, "<!--") == 0) skip_to("-->");
    else if (text.compare(i, 9, "<![CDATA[") == 0) skip_to("]]>");  // text, whatever its brackets
    else if (text.compare(i, 2, "<?") == 0 || text.compare(i, 2, "<!") == 0) skip_to(">");
    else if (text.compare(i, 2, "</") == 0) depth = std::max(0, depth - 1);
    else {
      if (++elements > kMaxUrdfElements)
        check.fail(line, "XML", fmt::format("more than {} elements: a URDF of at most {} links is read", kMaxUrdfElements, kMaxFrames));
      if (depth == 1 && tag_is(i + 1, "link") && ++links > kMaxFrames)
        check.fail(line, "link", fmt::format("more than {} links (wlx's limit of frames)", kMaxFrames));
      if (depth == 1 && tag_is(i + 1, "joint") && ++joints > kMaxFrames)
        check.fail(line, "joint", fmt::format("more than {} joints (wlx's limit of frames)", kMaxFrames));
      char quote = 0;
      std::size_t j = i + 1;
      for (; j < text.size() && (quote || text[j] != '>'); ++j) {
        if (text[j] == '\n') ++line;
        if (quote && text[j] == quote) quote = 0;
        else if (!quote && (text[j] == '"' || text[j] == '\'')) quote = text[j];
      }
      if (j < text.size() && text[j - 1] != '/' && ++depth > 64)
        check.fail(line, "XML", "elements nest more than 64 levels deep");
      i = j;
    }
  }
}


// ---- the first pass's elements ----------------------------------------------------------------

struct LinkEntry {
  int line;
  const TiXmlElement* element;
  std::optional<UrdfRoundShape> round_shape;
};
struct JointEntry {
  std::string name, type, parent, child;
  int line;
  std::optional<double> lower, upper, effort, velocity;
  int limit_line = 0;
};
// The <link>s and <joint>s the first pass accepted, in the file's order.
struct Entries {
  std::map<std::string, LinkEntry> links;
  std::vector<std::string> link_order;
  std::vector<JointEntry> joints;
  std::map<std::string, int> joint_lines;
};

void check_inertial(const TiXmlElement* inertial, const std::string& element, const Checker& check) {
  check.numbers(inertial->FirstChildElement("origin"), "xyz", 3, element + " inertial origin", {0, 0, 0});
  check.numbers(inertial->FirstChildElement("origin"), "rpy", 3, element + " inertial origin", {0, 0, 0});
  const TiXmlElement* mass = inertial->FirstChildElement("mass");
  if (mass == nullptr) check.fail(inertial->Row(), element + " inertial", "has no <mass value=\"...\"/>");
  const auto m = check.numbers(mass, "value", 1, element + " inertial mass", {});
  if (m.empty()) check.fail(mass->Row(), element + " inertial mass", "has no value attribute");
  if (m[0] < 0) check.fail(mass->Row(), element + " inertial mass", fmt::format("a mass cannot be negative, got {}", m[0]));
  const TiXmlElement* inertia = inertial->FirstChildElement("inertia");
  if (inertia == nullptr) check.fail(inertial->Row(), element + " inertial", "has no <inertia ixx=... iyy=... izz=... ixy=... ixz=... iyz=.../>");
  for (const char* a : {"ixx", "iyy", "izz", "ixy", "ixz", "iyz"})
    if (check.numbers(inertia, a, 1, element + " inertial inertia", {}).empty())
      check.fail(inertia->Row(), element + " inertial inertia", fmt::format("has no {} attribute", a));
}

// The first collision cylinder or sphere: a wheel's rolling radius (and its plane's offset).
std::optional<UrdfRoundShape> first_round_shape(const TiXmlElement* link, const std::string& element, const Checker& check) {
  for (const TiXmlElement* c = link->FirstChildElement("collision"); c != nullptr; c = c->NextSiblingElement("collision")) {
    const TiXmlElement* geometry = c->FirstChildElement("geometry");
    const TiXmlElement* shape = nullptr;
    bool cylinder = false;
    if (geometry != nullptr) {
      if ((shape = geometry->FirstChildElement("cylinder")) != nullptr) cylinder = true;
      else shape = geometry->FirstChildElement("sphere");
    }
    if (shape == nullptr) continue;
    const std::string where = element + " collision";
    const auto r = check.numbers(shape, "radius", 1, where, {});
    if (r.empty()) check.fail(shape->Row(), where, fmt::format("<{}> has no radius", cylinder ? "cylinder" : "sphere"));
    if (!(r[0] > 0 && r[0] <= 1e3)) check.fail(shape->Row(), where, fmt::format("radius=\"{}\" must be in (0, 1000] m", r[0]));
    const TiXmlElement* origin = c->FirstChildElement("origin");
    const auto xyz = check.numbers(origin, "xyz", 3, where + " origin", {0, 0, 0});
    const auto rpy = check.numbers(origin, "rpy", 3, where + " origin", {0, 0, 0});
    UrdfRoundShape round;
    round.cylinder = cylinder;
    round.radius = r[0];
    round.center = {xyz[0], xyz[1], xyz[2]};
    // z of R = Rz(yaw) Ry(pitch) Rx(roll): the cylinder's axis in the link's axes.
    const double cr = std::cos(rpy[0]), sr = std::sin(rpy[0]), cp = std::cos(rpy[1]), sp = std::sin(rpy[1]);
    const double cy = std::cos(rpy[2]), sy = std::sin(rpy[2]);
    round.axis = {cy * sp * cr + sy * sr, sy * sp * cr - cy * sr, cp * cr};
    round.line = c->Row();
    return round;
  }
  return std::nullopt;
}

void read_link(const TiXmlElement* e, Entries& entries, const Checker& check) {
  const char* name = e->Attribute("name");
  if (name == nullptr || !*name) check.fail(e->Row(), "link", "has no name");
  if (entries.links.count(name))
    check.fail(e->Row(), element_name("link", name), fmt::format("defined twice (first at line {})", entries.links[name].line));
  entries.links[name] = {e->Row(), e, std::nullopt};
  entries.link_order.push_back(name);
  const std::string element = element_name("link", name);
  if (const TiXmlElement* inertial = e->FirstChildElement("inertial")) check_inertial(inertial, element, check);
  entries.links[name].round_shape = first_round_shape(e, element, check);
}

// A moving joint's <limit>: its effort and velocity, and its range.
void read_limit(const TiXmlElement* limit, const std::string& element, JointEntry& j, const Checker& check) {
  j.limit_line = limit->Row();
  const auto one = [&](const char* attribute) -> std::optional<double> {
    const auto v = check.numbers(limit, attribute, 1, element + " limit", {});
    return v.empty() ? std::nullopt : std::optional<double>(v[0]);
  };
  j.effort = one("effort");
  j.velocity = one("velocity");
  for (const auto& [name, v] : {std::pair{"effort", j.effort}, std::pair{"velocity", j.velocity}})
    if (v && !(*v >= 0 && *v <= 1e9))
      check.fail(limit->Row(), element + " limit", fmt::format("{}=\"{}\" must be in [0, 1e9]", name, *v));
  // A continuous joint has no range (URDF ignores its lower and upper); neither has a range of
  // zero width, which is what URDF's defaults give when both are left out.
  if (j.type != "continuous") {
    const auto lower = one("lower"), upper = one("upper");
    const double lo = lower.value_or(0), hi = upper.value_or(0);
    if (lo > hi)
      check.fail(limit->Row(), element + " limit", fmt::format("lower=\"{}\" is above upper=\"{}\"", lo, hi));
    if (lo < hi) j.lower = lo, j.upper = hi;
  }
}

JointEntry read_joint(const TiXmlElement* e, std::map<std::string, int>& joint_lines, const Checker& check) {
  const char* name = e->Attribute("name");
  if (name == nullptr || !*name) check.fail(e->Row(), "joint", "has no name");
  const std::string element = element_name("joint", name);
  if (joint_lines.count(name)) check.fail(e->Row(), element, fmt::format("defined twice (first at line {})", joint_lines[name]));
  joint_lines[name] = e->Row();
  const char* type = e->Attribute("type");
  if (type == nullptr) check.fail(e->Row(), element, "has no type (revolute, continuous, prismatic or fixed)");
  const std::string t = type;
  if (t == "floating")
    check.fail(e->Row(), element,
               "floating joints are not read: leave the joint out and place the URDF's root link with `base: {chain: "
               "[tx: x, ty: y, tz: z, rz: yaw, ry: pitch, rx: roll]}` in the YAML file");
  if (t == "planar") check.fail(e->Row(), element, "planar joints are not supported: model the plane as two prismatic joints and a revolute one");
  if (t != "revolute" && t != "continuous" && t != "prismatic" && t != "fixed")
    check.fail(e->Row(), element, fmt::format("unknown joint type '{}'{}; the types read are revolute, continuous, prismatic and fixed",
                                              shown(t), did_you_mean(t, {"revolute", "continuous", "prismatic", "fixed"})));
  if (const TiXmlElement* mimic = e->FirstChildElement("mimic"))
    check.fail(mimic->Row(), element + " mimic",
               "mimic joints are not supported: wlx's joints are independent coordinates; drive the joint with its "
               "own coordinate and couple it with a closure condition in the YAML file");
  JointEntry j{name, t, "", "", e->Row(), {}, {}, {}, {}, 0};
  for (const char* role : {"parent", "child"}) {
    const TiXmlElement* r = e->FirstChildElement(role);
    const char* link = r ? r->Attribute("link") : nullptr;
    if (link == nullptr) check.fail(r ? r->Row() : e->Row(), element, fmt::format("has no <{} link=\"...\"/>", role));
    (std::string(role) == "parent" ? j.parent : j.child) = link;
  }
  const TiXmlElement* origin = e->FirstChildElement("origin");
  check.numbers(origin, "xyz", 3, element + " origin", {0, 0, 0});
  check.numbers(origin, "rpy", 3, element + " origin", {0, 0, 0});
  if (t != "fixed") {
    const TiXmlElement* axis = e->FirstChildElement("axis");
    const auto a = check.numbers(axis, "xyz", 3, element + " axis", {1, 0, 0});
    if (std::hypot(a[0], a[1], a[2]) < 1e-9) check.fail(axis->Row(), element + " axis", "the axis is zero: give its direction");
  }
  const TiXmlElement* limit = e->FirstChildElement("limit");
  if ((t == "revolute" || t == "prismatic") && limit == nullptr)
    check.fail(e->Row(), element, fmt::format("URDF requires <limit effort=... velocity=.../> for a {} joint", t));
  if (limit != nullptr && t != "fixed") read_limit(limit, element, j, check);
  return j;
}

Entries read_entries(const TiXmlElement* robot, const Checker& check) {
  Entries entries;
  for (const TiXmlElement* e = robot->FirstChildElement(); e != nullptr; e = e->NextSiblingElement()) {
    const std::string tag = e->Value();
    if (tag.rfind("xacro:", 0) == 0)
      check.fail(e->Row(), fmt::format("<{}>", shown(tag)), "this is xacro, not URDF: expand it first (xacro robot.urdf.xacro > robot.urdf)");
    if (tag == "link") read_link(e, entries, check);
    else if (tag == "joint") entries.joints.push_back(read_joint(e, entries.joint_lines, check));
  }
  if (entries.links.empty()) check.fail(robot->Row(), "robot", "has no <link>");
  return entries;
}

// ---- the tree ---------------------------------------------------------------------------------

// Every link hangs from the root. Links on a loop of joints apart from the tree each have a
// parent, so the count of roots cannot see them; unchecked, they and their mass would vanish.
void check_all_reached(const Entries& entries, const std::string& root, const Checker& check) {
  std::map<std::string, std::vector<std::string>> children_of;
  for (const auto& j : entries.joints) children_of[j.parent].push_back(j.child);
  std::set<std::string> reached{root};
  for (std::vector<std::string> todo{root}; !todo.empty();) {
    const std::string link = todo.back();
    todo.pop_back();
    for (const auto& child : children_of[link])
      if (reached.insert(child).second) todo.push_back(child);
  }
  std::vector<std::string> lost;
  for (const auto& n : entries.link_order)
    if (!reached.count(n)) lost.push_back(n);
  if (!lost.empty()) {
    std::string names;
    for (std::size_t k = 0; k < lost.size() && k < 5; ++k) names += fmt::format("{}'{}'", k ? ", " : "", shown(lost[k]));
    if (lost.size() > 5) names += fmt::format(" and {} more", lost.size() - 5);
    check.fail(entries.links.at(lost[0]).line, element_name("link", lost[0]),
               fmt::format("the root link '{}' does not reach it: {} hang on a loop of joints apart from the tree (a URDF "
                           "is one tree from its root; close loops with closure conditions in the YAML file)",
                           shown(root), lost.size() == 1 ? "it" : names));
  }
}

// The tree: every link has at most one parent joint, exactly one has none, all are reached.
// Returns the root link.
std::string root_of_tree(const Entries& entries, const TiXmlElement* robot, const Checker& check) {
  std::map<std::string, std::size_t> parent_of;
  for (std::size_t k = 0; k < entries.joints.size(); ++k) {
    const JointEntry& j = entries.joints[k];
    const std::string element = element_name("joint", j.name);
    for (const std::string* link : {&j.parent, &j.child})
      if (!entries.links.count(*link))
        check.fail(j.line, element, fmt::format("no link '{}'{}", shown(*link), did_you_mean(*link, entries.link_order)));
    if (j.parent == j.child) check.fail(j.line, element, "its parent and child are the same link");
    if (parent_of.count(j.child))
      check.fail(j.line, element,
                 fmt::format("link '{}' is already the child of joint '{}': a URDF is a tree (close loops with closure conditions in the YAML file)",
                             j.child, entries.joints[parent_of[j.child]].name));
    parent_of[j.child] = k;
  }
  std::vector<std::string> roots;
  for (const auto& n : entries.link_order)
    if (!parent_of.count(n)) roots.push_back(n);
  if (roots.size() != 1) {
    if (roots.empty()) check.fail(robot->Row(), "robot", "every link has a parent joint: the joints form a loop");
    check.fail(entries.links.at(roots[1]).line, element_name("link", roots[1]),
               fmt::format("a second root: no joint connects it to the tree of '{}' (a URDF has one root link)", roots[0]));
  }
  check_all_reached(entries, roots[0], check);
  return roots[0];
}

// ---- urdfdom's values -------------------------------------------------------------------------

// urdfdom reads the accepted file: the values come from it.
urdf::ModelInterfaceSharedPtr read_with_urdfdom(const std::string& text, const Entries& entries, const TiXmlElement* robot,
                                                const Checker& check) {
  Collector collector;
  console_bridge::useOutputHandler(&collector);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(text);
  } catch (const std::exception& e) {
    collector.last_error = e.what();
  }
  console_bridge::restorePreviousOutputHandler();
  if (!model) {
    // Place it where the message names an element ("... joint [name] ..."), else the robot.
    int line = robot->Row();
    std::string element = "robot";
    for (const auto& [n, l] : entries.joint_lines)
      if (collector.last_error.find("[" + n + "]") != std::string::npos) line = l, element = element_name("joint", n);
    for (const auto& [n, entry] : entries.links)
      if (collector.last_error.find("[" + n + "]") != std::string::npos) line = entry.line, element = element_name("link", n);
    check.fail(line, element, fmt::format("urdfdom cannot read it: {}", shown(collector.last_error.empty() ? "no reason given" : collector.last_error)));
  }
  return model;
}

UrdfInertial inertial_of(const urdf::Inertial& inertial) {
  UrdfInertial i;
  i.mass = inertial.mass;
  i.com = {inertial.origin.position.x, inertial.origin.position.y, inertial.origin.position.z};
  // The tensor is given in the inertial frame: turned into the link's axes, R I R^T.
  const Matrix3Rows R = rotation_of(inertial.origin.rotation);
  const double J[9] = {inertial.ixx, inertial.ixy, inertial.ixz, inertial.ixy, inertial.iyy,
                       inertial.iyz, inertial.ixz, inertial.iyz, inertial.izz};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double sum = 0;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) sum += R[3 * r + a] * J[3 * a + b] * R[3 * c + b];
      i.inertia[3 * r + c] = sum;
    }
  return i;
}

UrdfJoint joint_of(const JointEntry& e, const urdf::ModelInterface& model, const Checker& check) {
  const urdf::JointConstSharedPtr j = model.getJoint(e.name);
  // urdfdom reads names through its own pass over the XML: should it ever read a name
  // otherwise than the first pass did (it once did for bytes that were not UTF-8, which
  // check_encoding now refuses first), the joint is an error at its line, not a null pointer.
  if (!j)
    check.fail(e.line, "joint", fmt::format("name {}: the URDF parser does not find a joint of this name: write joint "
                                            "names in plain ASCII", shown(e.name)));
  UrdfJoint joint;
  joint.name = e.name;
  joint.line = e.line;
  joint.type = e.type == "revolute"     ? UrdfJoint::Type::Revolute
               : e.type == "continuous" ? UrdfJoint::Type::Continuous
               : e.type == "prismatic"  ? UrdfJoint::Type::Prismatic
                                        : UrdfJoint::Type::Fixed;
  joint.parent = e.parent;
  joint.child = e.child;
  joint.lower = e.lower;
  joint.upper = e.upper;
  joint.effort = e.effort;
  joint.velocity = e.velocity;
  joint.limit_line = e.limit_line;
  const auto& pose = j->parent_to_joint_origin_transform;
  joint.origin.translation = {pose.position.x, pose.position.y, pose.position.z};
  joint.origin.rotation = rotation_of(pose.rotation);
  const double norm = std::hypot(j->axis.x, j->axis.y, j->axis.z);
  if (joint.type != UrdfJoint::Type::Fixed) joint.axis = {j->axis.x / norm, j->axis.y / norm, j->axis.z / norm};
  return joint;
}

// The links depth first from the root, children in the order of their joints in the file, with
// their joints numbered in link order.
UrdfRobot robot_in_tree_order(const urdf::ModelInterface& model, const Entries& entries, const std::string& root,
                              const std::string& shown_name, const Checker& check) {
  UrdfRobot out;
  out.file = shown_name;
  out.name = model.getName();
  std::map<std::string, std::vector<std::size_t>> children;
  for (std::size_t k = 0; k < entries.joints.size(); ++k) children[entries.joints[k].parent].push_back(k);
  std::vector<std::pair<std::string, int>> stack{{root, -1}};
  while (!stack.empty()) {
    const auto [name, parent_joint] = stack.back();
    stack.pop_back();
    UrdfLink link;
    link.name = name;
    link.line = entries.links.at(name).line;
    link.round_shape = entries.links.at(name).round_shape;
    link.parent_joint = parent_joint;
    const urdf::LinkConstSharedPtr l = model.getLink(name);
    if (l && l->inertial) link.inertial = inertial_of(*l->inertial);
    out.links.push_back(std::move(link));
    const auto& mine = children[name];
    for (auto it = mine.rbegin(); it != mine.rend(); ++it) {
      const JointEntry& e = entries.joints[*it];
      out.joints.push_back(joint_of(e, model, check));
      stack.emplace_back(e.child, -1);
    }
    // The joints just pushed are numbered in pop order below.
  }
  // Number the joints in link order: link k's parent joint is the one whose child it is.
  std::vector<UrdfJoint> ordered;
  for (auto& link : out.links) {
    if (link.name == root) continue;
    for (auto& j : out.joints)
      if (j.child == link.name) {
        link.parent_joint = static_cast<int>(ordered.size());
        ordered.push_back(j);
        break;
      }
  }
  out.joints = std::move(ordered);
  return out;
}

}  // namespace

UrdfRobot read_urdf(const std::string& path, const std::string& shown_name) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ModelFileError(fmt::format("{}: cannot open the URDF file", shown_name));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return read_urdf_text(buffer.str(), shown_name);
}

UrdfRobot read_urdf_text(const std::string& text, const std::string& shown_name) {
  if (text.size() > (64u << 20)) throw ModelFileError(fmt::format("{}: a URDF of more than 64 MB is not read", shown_name));
  const Checker check(shown_name);

  check_encoding(text, check);
  check_xml_bounds(text, check);
  TiXmlDocument doc;
  doc.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (doc.Error()) check.fail(doc.ErrorRow() > 0 ? doc.ErrorRow() : 1, "XML", doc.ErrorDesc());
  const TiXmlElement* robot = doc.RootElement();
  if (robot == nullptr) check.fail(1, "XML", "no element: a URDF is a <robot> element");
  if (std::string(robot->Value()) != "robot")
    check.fail(robot->Row(), fmt::format("<{}>", shown(robot->Value())), "the root element of a URDF is <robot>");

  const Entries entries = read_entries(robot, check);
  const std::string root = root_of_tree(entries, robot, check);
  const urdf::ModelInterfaceSharedPtr model = read_with_urdfdom(text, entries, robot, check);
  return robot_in_tree_order(*model, entries, root, shown_name, check);
}

#endif

}  // namespace wlx::codegen
