// Emission of the headers describing the model itself: types.hpp (its sizes, names and fixed-size
// types, and the helpers every generated function shares) and params.hpp (its parameters).
#include "emit_internal.hpp"

#include <fmt/format.h>

#include <functional>

namespace wlx::codegen {

namespace {

// Whether the double functions are compiled in every translation unit or, in the model's own
// namespace, possibly once by a library (double_overload).
std::string double_linkage_note(const EmitOptions& opt) {
  const std::string inline_everywhere =
      "// The double versions of the functions are inline, compiled in every translation unit that\n"
      "// calls them.";
  if (!opt.name_space.empty()) return inline_everywhere + "\n";
  return inline_everywhere +
         fmt::format(" With {0} defined they are only declared: a library compiles them once, in\n"
                     "// translation units that define WLX_GEN_DEFINE_DOUBLE and include each header once (the wlx\n"
                     "// runtime library of the model does, and defines {0} for its users).\n",
                     compiled_macro(opt));
}

// The inverse dynamics' types, on the commanded speeds u (reduced_dynamics' arguments). Without a
// dynamics section: no commanded speeds, and the types stay defined (of size zero).
std::string dynamics_types(const Model& m) {
  const int n = static_cast<int>(m.coordinates.size());
  const std::size_t nu = m.dynamics ? m.dynamics->commanded.size() : 0;
  return fmt::format(
      "// The inverse dynamics on the {1} commanded speeds u (reduced_dynamics).\n"
      "inline constexpr int kCommandedCount = {1};\n"
      "template <typename Scalar> using CommandVectorOf = Eigen::Matrix<Scalar, {1}, 1>;\n"
      "template <typename Scalar> using CommandMatrixOf = Eigen::Matrix<Scalar, {1}, {1}>;\n"
      "template <typename Scalar> using RateBasisOf = Eigen::Matrix<Scalar, {0}, {1}>;  // s' = T u\n"
      "template <typename Scalar> using CommandRowsOf = Eigen::Matrix<Scalar, {1}, {0}>;\n"
      "using CommandVector = CommandVectorOf<double>;\n"
      "using CommandMatrix = CommandMatrixOf<double>;\n"
      "using RateBasis = RateBasisOf<double>;\n"
      "using CommandRows = CommandRowsOf<double>;\n\n",
      n, nu);
}

// The banner, the includes, the double functions' AVX2 + FMA version and linkage, and the namespace.
std::string types_opening(const Model& m, const EmitOptions& opt) {
  std::string t = banner(m, opt, "Model sizes, names and fixed-size types.");
  // The double functions are also compiled for AVX2 + FMA and picked at run time, so that the
  // committed headers stay portable (SSE2 at worst) and a machine that has the instructions uses
  // them: the generated code is long chains of scalar multiply-adds, which FMA shortens. Only GCC
  // and clang on x86-64 (the target and flatten attributes, __builtin_cpu_supports); not when the
  // build targets AVX2 + FMA already. FMA rounds a*b+c once, so results differ in the last bits.
  t += "#pragma once\n\n#include <Eigen/Core>\n\n#include <array>\n#include <string_view>\n\n"
       "// The double functions have an AVX2 + FMA version, picked at run time when the CPU has both\n"
       "// (x86-64 with GCC or clang, unless the build targets them anyway). Its results can differ from\n"
       "// the portable version's in the last bits (a fused multiply-add rounds once). Define\n"
       "// WLX_GEN_NO_MULTIVERSION to compile only the portable version.\n"
       "#if !defined(WLX_GEN_NO_MULTIVERSION) && defined(__x86_64__) && defined(__GNUC__) && \\\n"
       "    !(defined(__AVX2__) && defined(__FMA__)) && defined(__has_attribute)\n"
       "#if __has_attribute(target) && __has_attribute(flatten)\n"
       "#define WLX_GEN_MULTIVERSION 1\n"
       "#endif\n"
       "#endif\n\n"
       + double_linkage_note(opt) +
       "#if defined(WLX_GEN_DEFINE_DOUBLE)\n"
       "#define WLX_GEN_DOUBLE_INLINE\n"
       "#else\n"
       "#define WLX_GEN_DOUBLE_INLINE inline\n"
       "#endif\n\n" +
       namespace_open(opt);
  return t;
}

// The model's name and description, and how many of each thing it has.
std::string model_sizes(const Model& m) {
  const int n = static_cast<int>(m.coordinates.size());
  std::string t = fmt::format(
      "\ninline constexpr std::string_view kModelName = {};\n"
      "inline constexpr std::string_view kModelDescription = {};\n",
      quoted(m.name), quoted(m.description));
  t += fmt::format(
      "\ninline constexpr int kCoordinateCount = {};  // s = [inputs q, dependent joints]\n"
      "inline constexpr int kInputCount = {};\n"
      "inline constexpr int kDependentCount = {};\n"
      "inline constexpr int kClosureCount = {};\n"
      "inline constexpr int kFrameCount = {};\n"
      "inline constexpr int kBodyCount = {};\n"
      "inline constexpr int kWheelCount = {};\n\n",
      n, m.input_count, n - m.input_count, m.closure.size(), m.frames.size(), m.bodies.size(), m.wheels.size());
  return t;
}

std::string scalar_types(const Model& m) {
  // Every generated function is a template on the scalar type: double (tested, the runtime's),
  // float (targets without double-precision hardware), automatic-differentiation numbers. The
  // ...Of<Scalar> types are its arguments; the plain names are the double ones.
  return fmt::format(
      "// The types of the generated functions for scalar type Scalar.\n"
      "template <typename Scalar> using CoordinatesOf = Eigen::Matrix<Scalar, {0}, 1>;\n"
      "template <typename Scalar> using FramePositionsOf = Eigen::Matrix<Scalar, 3, {1}>;\n"
      "template <typename Scalar> using FrameRotationsOf = std::array<Eigen::Matrix<Scalar, 3, 3>, {1}>;\n"
      "template <typename Scalar> using ClosureVectorOf = Eigen::Matrix<Scalar, {2}, 1>;\n"
      "template <typename Scalar> using ClosureJacobianOf = Eigen::Matrix<Scalar, {2}, {0}>;\n"
      "template <typename Scalar> using WheelRowsOf = Eigen::Matrix<Scalar, {3}, {0}>;\n"
      "template <typename Scalar> using WheelVectorOf = Eigen::Matrix<Scalar, {3}, 1>;\n"
      "template <typename Scalar> using BodyVectorsOf = Eigen::Matrix<Scalar, 3, {4}>;\n"
      "template <typename Scalar> using BodyRotationsOf = std::array<Eigen::Matrix<Scalar, 3, 3>, {4}>;\n"
      "template <typename Scalar> using BodyJacobiansOf = std::array<Eigen::Matrix<Scalar, 3, {0}>, {4}>;\n"
      "template <typename Scalar> using JointJacobianOf = Eigen::Matrix<Scalar, 6, {0}>;\n"
      "template <typename Scalar> using Vector3Of = Eigen::Matrix<Scalar, 3, 1>;\n\n"
      "// The double ones: what the runtime uses.\n"
      "using Coordinates = CoordinatesOf<double>;\n"
      "using FramePositions = FramePositionsOf<double>;\n"
      "using FrameRotations = FrameRotationsOf<double>;\n"
      "using ClosureVector = ClosureVectorOf<double>;\n"
      "using ClosureJacobian = ClosureJacobianOf<double>;\n"
      "using WheelRows = WheelRowsOf<double>;\n"
      "using WheelVector = WheelVectorOf<double>;\n"
      "using BodyVectors = BodyVectorsOf<double>;\n"
      "using BodyRotations = BodyRotationsOf<double>;\n"
      "using BodyJacobians = BodyJacobiansOf<double>;\n"
      "using JointJacobian = JointJacobianOf<double>;\n"
      "using Vector3 = Vector3Of<double>;\n\n"
      "{5}",
      m.coordinates.size(), m.frames.size(), m.closure.size(), m.wheels.size(), m.bodies.size(), dynamics_types(m));
}

// detail::: NonDeduced (for output pointers that may be nullptr), Lanes (N scalars side by side,
// GCC / clang vectors for double) and has_avx2_fma().
std::string detail_helpers() {
  return "namespace detail {\n"
         "// T, but not deduced: the scalar type of a generated function comes from its coordinates, so an\n"
         "// output pointer may be nullptr (std::type_identity_t, which C++17 lacks).\n"
         "template <typename T> struct NonDeducedType { using type = T; };\n"
         "template <typename T> using NonDeduced = typename NonDeducedType<T>::type;\n"
         "// N scalars side by side, for code that does the same to N columns at once (reduced_dynamics'\n"
         "// composite pass, one lane per limb of one shape). Loops over a fixed N, which compilers unroll.\n"
         "template <typename Scalar, int N>\n"
         "struct Lanes {\n"
         "  Scalar v[N];\n"
         "  Scalar lane(int i) const noexcept { return v[i]; }\n"
         "  void set_lane(int i, const Scalar& x) noexcept { v[i] = x; }\n"

         "  Lanes& operator+=(const Lanes& o) noexcept {\n"
         "    for (int i = 0; i < N; ++i) v[i] += o.v[i];\n"
         "    return *this;\n"
         "  }\n"
         "  friend Lanes operator+(Lanes a, const Lanes& b) noexcept { return a += b; }\n"
         "  friend Lanes operator-(Lanes a, const Lanes& b) noexcept {\n"
         "    for (int i = 0; i < N; ++i) a.v[i] -= b.v[i];\n"
         "    return a;\n"
         "  }\n"
         "  friend Lanes operator-(Lanes a) noexcept {\n"
         "    for (int i = 0; i < N; ++i) a.v[i] = -a.v[i];\n"
         "    return a;\n"
         "  }\n"
         "  friend Lanes operator*(Lanes a, const Lanes& b) noexcept {\n"
         "    for (int i = 0; i < N; ++i) a.v[i] *= b.v[i];\n"
         "    return a;\n"
         "  }\n"
         "  friend Lanes operator*(const Scalar& s, const Lanes& a) noexcept {\n"
         "    Lanes out;\n"
         "    for (int i = 0; i < N; ++i) out.v[i] = s * a.v[i];\n"
         "    return out;\n"
         "  }\n"
         "};\n"
         "#if defined(__GNUC__) && !defined(WLX_GEN_NO_VECTOR_LANES)\n"
         "#define WLX_GEN_LANES_INLINE inline __attribute__((always_inline))\n"
         "// double: GCC / clang vectors of WLX_GEN_LANE_VECTOR doubles, as many as N needs, the last one\n"
         "// padded with zeros, so that the rows stay in registers and every operation is one vector\n"
         "// instruction per WLX_GEN_LANE_VECTOR lanes (rows of 2 lanes: below): 4, an AVX register, where the code\n"
         "// may use AVX (compiled for it, or the AVX2 version of the run-time dispatch); else 2, an SSE2\n"
         "// register, since GCC makes slow code of a 4-wide vector on SSE2 (the excavator's former Kane's sums\n"
         "// at -O2 without the dispatch: 2476 ns with 4 lanes a vector, 1526 ns with 2; clang 1477 ns\n"
         "// and 1478 ns). Always inlined: a vector is never passed to or returned from a call, whose\n"
         "// convention would depend on whether the caller targets AVX.\n"
         "#if defined(__AVX__) || defined(WLX_GEN_MULTIVERSION)\n"
         "#define WLX_GEN_LANE_VECTOR 4\n"
         "#else\n"
         "#define WLX_GEN_LANE_VECTOR 2\n"
         "#endif\n"
         "// clang fuses a product and a sum into one instruction (FMA, where the target has it) only\n"
         "// within one expression by default, and a row's `a + s * b` is two of these inline operators: here\n"
         "// it may fuse them, as GCC does (the excavator's Kane's sums, AVX2 build: 533 ns unfused, 445 ns\n"
         "// fused, GCC 445 ns). Only these operators: the includer's own code keeps its own setting.\n"
         "#if defined(__clang__) && __clang_major__ >= 12  // float_control: clang 11 on (12: Apple clang 12.0.0 is older)\n"
         "#pragma float_control(push)\n"
         "#pragma clang fp contract(fast)\n"
         "#endif\n"
         "template <int N>\n"
         "struct Lanes<double, N> {\n"
         "  // Rows of 2 lanes (two limbs of one shape) in 2-wide vectors even with AVX: GCC's AVX2 code\n"
         "  // for a 4-wide vector half used was 1.7 times clang's (the excavator's reduced_dynamics).\n"
         "  static constexpr int kWidth = N <= 2 ? 2 : WLX_GEN_LANE_VECTOR;\n"
         "  typedef double Vector __attribute__((vector_size(kWidth * 8)));\n"
         "  static constexpr int kVectors = (N + kWidth - 1) / kWidth;\n"
         "  Vector c[kVectors];\n"
         "  __attribute__((always_inline)) double lane(int i) const noexcept { return c[i / kWidth][i % kWidth]; }\n"
         "  __attribute__((always_inline)) void set_lane(int i, double x) noexcept { c[i / kWidth][i % kWidth] = x; }\n"

         "  __attribute__((always_inline)) Lanes& operator+=(const Lanes& o) noexcept {\n"
         "    for (int k = 0; k < kVectors; ++k) c[k] += o.c[k];\n"
         "    return *this;\n"
         "  }\n"
         "  __attribute__((always_inline)) friend Lanes operator+(Lanes a, const Lanes& b) noexcept { return a += b; }\n"
         "  __attribute__((always_inline)) friend Lanes operator-(Lanes a, const Lanes& b) noexcept {\n"
         "    for (int k = 0; k < kVectors; ++k) a.c[k] -= b.c[k];\n"
         "    return a;\n"
         "  }\n"
         "  __attribute__((always_inline)) friend Lanes operator-(Lanes a) noexcept {\n"
         "    for (int k = 0; k < kVectors; ++k) a.c[k] = -a.c[k];\n"
         "    return a;\n"
         "  }\n"
         "  __attribute__((always_inline)) friend Lanes operator*(Lanes a, const Lanes& b) noexcept {\n"
         "    for (int k = 0; k < kVectors; ++k) a.c[k] *= b.c[k];\n"
         "    return a;\n"
         "  }\n"
         "  __attribute__((always_inline)) friend Lanes operator*(const double& s, const Lanes& a) noexcept {\n"
         "    Lanes out;\n"
         "    for (int k = 0; k < kVectors; ++k) out.c[k] = s * a.c[k];\n"
         "    return out;\n"
         "  }\n"
         "};\n"
         "#if defined(__clang__) && __clang_major__ >= 12\n"
         "#pragma float_control(pop)\n"
         "#endif\n"
         "#else\n"
         "#define WLX_GEN_LANES_INLINE inline\n"
         "#endif\n"
         "// Value-initialized first: a vector's padding lanes are zero too.\n"
         "template <typename Scalar, int N>\n"
         "WLX_GEN_LANES_INLINE Lanes<Scalar, N> zero_lanes() noexcept {\n"
         "  Lanes<Scalar, N> out{};\n"
         "  for (int i = 0; i < N; ++i) out.set_lane(i, Scalar(0));\n"
         "  return out;\n"
         "}\n"

         "// The square root the generated functions take. For double and float, Eigen's: on x86 one\n"
         "// sqrtsd / sqrtss instruction, where std::sqrt must also set errno for a negative argument and\n"
         "// clang then keeps a library call beside every square root, which made its code for a whole\n"
         "// function up to 1.4 times slower than GCC's (a wheeled quadruped's kinematic_update). The\n"
         "// value is the same: the correctly rounded root, NaN for a negative argument. Other scalar\n"
         "// types: their own sqrt (argument-dependent lookup), or std::sqrt.\n"
         "template <typename Scalar>\n"
         "inline Scalar square_root(const Scalar& x) noexcept {\n"
         "  using std::sqrt;\n"
         "  return sqrt(x);\n"
         "}\n"
         "inline double square_root(double x) noexcept { return Eigen::numext::sqrt(x); }\n"
         "inline float square_root(float x) noexcept { return Eigen::numext::sqrt(x); }\n"
         "#if defined(WLX_GEN_MULTIVERSION)\n"
         "// Whether this CPU (and its operating system) runs AVX2 and FMA instructions; asked once.\n"
         "inline bool has_avx2_fma() noexcept {\n"
         "  static const bool yes = (__builtin_cpu_init(), __builtin_cpu_supports(\"avx2\") && __builtin_cpu_supports(\"fma\"));\n"
         "  return yes;\n"
         "}\n"
         "#endif\n"
         "}  // namespace detail\n\n";
}

// coord::, frame:: and body::: each one's index by name.
std::string index_namespaces(const Model& m) {
  std::string t = "// Index of each coordinate in s (the model file's order: inputs, then dependent joints).\nnamespace coord {\n";
  for (const auto& c : m.coordinates) t += fmt::format("inline constexpr int {} = {};  // {}, {}\n", c.name, c.index, comment(c.unit), comment(c.meaning));
  t += "}  // namespace coord\n\n";
  t += "// Index of each frame of interest in FramePositions / FrameRotations.\nnamespace frame {\n";
  for (std::size_t k = 0; k < m.frames.size(); ++k) t += fmt::format("inline constexpr int {} = {};  // {}\n", m.frames[k].name, k, comment(m.frames[k].meaning));
  t += "}  // namespace frame\n\nnamespace body {\n";
  for (std::size_t k = 0; k < m.bodies.size(); ++k) t += fmt::format("inline constexpr int {} = {};  // {}\n", m.bodies[k].name, k, comment(m.bodies[k].meaning));
  t += "}  // namespace body\n\n";
  return t;
}

// The names (and units, meanings) of the coordinates, frames, bodies, closure rows and wheels, as
// arrays in index order.
std::string name_tables(const Model& m) {
  const int n = static_cast<int>(m.coordinates.size());
  const int nf = static_cast<int>(m.frames.size());
  const int nb = static_cast<int>(m.bodies.size());
  const int nc = static_cast<int>(m.closure.size());
  const int nw = static_cast<int>(m.wheels.size());
  std::string t;
  const auto names = [&](const std::string& var, int count, const std::function<std::string(int)>& name) {
    std::string s = fmt::format("inline constexpr std::array<std::string_view, {}> {}{{{{\n", count, var);
    for (int k = 0; k < count; ++k) s += fmt::format("    {},\n", quoted(name(k)));
    return s + "}};\n";
  };
  const auto at = [](const auto& v, int k) -> const auto& { return v[static_cast<std::size_t>(k)]; };
  t += names("kCoordinateNames", n, [&](int k) { return at(m.coordinates, k).name; });
  t += names("kCoordinateUnits", n, [&](int k) { return at(m.coordinates, k).unit; });
  t += names("kFrameNames", nf, [&](int k) { return at(m.frames, k).name; });
  t += names("kBodyNames", nb, [&](int k) { return at(m.bodies, k).name; });
  t += names("kBodyMeanings", nb, [&](int k) { return at(m.bodies, k).meaning; });
  t += names("kClosureNames", nc, [&](int k) { return at(m.closure, k).name; });
  t += names("kWheelNames", nw, [&](int k) { return at(m.wheels, k).name; });
  return t;
}

std::string types_header(const Model& m, const EmitOptions& opt) {
  return types_opening(m, opt) + model_sizes(m) + scalar_types(m) + detail_helpers() + index_namespaces(m) +
         name_tables(m) + "\n" + namespace_close(opt);
}

// With the data read at run time: the parameters' values, set from model.json, which Params' fields
// default to.
std::string param_defaults_storage(const Model& m) {
  return fmt::format(
      "\nnamespace detail {{\n"
      "// The parameters' values, in Params' order: NaN until the runtime sets them from model.json\n"
      "// (wlx/settings.hpp, set_settings()), so that Params{{}} then holds the model file's values as a\n"
      "// Params with its values compiled in does, and a use before that fails the Model's checks.\n"
      "inline std::array<double, {0}>& param_defaults() noexcept {{\n"
      "  static std::array<double, {0}> values = [] {{\n"
      "    std::array<double, {0}> v{{}};\n"
      "    v.fill(std::numeric_limits<double>::quiet_NaN());\n"
      "    return v;\n"
      "  }}();\n"
      "  return values;\n"
      "}}\n"
      "}}  // namespace detail\n",
      m.parameters.size());
}

// struct Params: one field per parameter, its default the model file's value, model.json's or the baked one.
std::string params_struct(const Model& m, const EmitOptions& opt) {
  std::string p =
      opt.data_at_run_time
          ? "\n// The model's numbers: their defaults are read at run time from model.json (detail::param_defaults());\n"
            "// change any of them at run time.\nstruct Params {\n"
          : "\n// The model's numbers, defaults from its file; change any of them at run time.\nstruct Params {\n";
  for (const auto& par : m.parameters) {
    // A baked parameter's field keeps the baked value, not a stale default that nothing uses.
    if (auto it = opt.baked.find(par.name); it != opt.baked.end())
      p += fmt::format("  double {} = {};  // {}: {} (baked: the generated functions use this constant; changing the "
                       "field has no effect)\n",
                       par.name, literal(it->second), comment(par.unit), comment(par.meaning));
    else if (opt.data_at_run_time)  // model.json's value, once the runtime has read it
      p += fmt::format("  double {} = detail::param_defaults()[{}];  // {}: {}\n", par.name, &par - m.parameters.data(),
                       comment(par.unit), comment(par.meaning));
    else
      p += fmt::format("  double {} = {};  // {}: {}\n", par.name, literal(par.default_value), comment(par.unit), comment(par.meaning));
  }
  p += "};\n\n";
  return p;
}

// Each parameter's kind, unit and meaning, and each body's mass properties, by Params member.
std::string parameter_tables(const Model& m) {
  std::string p =
      "// What a parameter is, which fixes its unit and the values that make sense for it: length (m, > 0),\n"
      "// offset (m, any sign), angle (rad), mass (kg, > 0), inertia (kg*m^2, > 0), gravity (m/s^2, >= 0),\n"
      "// other (any finite value).\n"
      "enum class ParamKind { length, offset, angle, mass, inertia, gravity, other };\n\n"
      "struct ParamInfo {\n  std::string_view name;\n  double Params::*member;\n  std::string_view unit;\n"
      "  std::string_view meaning;\n  ParamKind kind;\n};\n\n";
  p += fmt::format("inline constexpr std::array<ParamInfo, {}> kParamInfo{{{{\n", m.parameters.size());
  for (std::size_t k = 0; k < m.parameters.size(); ++k) {
    const auto& par = m.parameters[k];
    p += fmt::format("    {{\"{0}\", &Params::{0}, {1}, {2}, ParamKind::{3}}},\n", par.name, quoted(par.unit), quoted(par.meaning),
                     kind_name(m.parameter_kinds[k]));
  }
  p += "}};\n\n// Mass properties of each body (index with wlx::gen::body::...).\nstruct BodyMassInfo {\n"
       "  double Params::*mass;\n  std::array<double Params::*, 3> inertia;  // principal, about the CoM, body axes\n};\n\n";
  p += fmt::format("inline constexpr std::array<BodyMassInfo, {}> kBodyMass{{{{\n", m.bodies.size());
  for (const auto& b : m.bodies)
    p += fmt::format("    {{&Params::{}, {{&Params::{}, &Params::{}, &Params::{}}}}},\n", b.mass, b.inertia[0], b.inertia[1], b.inertia[2]);
  p += "}};\n\n";
  return p;
}

std::string params_header(const Model& m, const EmitOptions& opt) {
  std::string p = banner(m, opt, "Model parameters: geometry and mass properties, defaults from the model file.");
  p += "#pragma once\n\n#include <array>\n";
  if (opt.data_at_run_time) p += "#include <limits>\n";
  p += "#include <string_view>\n\n" + namespace_open(opt);
  if (opt.data_at_run_time) p += param_defaults_storage(m);
  return p + params_struct(m, opt) + parameter_tables(m) + namespace_close(opt);
}

}  // namespace

std::vector<EmittedFile> emit_model_headers(const Model& m, const EmitOptions& opt) {
  return {{"wlx/gen/types.hpp", types_header(m, opt)}, {"wlx/gen/params.hpp", params_header(m, opt)}};
}

}  // namespace wlx::codegen
