// URDF import: a URDF with its YAML file gives the model a hand-written model file gives. The
// references are independent of the importer: tests/models/quadruped.yaml, written by hand for the
// same robot as models/wheeled_quadruped.urdf (whose base_inertia link tools/quadruped_urdf_inertia.py
// computed in plain Python), and, for what that robot does not have (oblique axes, prismatic
// joints, chains of fixed links, full inertia tensors turned against their links), transforms
// composed here with Eigen's AngleAxis from the URDF's own numbers.
#include "../../generator/model_file.hpp"
#include "../../generator/urdf_import.hpp"

#include <Eigen/Geometry>
#include <doctest/doctest.h>
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace wlx::codegen;
namespace fs = std::filesystem;

namespace {

const std::string kModels = WLX_SOURCE_DIR "/models";
const std::string kTestModels = WLX_SOURCE_DIR "/tests/models";

// Numeric values of a model's symbols: parameters at their defaults, coordinates as given.
struct Evaluator {
  const Model& model;
  GiNaC::exmap values;
  Evaluator(const Model& m, const std::map<std::string, double>& coordinates) : model(m) {
    for (const auto& p : m.parameters) values[p.symbol] = p.default_value;
    for (const auto& c : m.coordinates) values[c.q] = coordinates.count(c.name) ? coordinates.at(c.name) : 0.0;
  }
  double operator()(const ex& e) const {
    const ex v = GiNaC::evalf(e.subs(values));
    REQUIRE(GiNaC::is_a<GiNaC::numeric>(v));
    return GiNaC::ex_to<GiNaC::numeric>(v).to_double();
  }
  Eigen::Vector3d vec(const Vec3& v) const { return {(*this)(v[0]), (*this)(v[1]), (*this)(v[2])}; }
  Eigen::Matrix3d mat(const Mat3& m) const {
    Eigen::Matrix3d out;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out(r, c) = (*this)(m(r, c));
    return out;
  }
  double parameter(const std::string& n) const { return model.parameter(n).default_value; }
  // A body's inertia tensor about its centre of mass, in K0: R diag(I) R^T.
  Eigen::Matrix3d inertia(const Body& b) const {
    const Eigen::Matrix3d R = mat(b.com_frame.R);
    const Eigen::Vector3d d(parameter(b.inertia[0]), parameter(b.inertia[1]), parameter(b.inertia[2]));
    return R * d.asDiagonal() * R.transpose();
  }
};

const Body& body(const Model& m, const std::string& name) {
  for (const auto& b : m.bodies)
    if (b.name == name) return b;
  FAIL("no body " << name);
  return m.bodies.front();
}

fs::path scratch() {
  const fs::path dir = fs::temp_directory_path() / fmt::format("wlx_urdf_test_{}", static_cast<long>(::getpid()));
  fs::create_directories(dir);
  return dir;
}

}  // namespace

#ifdef WLX_HAVE_URDF_TESTS

