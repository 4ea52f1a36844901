// The closed-form IK's patterns match on geometry, not on how a file is written (docs/
// architecture.md, "Canonical chains"): the canonical chain of the quadruped's leg is the one the
// document shows, rewordings of a chain (zero offsets, split offsets, an offset moved along the
// joint axis it commutes with) give the same canonical chain and the same pattern, and a limb that
// matches nothing is told which precondition failed.
#include "../../generator/emit.hpp"
#include "../../generator/model_file.hpp"

#include <doctest/doctest.h>

#include <fstream>
#include <sstream>

using namespace wlx::codegen;

namespace {

std::string text_of(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string replaced(std::string text, const std::string& find, const std::string& by) {
  const auto at = text.find(find);
  REQUIRE(at != std::string::npos);
  return text.replace(at, find.size(), by);
}

// wlx-gen's report line for the limb: "<limb>: <pattern>: ..." or "<limb>: no closed form (...)".
std::string ik_line(const Model& m, const std::string& limb) {
  std::vector<std::string> report;
  emit_ik_header(m, EmitOptions{}, report);
  for (const auto& line : report)
    if (line.rfind(limb + ": ", 0) == 0) return line;
  FAIL("no report line for " << limb);
  return {};
}

bool same(const ex& a, const ex& b) { return (a - b).expand().is_zero(); }

// The same chain in two models read from two files (each reading makes its own symbols: b's are
// renamed to a's by name).
void check_same_chain(const Model& ma, const std::vector<ChainStep>& a, const Model& mb, const std::vector<ChainStep>& b) {
  GiNaC::exmap rename;
  for (const Parameter& p : mb.parameters) rename[p.symbol] = ma.parameter(p.name).symbol;
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    CAPTURE(i);
    CHECK(a[i].kind == b[i].kind);
    CHECK(a[i].axis == b[i].axis);
    CHECK(a[i].coordinate == b[i].coordinate);
    CHECK(a[i].sign == b[i].sign);
    for (int k = 0; k < 3; ++k) CHECK(same(a[i].offset[k], b[i].offset[k].subs(rename)));
    CHECK(same(a[i].angle, b[i].angle.subs(rename)));
  }
}

}  // namespace

TEST_CASE("IK patterns: the quadruped's leg in canonical form, offsets gathered along the axes they commute with") {
  const Model m = load_model_file(WLX_QUADRUPED_FILE);
  const auto sym = [&](const char* n) { return ex(m.parameter(n).symbol); };
  const std::vector<ChainStep> c = canonical_ik_chain(m, "hub_lf");
  using K = ChainStep::Kind;
  REQUIRE(c.size() == 7);
  const K kinds[] = {K::Translate, K::Rotate, K::Translate, K::Rotate, K::Translate, K::Rotate, K::Translate};
  for (std::size_t i = 0; i < 7; ++i) CHECK(c[i].kind == kinds[i]);
  CHECK(c[1].coordinate == m.coordinate("haa_lf").index);
  CHECK(c[1].axis == Axis::X);
  CHECK(c[3].coordinate == m.coordinate("hfe_lf").index);
  CHECK(c[5].coordinate == m.coordinate("kfe_lf").index);
  const Vec3 expected[] = {{sym("flex_x"), 0, 0},
                           {0, sym("flex_y") + sym("knee_y") + sym("hub_y"), 0},
                           {0, 0, -sym("thigh")},
                           {sym("hub_x"), 0, -sym("shank")}};
  for (int g = 0; g < 4; ++g)
    for (int k = 0; k < 3; ++k) CHECK(same(c[static_cast<std::size_t>(2 * g)].offset[k], expected[g][k]));
  // The right legs' joints about -y keep their sign.
  const std::vector<ChainStep> right = canonical_ik_chain(m, "hub_rf");
  REQUIRE(right.size() == 7);
  CHECK(right[1].sign == 1);
  CHECK(right[3].sign == -1);
  CHECK(right[5].sign == -1);
  CHECK(ik_line(m, "leg_lf").rfind("leg_lf: wheel leg: ", 0) == 0);
  CHECK(ik_line(m, "leg_rh").rfind("leg_rh: wheel leg: ", 0) == 0);
}

