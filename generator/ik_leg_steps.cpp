// The steps a leg's IK patterns share (wheel leg, plane leg, steering leg; point3's distance too):
// a hip that swings the plane of parallel joints through the target, then a planar two-link chain
// in it. Each returns a stage of the solve (ik_internal.hpp), its code calling the solvers emit_ik
// writes into ik.hpp.
#include "ik_internal.hpp"

#include <fmt/format.h>

#include <string>

namespace wlx::codegen::ik {

// The code that solves K + A cos q + B sin q = |v|^2 for a joint, v the stage's ik_<v>0..2 (a
// distance fixes a knee): `bit` of the branch picks the root, `stage` is the failure's number.
std::string distance_solve_code(const std::string& v, int bit, int stage, const SolvedJoint& s) {
  return fmt::format(
      "  const Scalar ik_{0}{0} = ik_{0}0 * ik_{0}0 + ik_{0}1 * ik_{0}1 + ik_{0}2 * ik_{0}2;\n"
      "  Scalar {1}, {2};\n"
      "  if (!ik_solve_cos_sin(ik_A, ik_B, ik_{0}{0} - ik_K, (branch & {3}) != 0, {1}, {2})) {{\n"
      "    const Scalar ik_R = detail::square_root(ik_A * ik_A + ik_B * ik_B);\n"
      "    why = {{{4}, detail::square_root(ik_{0}{0}), detail::square_root(std::max(Scalar(0), ik_K - ik_R)), detail::square_root(ik_K + ik_R), 0.0}};\n"
      "    return IkStatus::out_of_reach;\n"
      "  }}\n",
      v, s.c.get_name(), s.s.get_name(), bit, stage);
}

void add_plane_offset_solve(Stage& stage, const Sinusoid& first, const ex& plane, const SolvedJoint& s1) {
  stage.locals.emplace_back(realsymbol("ik_alpha"), first.a);
  stage.locals.emplace_back(realsymbol("ik_beta"), first.b);
  stage.locals.emplace_back(realsymbol("ik_gamma"), (plane - first.c).expand());
  stage.code += fmt::format(
      "  Scalar {0}, {1};\n"
      "  if (!ik_solve_cos_sin(ik_alpha, ik_beta, ik_gamma, (branch & 1) != 0, {0}, {1})) {{\n"
      "    why = {{1, double(std::abs(ik_gamma)), 0.0, double(detail::square_root(ik_alpha * ik_alpha + ik_beta * ik_beta)), 0.0}};\n"
      "    return IkStatus::out_of_reach;\n"
      "  }}\n",
      s1.c.get_name(), s1.s.get_name());
  stage.defines = {s1.c.get_name(), s1.s.get_name()};
}

Stage two_link_distance_stage(const Model& m, const Solve& solve, const Vec3& w, const Vec3& p2, const Mat3& R2,
                              const ChainStep& j3, const Vec3& p3, const SolvedJoint& s3) {
  Stage st;
  for (int i = 0; i < 3; ++i) st.locals.emplace_back(realsymbol(fmt::format("ik_w{}", i)), in_results(m, w[i], solve));
  const Sinusoid distance = distance_squared(p2, R2, j3, p3);
  st.locals.emplace_back(realsymbol("ik_K"), distance.c);
  st.locals.emplace_back(realsymbol("ik_A"), distance.a);
  st.locals.emplace_back(realsymbol("ik_B"), distance.b);
  st.code = distance_solve_code("w", 2, 2, s3);
  st.defines = {s3.c.get_name(), s3.s.get_name()};
  return st;
}

Stage two_link_rotation_stage(const Model& m, const Solve& solve, const Vec3& p2, const Mat3& R2, const ChainStep& j2,
                              const ChainStep& j3, const Vec3& p3, const SolvedJoint& s2) {
  const ex& q3 = m.coordinates[static_cast<std::size_t>(j3.coordinate)].q;
  Stage st;
  const Vec3 v = p2 + R2 * (signed_rot(j3.axis, j3.sign, q3) * p3);
  const int b = static_cast<int>(j2.axis), i = (b + 1) % 3, j = (b + 2) % 3;  // R_b turns i towards j
  for (int k : {i, j}) st.locals.emplace_back(realsymbol(fmt::format("ik_v{}", k)), in_results(m, v[k], solve));  // v_b = w_b
  st.code = fmt::format(
      "  const Scalar ik_x = ik_v{0} * ik_w{0} + ik_v{1} * ik_w{1}, ik_y = ik_v{0} * ik_w{1} - ik_v{1} * ik_w{0};\n"
      "  const Scalar ik_r = detail::square_root(ik_x * ik_x + ik_y * ik_y);\n"
      "  Scalar {2} = ik_r > 0 ? ik_x / ik_r : Scalar(1), {3} = ik_r > 0 ? ik_y / ik_r : Scalar(0);\n",
      i, j, s2.c.get_name(), s2.s.get_name()) +
      unsign(j2, s2);
  st.defines = {s2.c.get_name(), s2.s.get_name()};
  return st;
}

}  // namespace wlx::codegen::ik