TEST_CASE("URDF import: the wheeled quadruped's URDF and YAML give the hand-written quadruped's model") {
  const Model hand = load_model_file(kTestModels + "/quadruped.yaml");
  const Model urdf = load_model_file(kModels + "/wheeled_quadruped.yaml");
  // The same coordinates in the same order: the YAML's inputs, then the URDF's moving joints that
  // are not wheels, depth first.
  REQUIRE(urdf.coordinates.size() == hand.coordinates.size());
  for (std::size_t k = 0; k < hand.coordinates.size(); ++k) {
    CHECK(urdf.coordinates[k].name == hand.coordinates[k].name);
    CHECK(urdf.coordinates[k].unit == hand.coordinates[k].unit);
  }
  CHECK(urdf.input_count == hand.input_count);
  CHECK(urdf.wheels.size() == 4);
  CHECK(urdf.limbs.size() == 4);
  // The twelve leg joints and the four wheels' drives, which the URDF's continuous joints name
  // (the hand-written file's drives are spin_<wheel>), each on its own wheel.
  REQUIRE(urdf.dynamics->actuated.size() == 16);
  REQUIRE(hand.dynamics->actuated.size() == 16);
  for (std::size_t k = 0; k < 16; ++k) {
    const Actuator &u = urdf.dynamics->actuated[k], &h = hand.dynamics->actuated[k];
    CHECK(u.coordinate == h.coordinate);
    CHECK(u.wheel == h.wheel);
    if (k < 12) CHECK(u.name == h.name);
  }
  CHECK(urdf.dynamics->actuated[12].name == "wheel_joint_lf");
  CHECK(hand.dynamics->actuated[12].name == "spin_lf");
  CHECK(urdf.dynamics->actuated[15].wheel == 3);
  // Every link is a frame (the fixed sensor links too): 1 + 4 fixed + 4 x 4 leg links + 4 contacts.
  CHECK(urdf.frames.size() == 25);
  CHECK(urdf.frame_index("imu_link") >= 0);
  CHECK(urdf.source.find("wheeled_quadruped.urdf, fingerprint ") != std::string::npos);

  // Forward kinematics of every hand-written frame (hub_<leg> is the URDF's wheel_<leg>) at random
  // states: positions and orientations agree to rounding (1e-12: a few operations on numbers of
  // order 1; the URDF's rpy went through urdfdom's quaternions). Five states, each of every
  // coordinate at once: a wrong axis, origin or inertia differs at almost every state, and each
  // state costs GiNaC's substitution into every frame and body of both models (20 states took 24 s
  // of CI's sanitized run).
  std::mt19937_64 rng(24);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  double worst_position = 0, worst_rotation = 0, worst_inertia = 0, worst_com = 0;
  for (int trial = 0; trial < 5; ++trial) {
    std::map<std::string, double> s;
    for (const auto& c : hand.coordinates) s[c.name] = u(rng);
    const Evaluator eh(hand, s), eu(urdf, s);
    for (const auto& f : hand.frames) {
      std::string n = f.name;
      if (n.rfind("hub_", 0) == 0) n = "wheel_" + n.substr(4);
      REQUIRE_MESSAGE(urdf.frame_index(n) >= 0, n);
      const Frame& g = urdf.frames[static_cast<std::size_t>(urdf.frame_index(n))].frame;
      worst_position = std::max(worst_position, (eh.vec(f.frame.r) - eu.vec(g.r)).cwiseAbs().maxCoeff());
      worst_rotation = std::max(worst_rotation, (eh.mat(f.frame.R) - eu.mat(g.R)).cwiseAbs().maxCoeff());
    }
    // Bodies: the base merged from base_inertia, the IMU and the lidar (fixed links) is the
    // hand-written base; the rest one to one. Mass, centre of mass and tensor in K0.
    for (const auto& b : hand.bodies) {
      const Body& c = body(urdf, b.name);
      CHECK(eu.parameter(c.mass) == doctest::Approx(eh.parameter(b.mass)).epsilon(1e-14));
      worst_com = std::max(worst_com, (eh.vec(b.com_frame.r) - eu.vec(c.com_frame.r)).cwiseAbs().maxCoeff());
      worst_inertia = std::max(worst_inertia, (eh.inertia(b) - eu.inertia(c)).cwiseAbs().maxCoeff());
    }
  }
  MESSAGE(fmt::format("URDF vs hand-written: frames {:.1e} m, {:.1e} (rotation); bodies' CoM {:.1e} m, inertia {:.1e} kg*m^2",
                      worst_position, worst_rotation, worst_com, worst_inertia));
  CHECK(worst_position < 1e-12);
  CHECK(worst_rotation < 1e-12);
  CHECK(worst_com < 1e-12);
  CHECK(worst_inertia < 1e-12);
}