TEST_CASE("IK patterns: rewording a chain changes neither its canonical form nor its pattern") {
  const std::string original = text_of(WLX_QUADRUPED_FILE);
  const Model base = parse_model(original, "quadruped.yaml");
  // Zero offsets and an offset split over three steps; the wheel-plane offset written before the
  // knee instead of after it (along the knee axis: the same geometry).
  std::string reworded = replaced(original, "chain: [translate: [<sx>*flex_x, <sy>*flex_y, 0], ry: <sy>*hfe_<leg>]",
                                  "chain: [translate: [0, 0, 0], translate: [<sx>*flex_x, 0, 0], translate: [0, <sy>*flex_y, 0], "
                                  "ry: <sy>*hfe_<leg>, translate: [0, 0, 0]]");
  reworded = replaced(reworded, "chain: [translate: [0, <sy>*knee_y, -thigh], ry: <sy>*kfe_<leg>]",
                      "chain: [translate: [0, <sy>*knee_y + <sy>*hub_y, -thigh], ry: <sy>*kfe_<leg>]");
  reworded = replaced(reworded, "chain: [translate: [hub_x, <sy>*hub_y, -shank]]", "chain: [translate: [hub_x, 0, -shank]]");
  const Model m = parse_model(reworded, "reworded.yaml");
  for (const char* hub : {"hub_lf", "hub_rh"}) {
    CAPTURE(hub);
    check_same_chain(m, canonical_ik_chain(m, hub), base, canonical_ik_chain(base, hub));
  }
  // The same pattern and solve (the operation count, after the branch count, may differ by a few:
  // the two readings' symbols order GiNaC's sums differently, and so the common subexpressions).
  const auto solve_of = [](const std::string& line) { return line.substr(0, line.find(" (4 branches")); };
  CHECK(solve_of(ik_line(m, "leg_lf")) == solve_of(ik_line(base, "leg_lf")));
}

TEST_CASE("IK patterns: point3 tests whether the axes meet, whatever separates the joints in the file") {
  const std::string original = text_of(WLX_NEWTON_LEG_FILE);
  const std::string straight_knee = replaced(original, "rz: skew, ry: knee", "ry: knee");
  // As written, the flexion axis passes `drop` below the abduction axis: no point3, and the
  // report says which offset and what point3 needs.
  const std::string apart = ik_line(parse_model(original, "newton_leg.yaml"), "leg");
  CHECK(apart.find("no closed form") != std::string::npos);
  CHECK(apart.find("point3: the axes of abduct and flex do not meet") != std::string::npos);
  CHECK(apart.find("translate [0, 0, -drop]") != std::string::npos);
  CHECK(apart.find("goes after the second joint") != std::string::npos);  // what to change in the file
  CHECK(apart.find("plane leg: the axes of flex and knee are not parallel") != std::string::npos);
  // With the knee straight the leg is a plane leg (the first two axes need not meet there).
  CHECK(ik_line(parse_model(straight_knee, "plane.yaml"), "leg").rfind("leg: plane leg: ", 0) == 0);
  // `translate: [0, 0, 0]` between the first two joints, or an offset along the second joint's
  // axis: the axes meet, point3 (which comes first) solves the leg with the skewed knee too.
  for (const char* between : {"translate: [0, 0, 0]", "translate: [0, drop, 0]", "translate: [drop, 0, 0], translate: [0, drop, 0]"}) {
    CAPTURE(between);
    const std::string text = replaced(original, "chain: [translate: [0, 0, -drop], ry: flex]", std::string("chain: [") + between + ", ry: flex]");
    CHECK(ik_line(parse_model(text, "meeting.yaml"), "leg").rfind("leg: point3: ", 0) == 0);
  }
  // A turn between the first two joints about an axis of neither tilts the second axis.
  const std::string tilted = replaced(original, "chain: [translate: [0, 0, -drop], ry: flex]", "chain: [rz: skew, ry: flex]");
  const std::string tilted_line = ik_line(parse_model(tilted, "tilted.yaml"), "leg");
  CHECK(tilted_line.find("point3: between abduct and flex the chain turns (rz: skew)") != std::string::npos);
  // A limb with a row beyond a frame's x, y and z (the wheel arm's row joined to the leg): the
  // report names the rows the limb has, so that the extra one is seen.
  std::string joined = replaced(original, "closure: [foot_at_x, foot_at_y, foot_at_z], joints: [abduct, flex, knee]",
                                "closure: [foot_at_x, foot_at_y, foot_at_z, on_ground], joints: [abduct, flex, knee, swing]");
  joined = replaced(joined, "  - {name: wheel_arm, title: wheel arm, closure: [on_ground], joints: [swing]}\n", "");
  joined = replaced(joined, "limb: wheel_arm}", "limb: leg}");
  const std::string four = ik_line(parse_model(joined, "joined.yaml"), "leg");
  CHECK(four.find("point3 solves exactly three point rows (x, y and z of one frame); this limb has 4: foot_at_x, foot_at_y, "
                  "foot_at_z, on_ground") != std::string::npos);
}

