// The walking excavator (MODEL.md sections 1-4 and 6), written in the generator's vocabulary.
// This file is the single source of truth for names, geometry and mass values: the emitted
// params.hpp carries them to the runtime, the CLI and the tests.
#include "model.hpp"

#include <stdexcept>

namespace wlx::gen {

namespace {

struct Builder {
  Model m;

  ex param(const std::string& name, double value, const std::string& unit, const std::string& meaning) {
    m.parameters.push_back({name, value, unit, meaning, GiNaC::realsymbol(name)});
    return m.parameters.back().symbol;
  }
  void coordinate(const std::string& name, const std::string& unit, const std::string& meaning) {
    const int index = static_cast<int>(m.coordinates.size());
    m.coordinates.push_back(
        {name, index, GiNaC::realsymbol(name), GiNaC::realsymbol(name + "_dot"), unit, meaning});
  }
  const Coordinate& c(const std::string& name) const { return m.coordinate(name); }
  const Frame& frame(const std::string& name, const std::string& meaning, Frame f) {
    m.frames.push_back({name, meaning, std::move(f)});
    return m.frames.back().frame;
  }
};

}  // namespace

Model make_excavator_model() {
  Builder b;
  b.m.name = "excavator";
  b.m.source = "generator/excavator_model.cpp (MODEL.md sections 1-4, 6)";
  b.m.frames.reserve(16);

  // Geometry (thesis Table 3-1).
  const ex cxd = b.param("cxd", 3.0, "m", "cabin length between front hips and rear hips");
  const ex cyd = b.param("cyd", 3.0, "m", "cabin width between left and right hips");
  const ex thighD = b.param("thighD", 2.0, "m", "hip-to-knee length of a leg");
  const ex legD = b.param("legD", 1.5, "m", "knee-to-foot length of a leg");
  const ex wl = b.param("wl", 2.5, "m", "wheel lever length");
  b.param("w", 0.5, "m", "wheel radius: hub to contact point");
  const ex w = b.m.parameters.back().symbol;
  // The cabin is a cxd x cyd x cabin_height block centred on K_C (thesis 6.2.1); only the
  // ground-clearance check uses its height.
  b.param("cabin_height", 0.5, "m", "height of the cabin block centred on the cabin frame");
  // Mass properties (thesis Table 6-1): mass and principal inertia about the CoM.
  const struct { const char* body; double mass; double Ixx, Iyy, Izz; const char* what; } masses[] = {
      {"M1", 5400.0, 4090.5, 4090.5, 8100.0, "cabin"},
      {"M2", 125.66, 0.63, 42.20, 42.20, "right thigh"},
      {"M3", 125.66, 0.63, 42.20, 42.20, "left thigh"},
      {"M4", 94.25, 0.47, 17.91, 17.91, "right shank"},
      {"M5", 94.25, 0.47, 17.91, 17.91, "left shank"},
      {"M6", 157.08, 0.79, 82.21, 82.21, "left lever and wheel"},
      {"M7", 157.08, 0.79, 82.21, 82.21, "right lever and wheel"},
  };
  for (const auto& mp : masses) {
    const std::string body = mp.body;
    b.param("m_" + body, mp.mass, "kg", std::string("mass of the ") + mp.what);
    b.param("Ixx_" + body, mp.Ixx, "kg*m^2", std::string("inertia of the ") + mp.what + " about its CoM, body x");
    b.param("Iyy_" + body, mp.Iyy, "kg*m^2", std::string("inertia of the ") + mp.what + " about its CoM, body y");
    b.param("Izz_" + body, mp.Izz, "kg*m^2", std::string("inertia of the ") + mp.what + " about its CoM, body z");
  }
  b.param("g", 9.81, "m/s^2", "gravity, along -z of K0");

  // The 18 independent inputs q (thesis eq. 3.2), then the 14 dependent joints.
  b.coordinate("x_C", "m", "cabin position x in K0");
  b.coordinate("y_C", "m", "cabin position y in K0");
  b.coordinate("z_C", "m", "cabin position z in K0");
  b.coordinate("yaw", "rad", "cabin yaw, R_C = Rz(yaw) Ry(pitch) Rx(roll)");
  b.coordinate("pitch", "rad", "cabin pitch");
  b.coordinate("roll", "rad", "cabin roll");
  for (const char* side : {"l", "r"})
    for (const char* axis : {"x", "y", "z"})
      b.coordinate(std::string(axis) + "_F" + side, "m", std::string("foot position ") + axis + " in K0");
  b.coordinate("z_Wl", "m", "ground level under the left wheel");
  b.coordinate("z_Wr", "m", "ground level under the right wheel");
  b.coordinate("psi_l1", "rad", "left hip roll joint");
  b.coordinate("psi_r1", "rad", "right hip roll joint");
  b.coordinate("theta_l5", "rad", "left lever straddle joint");
  b.coordinate("theta_r5", "rad", "right lever straddle joint");
  b.m.input_count = static_cast<int>(b.m.coordinates.size());
  for (const char* side : {"l", "r"}) {
    b.coordinate(std::string("psi_") + side + "2", "rad", "hip pitch joint");
    b.coordinate(std::string("psi_") + side + "3", "rad", "hip yaw joint");
    b.coordinate(std::string("psi_") + side + "4", "rad", "knee joint");
  }
  for (const char* side : {"l", "r"}) {
    b.coordinate(std::string("theta_") + side + "2", "rad", "wheel camber about the contact line");
    b.coordinate(std::string("theta_") + side + "3", "rad", "hub axis joint");
    b.coordinate(std::string("theta_") + side + "4", "rad", "parallel guidance joint");
    b.coordinate(std::string("theta_") + side + "6", "rad", "lever pitch joint");
  }

  // Cabin: prismatic along the K0 axes, then R_C = Rz(yaw) Ry(pitch) Rx(roll).
  const Frame& cabin = b.frame("C", "cabin frame K_C (origin r_C)",
                               Frame::ground()
                                   .slid(Axis::X, b.c("x_C"))
                                   .slid(Axis::Y, b.c("y_C"))
                                   .slid(Axis::Z, b.c("z_C"))
                                   .rotated(Axis::Z, b.c("yaw"))
                                   .rotated(Axis::Y, b.c("pitch"))
                                   .rotated(Axis::X, b.c("roll")));

  for (const auto& [side, sign] : {std::pair{"l", 1}, std::pair{"r", -1}}) {
    const std::string s = side;
    // Front leg: hip R_hip = Rx(psi_1) Ry(psi_2) Rz(psi_3), knee Ry(psi_4) (thesis eqs. 3.4-3.11).
    const Frame hip_joint = cabin.translated({cxd / 2, sign * cyd / 2, 0});
    const Frame& hip = b.frame("hip_" + s, "leg hip, orientation R_C R_hip",
                               hip_joint.rotated(Axis::X, b.c("psi_" + s + "1"))
                                   .rotated(Axis::Y, b.c("psi_" + s + "2"))
                                   .rotated(Axis::Z, b.c("psi_" + s + "3")));
    const Frame& knee = b.frame("knee_" + s, "knee, orientation R_C R_hip Ry(psi_4)",
                                hip.translated({thighD, 0, 0}).rotated(Axis::Y, b.c("psi_" + s + "4")));
    b.frame("F_" + s, "foot (end of the shank)", knee.translated({legD, 0, 0}));
  }
  for (const auto& [side, sign] : {std::pair{"l", 1}, std::pair{"r", -1}}) {
    const std::string s = side;
    // Rear wheel lever: R_lev = Ry(theta_6) Rz(theta_5), R_10 = R_lev Rz(theta_4) Ry(theta_3),
    // R_W = R_10 Rx(theta_2) (thesis eqs. 3.20-3.28).
    const Frame& lever = b.frame("lever_hip_" + s, "lever hip, orientation R_C R_lev",
                                 cabin.translated({-cxd / 2, sign * cyd / 2, 0})
                                     .rotated(Axis::Y, b.c("theta_" + s + "6"))
                                     .rotated(Axis::Z, b.c("theta_" + s + "5")));
    const Frame& hub = b.frame("lever_end_" + s, "lever end (wheel hub), orientation R_C R_10",
                               lever.translated({-wl, 0, 0})
                                   .rotated(Axis::Z, b.c("theta_" + s + "4"))
                                   .rotated(Axis::Y, b.c("theta_" + s + "3")));
    b.frame("W_" + s, "wheel contact frame K_W, orientation R_C R_W",
            hub.translated({0, 0, -w}).rotated(Axis::X, b.c("theta_" + s + "2")));
  }

  // Bodies (thesis 6.2): CoM frames.
  const auto body = [&](const std::string& name, const std::string& meaning, const Frame& f, const Vec3& com) {
    b.m.bodies.push_back({name, meaning, f.translated(com), "m_" + name,
                          {"Ixx_" + name, "Iyy_" + name, "Izz_" + name}});
  };
  body("M1", "cabin", cabin, {0, 0, 0});
  body("M2", "right thigh", b.m.frame("hip_r"), {thighD / 2, 0, 0});
  body("M3", "left thigh", b.m.frame("hip_l"), {thighD / 2, 0, 0});
  body("M4", "right shank", b.m.frame("knee_r"), {legD / 2, 0, 0});
  body("M5", "left shank", b.m.frame("knee_l"), {legD / 2, 0, 0});
  body("M6", "left lever and wheel", b.m.frame("lever_hip_l"), {-wl / 2, 0, 0});
  body("M7", "right lever and wheel", b.m.frame("lever_hip_r"), {-wl / 2, 0, 0});

  // Loop closure (MODEL.md section 4): 14 conditions, ordered like the dependent joints.
  using K = ClosureCondition::Kind;
  const auto idx = [&](const std::string& n) { return b.m.coordinate(n).index; };
  for (const char* side : {"l", "r"}) {
    const std::string s = side;
    for (const auto& [axis, a] : {std::pair{"x", Axis::X}, std::pair{"y", Axis::Y}, std::pair{"z", Axis::Z}})
      b.m.closure.push_back({std::string("foot_") + axis + "_" + s, K::PointEqualsCoordinate, "F_" + s, a,
                             idx(std::string(axis) + "_F" + s), {}});
  }
  for (const char* side : {"l", "r"}) {
    const std::string s = side;
    b.m.closure.push_back({"contact_z_" + s, K::PointEqualsCoordinate, "W_" + s, Axis::Z, idx("z_W" + s), {}});
    b.m.closure.push_back({"level_x_" + s, K::AttachedDirectionLevel, "W_" + s, Axis::X, -1, {}});
    b.m.closure.push_back({"level_y_" + s, K::AttachedDirectionLevel, "W_" + s, Axis::Y, -1, {}});
    b.m.closure.push_back({"guidance_" + s, K::CoordinateSum, "", Axis::X, -1,
                           {idx("theta_" + s + "4"), idx("theta_" + s + "5")}});
  }

  // Non-holonomic wheels (MODEL.md section 5).
  b.m.wheels.push_back({"l", "W_l", Axis::Y, Axis::X, "w"});
  b.m.wheels.push_back({"r", "W_r", Axis::Y, Axis::X, "w"});
  return std::move(b.m);
}

const Parameter& Model::parameter(const std::string& n) const {
  for (const auto& p : parameters)
    if (p.name == n) return p;
  throw std::out_of_range("model has no parameter '" + n + "'");
}
const Coordinate& Model::coordinate(const std::string& n) const {
  for (const auto& c : coordinates)
    if (c.name == n) return c;
  throw std::out_of_range("model has no coordinate '" + n + "'");
}
const Frame& Model::frame(const std::string& n) const {
  for (const auto& f : frames)
    if (f.name == n) return f.frame;
  throw std::out_of_range("model has no frame '" + n + "'");
}

}  // namespace wlx::gen