TEST_CASE("URDF import: --print-model writes a model file that reads without the URDF, to the same model") {
  const std::string text = print_model_file(kModels + "/wheeled_quadruped.yaml");
  CHECK(text.find("urdf:") == std::string::npos);
  CHECK(text.find("haa_lf_x") != std::string::npos);  // the origins' numbers as parameters
  const Model printed = parse_model(text, "printed.yaml");
  const Model urdf = load_model_file(kModels + "/wheeled_quadruped.yaml");
  REQUIRE(printed.frames.size() == urdf.frames.size());
  REQUIRE(printed.parameters.size() == urdf.parameters.size());
  for (std::size_t k = 0; k < urdf.parameters.size(); ++k) {
    CHECK(printed.parameters[k].name == urdf.parameters[k].name);
    CHECK(printed.parameters[k].default_value == urdf.parameters[k].default_value);
  }
  std::map<std::string, double> s;
  for (const auto& c : urdf.coordinates) s[c.name] = 0.1 * (c.index % 7) - 0.3;
  const Evaluator a(printed, s), b(urdf, s);
  for (std::size_t k = 0; k < urdf.frames.size(); ++k) {
    CHECK(printed.frames[k].name == urdf.frames[k].name);
    CHECK((a.vec(printed.frames[k].frame.r) - b.vec(urdf.frames[k].frame.r)).norm() == 0);
  }
  // The drives keep the URDF joints' names without the URDF.
  REQUIRE(printed.dynamics->actuated.size() == urdf.dynamics->actuated.size());
  for (std::size_t k = 0; k < urdf.dynamics->actuated.size(); ++k) {
    CHECK(printed.dynamics->actuated[k].name == urdf.dynamics->actuated[k].name);
    CHECK(printed.dynamics->actuated[k].wheel == urdf.dynamics->actuated[k].wheel);
  }
}

// What the quadruped does not have, against transforms composed here from the URDF's numbers.
TEST_CASE("URDF import: oblique axes, prismatic joints, chains of fixed links and turned inertials") {
  const fs::path dir = scratch();
  std::ofstream(dir / "arm.urdf") << R"(<?xml version="1.0"?>
<robot name="arm">
  <link name="world"/>
  <joint name="mount" type="fixed">
    <parent link="world"/><child link="base-link"/>
    <origin xyz="0 0 0.1" rpy="0 0 0.3"/>
  </joint>
  <link name="base-link">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="base-link"/><child link="carriage"/>
    <origin xyz="0.1 0 0.05"/><axis xyz="0 0 1"/><limit lower="0" upper="0.5" effort="100" velocity="1"/>
  </joint>
  <link name="carriage">
    <inertial>
      <origin xyz="0.01 0.02 0.03" rpy="0.1 0.2 0.3"/><mass value="2"/>
      <inertia ixx="0.01" ixy="0.001" ixz="0" iyy="0.02" iyz="0.0005" izz="0.03"/>
    </inertial>
  </link>
  <joint name="tilt" type="revolute">
    <parent link="carriage"/><child link="arm"/>
    <origin xyz="0 0.2 0" rpy="0.4 -0.2 0.1"/><axis xyz="0.6 0 0.8"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
  <link name="arm">
    <inertial><origin xyz="0.2 0 0"/><mass value="1.5"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <visual><geometry><mesh filename="package://arm/arm.stl"/></geometry></visual>
  </link>
  <joint name="flange_joint" type="fixed">
    <parent link="arm"/><child link="flange"/><origin xyz="0.4 0 0" rpy="0 1.5707963267948966 0"/>
  </joint>
  <link name="flange">
    <inertial><origin xyz="0 0 0.02"/><mass value="0.5"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.0005"/></inertial>
  </link>
  <joint name="tool_joint" type="fixed">
    <parent link="flange"/><child link="tool"/><origin xyz="0 0 0.05"/>
  </joint>
  <link name="tool">
    <inertial><origin xyz="0 0 0.03" rpy="0.5 0 0"/><mass value="0.25"/><inertia ixx="0.0002" ixy="0" ixz="0" iyy="0.0003" iyz="0" izz="0.0001"/></inertial>
  </link>
  <joint name="spin" type="continuous">
    <parent link="tool"/><child link="marker"/><origin xyz="0 0 0.1"/><axis xyz="0 0 -1"/>
  </joint>
  <link name="marker"/>
</robot>
)";
  const std::string yaml = R"(model: urdf_arm
urdf: arm.urdf
rename: {base-link: base_link@}
parameters:
  - {name: g, value: 9.81, unit: m/s^2, kind: gravity}
coordinates:
  inputs:
    - {name: slide, unit: m}
    - {name: tilt, unit: rad}
    - {name: wrist, unit: rad}