#ifdef WLX_HAVE_URDF_TESTS
TEST_CASE("IK patterns: a steering leg (a hip, three parallel joints held by a sum row, then the inputs' joints and a wheel)") {
  // tests/models/big_wheeled: hip yaw, hip pitch, knee, ankle pitch (the sum row squares the
  // steering axis), then ankle yaw and roll (inputs) and the wheel. On its floating base, which
  // pitches and rolls, the hip yaw axis tilts: the rim point nearest the ground then moves with
  // the hip yaw's angle, and the pattern says so.
  const std::string path = WLX_BIG_WHEELED_FILE;
  const std::string original = text_of(path);
  const std::string directory = path.substr(0, path.rfind('/'));
  const Model tilting = parse_model(original, "big_wheeled.yaml", directory);
  const std::string refused = ik_line(tilting, "leg_lf");
  CHECK(refused.find("no closed form") != std::string::npos);
  CHECK(refused.find("steering leg: the axis of hip_yaw_lf is not vertical whatever the inputs (pitch, roll tilt it)") !=
        std::string::npos);
  CHECK(refused.find("for a wheel the pattern needs that axis vertical") != std::string::npos);
  // On a base that only yaws every leg is a steering leg.
  const std::string level_text = replaced(original, "chain: [tx: x_B, ty: y_B, tz: z_B, rz: yaw, ry: pitch, rx: roll]",
                                          "chain: [tx: x_B, ty: y_B, tz: z_B, rz: yaw]");
  const Model level = parse_model(level_text, "level.yaml", directory);
  for (const char* leg : {"leg_lf", "leg_rf", "leg_lh", "leg_rh"}) {
    CAPTURE(leg);
    CHECK(ik_line(level, leg).rfind(std::string(leg) + ": steering leg: the contact point of wheel ", 0) == 0);
  }
  CHECK(ik_line(level, "leg_lf").find("by hip_yaw_lf (z), then hip_pitch_lf and knee_lf (parallel, about y), ankle_pitch_lf by the "
                                      "sum row ankle_square_lf; inputs after it: ankle_yaw_lf, ankle_roll_lf (4 branches") !=
        std::string::npos);
  // A sum row that leaves the ankle pitch out does not fix the parallel joints' total turn.
  const std::string partial = replaced(level_text, "coordinates: [hip_pitch_<leg>, knee_<leg>, ankle_pitch_<leg>]",
                                       "coordinates: [hip_pitch_<leg>, knee_<leg>, hip_yaw_<leg>]");
  const std::string partial_line = ik_line(parse_model(partial, "partial.yaml", directory), "leg_lf");
  CHECK(partial_line.find("steering leg: the sum row ankle_square_lf holds other dependent joints than the three parallel ones "
                          "(hip_pitch_lf, knee_lf, ankle_pitch_lf)") != std::string::npos);
}
#endif

TEST_CASE("IK patterns: a steering leg's preconditions are its geometry's") {
  // tests/ik_shapes/ik_shapes.yaml's leg_e (a wheel) and leg_f (a point, on the tilting base).
  const std::string original = text_of(WLX_IK_SHAPES_FILE);
  const Model m = parse_model(original, "ik_shapes.yaml");
  CHECK(ik_line(m, "leg_e").rfind("leg_e: steering leg: the contact point of wheel e (contact_e)", 0) == 0);
  CHECK(ik_line(m, "leg_f").rfind("leg_f: steering leg: f_foot at (x, y, z) = (xf, yf, zf) by f1 (y), then f2 and f3", 0) == 0);
  // A third joint about another axis than the second's.
  const std::string skewed = ik_line(parse_model(replaced(original, "ry: eturn, ry: e3", "ry: eturn, rx: e3"), "skewed.yaml"), "leg_e");
  CHECK(skewed.find("steering leg: the axes of e2, e3 and e4 are not parallel (") != std::string::npos);
  CHECK(skewed.find("ry: eturn between the first two") != std::string::npos);
  CHECK(skewed.find("the pattern needs three joints about one axis, with turns between them only about that axis") != std::string::npos);
  // A turn between the parallel joints about another axis tilts the next one.
  const std::string tilted = ik_line(parse_model(replaced(original, "rx: fturn, rx: -f4", "rz: fturn, rx: -f4"), "tilted.yaml"), "leg_f");
  CHECK(tilted.find("steering leg: the axes of f2, f3 and f4 are not parallel") != std::string::npos);
  // The parallel joints about opposite directions: the sum row does not fix their total turn.
  const std::string opposed = ik_line(parse_model(replaced(original, "ry: e4]", "ry: -e4]"), "opposed.yaml"), "leg_e");
  CHECK(opposed.find("steering leg: e2, e3 and e4 turn about opposite directions of their axis") != std::string::npos);
  // An input's joint among the four dependent ones.
  const std::string moved = replaced(replaced(original, "rz: swivel_f, tz: slide_f", "tz: slide_f"), "rx: -f2]", "rx: -f2, rz: swivel_f]");
  const std::string between = ik_line(parse_model(moved, "between.yaml"), "leg_f");
  CHECK(between.find("steering leg: input swivel_f moves the chain between the first dependent joint f1 and the fourth") !=
        std::string::npos);
}