dynamics: {gravity: g, commanded: [slide, tilt], actuated: [slide, tilt]}
)";
  // The URDF's joint `spin` is a name the generated code uses itself: refused, with the rename.
  std::ofstream(dir / "arm.yaml") << yaml.substr(0, yaml.find('@')) + yaml.substr(yaml.find('@') + 1);
  CHECK_THROWS_WITH_AS(load_model_file((dir / "arm.yaml").string()),
                       "arm.urdf:42: joint 'spin': 'spin' cannot name a coordinate: the generated functions use that name "
                       "themselves; rename it in the URDF, or in arm.yaml: `rename: {\"spin\": spin_joint}`",
                       ModelFileError);
  std::ofstream(dir / "arm.yaml") << yaml.substr(0, yaml.find('@')) + ", spin: wrist" + yaml.substr(yaml.find('@') + 1);
  const Model m = load_model_file((dir / "arm.yaml").string());
  CHECK(m.coordinates.size() == 3);
  CHECK(m.input_count == 3);
  const double slide = 0.23, tilt = -0.7;
  const double spin = 0.4;
  const Evaluator e(m, {{"slide", slide}, {"tilt", tilt}, {"wrist", spin}});
  using Eigen::AngleAxisd;
  using Eigen::Vector3d;
  const auto rpy = [](double r, double p, double y) {
    return (AngleAxisd(y, Vector3d::UnitZ()) * AngleAxisd(p, Vector3d::UnitY()) * AngleAxisd(r, Vector3d::UnitX())).toRotationMatrix();
  };
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity(), carriage, arm, flange, tool;
  base.translate(Vector3d(0, 0, 0.1)).rotate(rpy(0, 0, 0.3));
  carriage = base * Eigen::Translation3d(0.1, 0, 0.05) * Eigen::Translation3d(0, 0, slide);
  arm = carriage * Eigen::Translation3d(0, 0.2, 0) * Eigen::Isometry3d(rpy(0.4, -0.2, 0.1)) *
        Eigen::Isometry3d(AngleAxisd(tilt, Vector3d(0.6, 0, 0.8)));
  flange = arm * Eigen::Translation3d(0.4, 0, 0) * Eigen::Isometry3d(rpy(0, M_PI / 2, 0));
  tool = flange * Eigen::Translation3d(0, 0, 0.05);
  const Eigen::Isometry3d marker = tool * Eigen::Translation3d(0, 0, 0.1) * Eigen::Isometry3d(AngleAxisd(spin, -Vector3d::UnitZ()));
  for (const auto& entry : std::vector<std::pair<std::string, Eigen::Isometry3d>>{
           {"base_link", base}, {"carriage", carriage}, {"arm", arm}, {"flange", flange}, {"tool", tool}, {"marker", marker}}) {
    // Not a structured binding: clang 14 cannot capture one in CAPTURE's lambda.
    const std::string& name = entry.first;
    const Eigen::Isometry3d& pose = entry.second;
    CAPTURE(name);
    REQUIRE(m.frame_index(name) >= 0);
    const Frame& f = m.frames[static_cast<std::size_t>(m.frame_index(name))].frame;
    CHECK((e.vec(f.r) - pose.translation()).cwiseAbs().maxCoeff() < 1e-14);
    CHECK((e.mat(f.R) - pose.rotation()).cwiseAbs().maxCoeff() < 1e-14);
  }
  // The arm, the flange and the tool are one rigid body: masses add, the tensors move to the
  // common centre of mass by the parallel-axis theorem, here in K0.
  struct Part {
    Eigen::Isometry3d link;
    double mass;
    Vector3d com;
    Eigen::Matrix3d rotation, inertia;
  };
  const std::vector<Part> parts = {
      {arm, 1.5, {0.2, 0, 0}, Eigen::Matrix3d::Identity(), Vector3d(0.001, 0.02, 0.02).asDiagonal()},
      {flange, 0.5, {0, 0, 0.02}, Eigen::Matrix3d::Identity(), Vector3d(0.001, 0.001, 0.0005).asDiagonal()},
      {tool, 0.25, {0, 0, 0.03}, rpy(0.5, 0, 0), Vector3d(0.0002, 0.0003, 0.0001).asDiagonal()}};
  double mass = 0;
  Vector3d moment = Vector3d::Zero();
  for (const auto& p : parts) mass += p.mass, moment += p.mass * (p.link * p.com);
  const Vector3d com = moment / mass;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const auto& p : parts) {
    const Eigen::Matrix3d R = p.link.rotation() * p.rotation;
    const Vector3d d = p.link * p.com - com;
    inertia += R * p.inertia * R.transpose() + p.mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  const Body& merged = body(m, "arm");
  CHECK(e.parameter(merged.mass) == doctest::Approx(2.25).epsilon(1e-15));
  CHECK((e.vec(merged.com_frame.r) - com).cwiseAbs().maxCoeff() < 1e-14);
  CHECK((e.inertia(merged) - inertia).cwiseAbs().maxCoeff() < 1e-15);
  // A full tensor turned against its link: diagonalised, the same tensor in K0.
  const Body& c = body(m, "carriage");
  const Eigen::Matrix3d Rc = carriage.rotation() * rpy(0.1, 0.2, 0.3);
  Eigen::Matrix3d J;
  J << 0.01, 0.001, 0, 0.001, 0.02, 0.0005, 0, 0.0005, 0.03;
  CHECK((e.inertia(c) - Rc * J * Rc.transpose()).cwiseAbs().maxCoeff() < 1e-15);
  CHECK((e.vec(c.com_frame.r) - carriage * Vector3d(0.01, 0.02, 0.03)).cwiseAbs().maxCoeff() < 1e-14);
  // The massless world and the base fixed to it: one body, named after the group's first link;
  // the massless marker on its own joint: none.
  CHECK(e.parameter(body(m, "world").mass) == 1);
  CHECK(m.bodies.size() == 3);
}


TEST_CASE("URDF import: a wheel without `radius` rolls on its hub's collision cylinder, its plane where the cylinder's centre is") {
  const fs::path dir = scratch() / "wheel_shapes";
  fs::create_directories(dir);
  std::ifstream yaml_in(kModels + "/wheeled_quadruped.yaml"), urdf_in(kModels + "/wheeled_quadruped.urdf");
  std::stringstream yaml_text, urdf_text;
  yaml_text << yaml_in.rdbuf();
  urdf_text << urdf_in.rdbuf();
  std::string yaml = yaml_text.str(), urdf = urdf_text.str();
  const std::string with_radius = "axle: y, radius: wheel_radius, ground:";
  REQUIRE(yaml.find(with_radius) != std::string::npos);
  yaml.replace(yaml.find(with_radius), with_radius.size(), "axle: y, ground:");
  // The left front wheel's cylinder 6 cm out along its axle (y of the hub), as real wheels sit.
  const std::string centred = "<origin xyz=\"0 0 0\" rpy=\"1.5707963267948966 0 0\"/>";
  REQUIRE(urdf.find(centred) != std::string::npos);
  std::string moved = urdf;
  moved.replace(moved.find(centred), centred.size(), "<origin xyz=\"0 0.06 0\" rpy=\"1.5707963267948966 0 0\"/>");
  std::ofstream(dir / "robot.yaml") << yaml;
  std::ofstream(dir / "robot.urdf") << moved;
  const Model m = load_model_file((dir / "robot.yaml").string(), (dir / "robot.urdf").string());
  REQUIRE(m.wheels.size() == 4);
  CHECK(m.wheels[0].radius == "wheel_lf_radius");
  CHECK(m.wheels[0].offset == "wheel_lf_offset");
  CHECK(m.parameter("wheel_lf_radius").default_value == 0.1);
  CHECK(m.parameter("wheel_lf_offset").default_value == 0.06);
  CHECK(m.parameter("wheel_rf_offset").default_value == 0);
  // At a pose with tilted legs, the contact point is the hub's centre, moved along the axle a by the
  // offset, then down the wheel's plane by the radius: c = h + d a - r u (u: up in the wheel's plane).
  const Evaluator e(m, {{"z_B", 0.5}, {"roll", 0.2}, {"haa_lf", 0.1}, {"hfe_lf", 0.4}, {"kfe_lf", -0.9}});
  for (const auto& [wheel, d] : {std::pair{0, 0.06}, std::pair{1, 0.0}}) {
    const NonholonomicWheel& w = m.wheels[static_cast<std::size_t>(wheel)];
    CAPTURE(w.name);
    const Frame& hub = m.frames[static_cast<std::size_t>(m.frame_index(w.hub))].frame;
    const Frame& contact = m.frames[static_cast<std::size_t>(m.frame_index(w.contact))].frame;
    const Eigen::Vector3d h = e.vec(hub.r), a = e.mat(hub.R).col(1);
    const Eigen::Vector3d up = (Eigen::Vector3d::UnitZ() - a.z() * a).normalized();
    CHECK((e.vec(contact.r) - (h + d * a - 0.1 * up)).cwiseAbs().maxCoeff() < 1e-14);
  }
  // A cylinder across the axle gives no radius; a wheel link with a mesh only has none: named, with what to do.
  std::string across = urdf;
  across.replace(across.find(centred), centred.size(), "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>");
  std::ofstream(dir / "robot.urdf") << across;
  CHECK_THROWS_WITH_AS(load_model_file((dir / "robot.yaml").string(), (dir / "robot.urdf").string()),
                       doctest::Contains("robot.urdf:151: link 'wheel_lf' collision: the cylinder's axis (0, 0, 1) is not the wheel's axle (y of the link)"),
                       ModelFileError);
  std::string mesh_only = urdf;
  const auto at = mesh_only.find("<collision>", mesh_only.find("<link name=\"wheel_lf\">"));
  mesh_only.replace(at, mesh_only.find("</collision>", at) + 12 - at, "");
  std::ofstream(dir / "robot.urdf") << mesh_only;
  CHECK_THROWS_WITH_AS(load_model_file((dir / "robot.yaml").string(), (dir / "robot.urdf").string()),
                       doctest::Contains("the wheel on 'wheel_lf' has no `radius`, and the URDF's link 'wheel_lf' has no collision cylinder or "
                                         "sphere to read one from (a mesh has none): give `radius: PARAMETER`"),
                       ModelFileError);
  // A wheel's own `radius` and `offset` (any model file, with or without a URDF): the shape then unused.
  std::string own = yaml;
  own.replace(own.find("axle: y, ground:"), 16, "axle: y, radius: wheel_radius, offset: hub_shift, ground:");
  const std::string g = "  - {name: g,";
  REQUIRE(own.find(g) != std::string::npos);
  own.replace(own.find(g), 0, "  - {name: hub_shift, value: -0.05, unit: m, kind: offset, meaning: the rolling plane inwards}\n");
  std::ofstream(dir / "own.yaml") << own;
  std::ofstream(dir / "robot.urdf") << moved;
  const Model m2 = load_model_file((dir / "own.yaml").string(), (dir / "robot.urdf").string());
  CHECK(m2.wheels[0].radius == "wheel_radius");
  CHECK(m2.wheels[0].offset == "hub_shift");
  CHECK_THROWS(m2.parameter("wheel_lf_offset"));
  {
    const Evaluator e2(m2, {{"z_B", 0.5}, {"roll", 0.2}, {"haa_lf", 0.1}, {"hfe_lf", 0.4}, {"kfe_lf", -0.9}});
    const NonholonomicWheel& w = m2.wheels[0];
    const Frame& hub = m2.frames[static_cast<std::size_t>(m2.frame_index(w.hub))].frame;
    const Frame& contact = m2.frames[static_cast<std::size_t>(m2.frame_index(w.contact))].frame;
    const Eigen::Vector3d h = e2.vec(hub.r), a = e2.mat(hub.R).col(1);
    const Eigen::Vector3d up = (Eigen::Vector3d::UnitZ() - a.z() * a).normalized();
    CHECK((e2.vec(contact.r) - (h - 0.05 * a - 0.1 * up)).cwiseAbs().maxCoeff() < 1e-14);
  }
  // --print-model writes the read radius and offset as parameters the wheels name: it reads alone.
  std::ofstream(dir / "robot.urdf") << moved;
  std::ofstream(dir / "printed.yaml") << print_model_file((dir / "robot.yaml").string(), (dir / "robot.urdf").string());
  const Model printed = load_model_file((dir / "printed.yaml").string());
  CHECK(printed.wheels[0].offset == "wheel_lf_offset");
  CHECK(printed.parameter("wheel_lf_offset").default_value == 0.06);
  // ... and the joints' limits and the actuators' torque limits the URDF gave (the drives' efforts
  // are its wheel joints', which the printed file does not have).
  REQUIRE(printed.lower.size() == m.lower.size());
  for (std::size_t k = 0; k < m.lower.size(); ++k) {
    CAPTURE(m.coordinates[k].name);
    CHECK(printed.lower[k] == m.lower[k]);
    CHECK(printed.upper[k] == m.upper[k]);
    CHECK(printed.effort[k] == m.effort[k]);
    CHECK(printed.velocity[k] == m.velocity[k]);
  }
  const auto kfe_lf = static_cast<std::size_t>(&m.coordinate("kfe_lf") - m.coordinates.data());
  CHECK(printed.lower[kfe_lf] == -2.8);
  REQUIRE(printed.dynamics);
  CHECK(printed.dynamics->torque_limits == m.dynamics->torque_limits);
  CHECK(printed.dynamics->torque_limits.back() == 40);
}

TEST_CASE("URDF import: text that is not UTF-8 is refused at its line before an XML parser reads it") {
  const std::string head = "<robot name=\"r\">\n  <link name=\"base\"/>\n";
  // A multi-byte sequence cut short by the end of the file: TinyXML would step past the buffer's
  // end (fuzz_urdf's finding); a byte no UTF-8 has; a NUL, which would end TinyXML's reading early.
  const std::pair<std::string, std::string> cases[] = {
      {head + "</robot>\n<!-- \xE2", "r.urdf:4: XML: bytes that are not UTF-8 at byte 6 of the line"},
      {head + "  <link name=\"b\xFF\"/>\n</robot>\n", "r.urdf:3: XML: bytes that are not UTF-8 at byte 16 of the line"},
      {head + std::string("</robot>\0<robot/>", 18), "r.urdf:3: XML: a NUL byte at byte 9 of the line"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.second);
    CHECK_THROWS_WITH_AS(read_urdf_text(c.first, "r.urdf"), doctest::Contains(c.second.c_str()), ModelFileError);
  }
  // Well-formed UTF-8 beyond ASCII (a comment, a robot name) reads.
  const UrdfRobot robot = read_urdf_text("<robot name=\"r\xC3\xB6\">\n  <!-- \xE2\x86\x92 -->\n  <link name=\"base\"/>\n</robot>\n", "r.urdf");
  CHECK(robot.links.size() == 1);
}

// tests/models/big_wheeled: an outside-style robot of CENTAURO's kind (written apart from the
// importer: four legs of six joints and a wheel, a torso yaw, two arms of seven; 43 moving
// joints, 115 kg), the size issue "Edit your robot and see the result in seconds" measures first
// use on. Its URDF read here by a plain scan of the text, independently of urdfdom and the importer.
TEST_CASE("URDF import: a 43-joint wheeled-legged robot: every moving joint a coordinate, every kilogram a body's") {
  std::ifstream in(kTestModels + "/big_wheeled/big_wheeled.urdf");
  std::ostringstream text;
  text << in.rdbuf();
  const std::string urdf = text.str();
  REQUIRE(!urdf.empty());
  int moving = 0, wheels = 0;
  double mass = 0;
  for (std::size_t at = 0; (at = urdf.find("<joint name=", at)) != std::string::npos; ++at) {
    const std::string tag = urdf.substr(at, urdf.find('>', at) - at);
    moving += tag.find("type=\"revolute\"") != std::string::npos || tag.find("type=\"continuous\"") != std::string::npos;
    wheels += tag.find("type=\"continuous\"") != std::string::npos;
  }
  for (std::size_t at = 0; (at = urdf.find("<mass value=\"", at)) != std::string::npos; ++at) mass += std::stod(urdf.substr(at + 13));
  REQUIRE(moving == 43);
  REQUIRE(wheels == 4);
  const Model m = load_model_file(kTestModels + "/big_wheeled/big_wheeled.yaml");
  // The floating base's six coordinates and the contact targets are the file's own inputs; every
  // moving joint but the wheels' (whose spins are no coordinates) is one coordinate.
  const int base_and_targets = 6 + 4 * 3;
  CHECK(static_cast<int>(m.coordinates.size()) == base_and_targets + moving - wheels);
  CHECK(m.wheels.size() == 4);
  CHECK(m.limbs.size() == 4);
  double bodies = 0;
  for (const Body& b : m.bodies) bodies += m.parameter(b.mass).default_value;
  CHECK(std::abs(bodies - mass) <= 1e-12 * mass);
  CHECK(std::abs(mass - 115.0) <= 1e-9);
}

#else

TEST_CASE("URDF import: without liburdfdom a URDF is refused with a message that says so") {
  CHECK(!urdf_import_available());
  CHECK_THROWS_WITH_AS(load_model_file(kModels + "/wheeled_quadruped.yaml"), doctest::Contains("URDF import is unavailable"),
                       ModelFileError);
}

#endif
