// Emission of trig.hpp: sin and cos of all of a function's angles in one vectorized pass.
//
// Why: every generated function needs sin and cos of up to a few dozen joint and body angles, and the
// libm calls (about 6.5 ns per angle here, even fused into sincos) are over half of the fused
// kinematic update. The angles are independent, so one SIMD pass over all of them is cheaper.
// The constants are derived here with GiNaC's arbitrary precision, not copied from a libm.
#include "emit.hpp"

#include <ginac/ginac.h>
#include <fmt/format.h>

#include <cmath>

namespace wlx::codegen {

namespace {

struct TrigConstants {
  double two_over_pi;
  // pi/2 = hi + mid + lo: hi and mid carry 33 and 31 significant bits, so n * hi and n * mid are
  // exact for every quadrant count n the fast path allows (|n| < 2^21); Cody-Waite reduction.
  double half_pi_hi, half_pi_mid, half_pi_lo;
  std::vector<double> sin_coefficients;  // r^3, r^5, ..., r^15: (-1)^k / (2k+1)!
  std::vector<double> cos_coefficients;  // r^4, r^6, ..., r^16: (-1)^k / (2k)!
  // atan2: atan(k/8) = hi + lo for k = 0..8; pi/2 and pi as hi + lo; the Taylor coefficients
  // (-1)^k / (2k + 1) of atan u for u^3 .. u^17.
  std::vector<double> atan_hi, atan_lo;
  double half_pi_hi2, half_pi_lo2, pi_hi, pi_lo;
  std::vector<double> atan_coefficients;
};

TrigConstants derive_constants() {
  using GiNaC::numeric;
  const long saved_digits = GiNaC::Digits;
  GiNaC::Digits = 60;
  const numeric half_pi = GiNaC::ex_to<numeric>(GiNaC::evalf(GiNaC::Pi / 2));
  const numeric two32 = GiNaC::ex_to<numeric>(GiNaC::pow(numeric(2), 32)), two64 = GiNaC::ex_to<numeric>(GiNaC::pow(numeric(2), 64));
  const long hi_units = static_cast<long>(std::floor((half_pi * two32).to_double()));
  const numeric rest = half_pi - numeric(hi_units) / two32;  // exact: the subtrahend is dyadic
  const long mid_units = static_cast<long>(std::floor((rest * two64).to_double()));
  const numeric tail = rest - numeric(mid_units) / two64;
  TrigConstants k{};
  k.two_over_pi = (numeric(1) / half_pi).to_double();
  k.half_pi_hi = std::ldexp(static_cast<double>(hi_units), -32);
  k.half_pi_mid = std::ldexp(static_cast<double>(mid_units), -64);
  k.half_pi_lo = tail.to_double();
  // Taylor terms suffice on |r| <= pi/4: the first omitted ones, (pi/4)^17/17! and (pi/4)^18/18!,
  // are below 5e-17, under half an ulp of the results.
  const auto taylor = [](int power) {  // the coefficient of r^power in sin r or cos r
    return (numeric((power / 2) % 2 ? -1 : 1) / GiNaC::factorial(numeric(power))).to_double();
  };
  for (int power = 3; power <= 15; power += 2) k.sin_coefficients.push_back(taylor(power));
  for (int power = 4; power <= 16; power += 2) k.cos_coefficients.push_back(taylor(power));
  // atan on |u| <= 1/8 (t reduced to the nearest eighth, or not at all below 1/8): the first
  // omitted Taylor term, u^19/19, is below 3e-18 of u, far under half an ulp.
  const auto split = [](const numeric& v, double& hi, double& lo) {
    hi = v.to_double();
    // hi as an exact rational, M 2^(e - 53): CLN would round the difference to hi's precision.
    int e = 0;
    const double mantissa = std::frexp(hi, &e);
    const numeric exact_hi = numeric(static_cast<long>(std::ldexp(mantissa, 53))) * GiNaC::ex_to<numeric>(GiNaC::pow(numeric(2), e - 53));
    lo = (v - exact_hi).to_double();
  };
  for (int j = 0; j <= 8; ++j) {
    double hi = 0, lo = 0;
    split(GiNaC::ex_to<numeric>(GiNaC::evalf(GiNaC::atan(numeric(j, 8)))), hi, lo);
    k.atan_hi.push_back(hi);
    k.atan_lo.push_back(lo);
  }
  split(half_pi, k.half_pi_hi2, k.half_pi_lo2);
  split(half_pi * 2, k.pi_hi, k.pi_lo);
  for (int power = 3; power <= 17; power += 2)
    k.atan_coefficients.push_back((numeric((power / 2) % 2 ? -1 : 1) / numeric(power)).to_double());
  GiNaC::Digits = saved_digits;
  return k;
}

// Horner form c0 + r2*(c1 + r2*(...)) of the coefficients.
std::string horner(const std::vector<double>& c, const char* var = "r2", std::size_t i = 0) {
  if (i + 1 == c.size()) return literal(c[i]);
  return fmt::format("{} + {} * ({})", literal(c[i]), var, horner(c, var, i + 1));
}

// The header's opening: its banner, what its functions do, how accurately and by which method.
std::string trig_header_opening(const Model& m, const EmitOptions& opt) {
  std::string t = banner(m, opt, "sin and cos, and atan2, of many angles in one vectorized pass (used by the generated functions).");
  t += R"(//
// sincos(x, sin_x, cos_x) fills sin_x[i] = sin(x[i]) and cos_x[i] = cos(x[i]) for a fixed-size
// array of angles. Accuracy: within 1 ulp of 1 (absolute error <= 2.3e-16) of the correctly
// rounded values for |x| <= 1e6; larger, infinite or NaN angles go to std::sin / std::cos.
// Method: x = n pi/2 + r with |r| <= pi/4 (Cody-Waite reduction with pi/2 split in three parts),
// Taylor polynomials of sin r and cos r, the quadrant n mod 4 picked by bit masks, so the whole
// pass is branch-free and runs on SIMD registers (4 lanes: one AVX or two SSE2 registers).
// Compilers without GCC vector extensions, and -ffast-math builds (whose reassociation would undo
// the rounding trick), get the std:: functions.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

)";
  return t;
}

// trig_detail's constants: pi/2 in three parts for sincos' reduction; atan(k/8), pi/2 and pi in two
// for atan2.
std::string trig_constants(const TrigConstants& k) {
  std::string t = fmt::format(
      "inline constexpr double kTwoOverPi = {};\n"
      "inline constexpr double kRoundToInteger = 6755399441055744.0;  // 1.5 * 2^52: x + this - this rounds x\n"
      "inline constexpr double kHalfPiHi = {};  // 33 bits\n"
      "inline constexpr double kHalfPiMid = {};  // 31 bits\n"
      "inline constexpr double kHalfPiLo = {};\n"
      "inline constexpr double kFastPathLimit = 1e6;  // |n| < 2^21 keeps n * kHalfPiHi and n * kHalfPiMid exact\n\n",
      literal(k.two_over_pi), literal(k.half_pi_hi), literal(k.half_pi_mid), literal(k.half_pi_lo));
  const auto list = [](const std::vector<double>& v) {
    std::vector<std::string> out;
    for (double x : v) out.push_back(literal(x));
    return fmt::format("{}", fmt::join(out, ", "));
  };
  t += fmt::format(
      "// atan(k/8) = hi + lo for k = 0..8; pi/2 and pi as hi + lo (lo: the rounding error of hi).\n"
      "inline constexpr double kAtanEighthHi[9] = {{{}}};\n"
      "inline constexpr double kAtanEighthLo[9] = {{{}}};\n"
      "inline constexpr double kHalfPiHead = {}, kHalfPiTail = {};\n"
      "inline constexpr double kPiHead = {}, kPiTail = {};\n\n",
      list(k.atan_hi), list(k.atan_lo), literal(k.half_pi_hi2), literal(k.half_pi_lo2), literal(k.pi_hi), literal(k.pi_lo));
  return t;
}

// sincos and atan2 of 4 angles at once on GCC / clang vectors, their polynomials in Horner form with
// the derived coefficients (none without vector extensions, or with -ffast-math).
std::string lane_kernels(const TrigConstants& k) {
  std::string t =
      "#if (defined(__GNUC__) || defined(__clang__)) && !defined(__FAST_MATH__)\n"
      "#define WLX_GEN_SIMD_SINCOS 1\n"
      "// 4 lanes whatever the build targets: one AVX register, so that the AVX2 version of the generated\n"
      "// functions (types.hpp) gets them, or two SSE2 registers, two independent chains (as fast as one\n"
      "// 2-lane vector at a time). Vectors are passed by reference only: by value, a 32-byte vector's\n"
      "// calling convention would depend on whether the translation unit targets AVX.\n"
      "// reinterpret_cast between vector types of the same size gives the same bits (GCC and clang).\n"
      "inline constexpr std::size_t kLanes = 4;\n"
      "typedef double Doubles __attribute__((vector_size(32)));\n"
      "typedef std::uint64_t Bits __attribute__((vector_size(32)));\n\n"
      "inline void sincos_lanes(const Doubles& x, Doubles& sin_x, Doubles& cos_x) noexcept {\n"
      "  const Doubles shifted = x * kTwoOverPi + kRoundToInteger;\n"
      "  const Doubles n = shifted - kRoundToInteger;          // nearest integer to x / (pi/2)\n"
      "  const Bits quadrant = reinterpret_cast<Bits>(shifted);  // its low bits: n mod 4\n"
      "  const Doubles r = ((x - n * kHalfPiHi) - n * kHalfPiMid) - n * kHalfPiLo;\n"
      "  const Doubles r2 = r * r;\n";
  // r * (1 + r2 p) rather than r + r r2 p keeps the sign of sin(-0) = -0.
  t += fmt::format("  const Doubles s = r * (1.0 + r2 * ({}));\n", horner(k.sin_coefficients));
  t += fmt::format("  const Doubles c = 1.0 - 0.5 * r2 + r2 * r2 * ({});\n", horner(k.cos_coefficients));
  t += "  const Bits s_bits = reinterpret_cast<Bits>(s), c_bits = reinterpret_cast<Bits>(c);\n"
       "  const Bits swap = Bits{} - (quadrant & 1);  // odd quadrants exchange sin and cos\n"
       "  const Bits sin_bits = ((c_bits & swap) | (s_bits & ~swap)) ^ ((quadrant & 2) << 62);  // quadrants 2, 3: -\n"
       "  const Bits cos_bits = ((s_bits & swap) | (c_bits & ~swap)) ^ (((quadrant + 1) & 2) << 62);  // 1, 2: -\n"
       "  sin_x = reinterpret_cast<Doubles>(sin_bits);\n"
       "  cos_x = reinterpret_cast<Doubles>(cos_bits);\n"
       "}\n\n"
       "// Picks a where the mask is all ones, b where it is zero.\n"
       "inline void select(const Bits& mask, const Doubles& a, const Doubles& b, Doubles& out) noexcept {\n"
       "  out = reinterpret_cast<Doubles>((mask & reinterpret_cast<Bits>(a)) | (~mask & reinterpret_cast<Bits>(b)));\n"
       "}\n\n"
       "inline void atan2_lanes(const Doubles& y, const Doubles& x, Doubles& angle) noexcept {\n"
       "  const Bits sign = Bits{} + 0x8000000000000000u;\n"
       "  const Doubles ax = reinterpret_cast<Doubles>(reinterpret_cast<Bits>(x) & ~sign), ay = reinterpret_cast<Doubles>(reinterpret_cast<Bits>(y) & ~sign);\n"
       "  const Bits swap = reinterpret_cast<Bits>(ay > ax);  // above the diagonal: atan2 = pi/2 - atan(|x| / |y|)\n"
       "  Doubles num, den, origin;\n"
       "  select(swap, ax, ay, num);\n"
       "  select(swap, ay, ax, den);\n"
       "  select(reinterpret_cast<Bits>(den == 0.0), Doubles{} + 1.0, Doubles{}, origin);\n"
       "  const Doubles t = num / (den + origin);  // in [0, 1]; 0 / 1 at the origin\n"
       "  const Doubles shifted = t * 8.0 + kRoundToInteger;\n"
       "  // The nearest eighth k/8, but 0 below 1/8: atan(1/8) + atan u with u near -1/16 would cancel.\n"
       "  const Bits small = reinterpret_cast<Bits>(t < 0.125);\n"
       "  Doubles centre;\n"
       "  select(small, Doubles{}, (shifted - kRoundToInteger) * 0.125, centre);\n"
       "  const Bits k = reinterpret_cast<Bits>(shifted) & 15 & ~small;\n"
       "  // atan t = atan(k/8) + atan u; t - k/8 is exact (Sterbenz), |u| <= 1/8.\n"
       "  const Doubles u = (t - centre) / (1.0 + t * centre);\n"
       "  const Doubles u2 = u * u;\n";
  t += fmt::format("  const Doubles atan_u = u + u * u2 * ({});\n", horner(k.atan_coefficients, "u2"));
  t += "  Doubles head, tail;\n"
       "  for (std::size_t lane = 0; lane < kLanes; ++lane) {\n"
       "    head[lane] = kAtanEighthHi[k[lane]];\n"
       "    tail[lane] = kAtanEighthLo[k[lane]];\n"
       "  }\n"
       "  Doubles a = head + (tail + atan_u);  // atan t, in [0, pi/4]\n"
       "  select(swap, (kHalfPiHead - a) + kHalfPiTail, a, a);\n"
       "  select(Bits{} - (reinterpret_cast<Bits>(x) >> 63), (kPiHead - a) + kPiTail, a, a);  // x < 0 (and x = -0): pi - a\n"
       "  angle = reinterpret_cast<Doubles>(reinterpret_cast<Bits>(a) ^ (reinterpret_cast<Bits>(y < 0.0) & sign));  // y < 0: -a; y = -0 counts as +0\n"
       "}\n"
       "#endif\n"
       "// atan2() of doubles is always inlined: clang kept atan2<12> out of line, compiled for baseline\n"
       "// x86-64, so that the AVX2 version of the IK (types.hpp) called its SSE2 code (clang's ik_all of\n"
       "// the excavator 1.25 times GCC's, which inlines it; 1.1 inlined). sincos() is not: inlined, clang's\n"
       "// `bodies` of the excavator took 2 times GCC's.\n"
       "#if defined(WLX_GEN_SIMD_SINCOS)\n"
       "#define WLX_GEN_TRIG_INLINE inline __attribute__((always_inline))\n"
       "#else\n"
       "#define WLX_GEN_TRIG_INLINE inline\n"
       "#endif\n\n";
  return t;
}

// sincos() of fixed-size arrays: double through the lane kernel (std::sin and std::cos beyond its
// range), any other scalar type through its own sin and cos.
std::string sincos_of_arrays() {
  return "template <std::size_t N>\n"
         "inline void sincos(const std::array<double, N>& x, std::array<double, N>& sin_x, std::array<double, N>& cos_x) noexcept {\n"
         "#if defined(WLX_GEN_SIMD_SINCOS)\n"
         "  using trig_detail::Doubles;\n"
         "  constexpr std::size_t lanes = trig_detail::kLanes, full = N / lanes * lanes;\n"
         "  // Loops, not unrolled: clang -O3 unrolls this one and the check below completely, which\n"
         "  // made the generated forward kinematics 45% slower than at -O2 (GCC keeps them loops).\n"
         "#if defined(__clang__)\n"
         "#pragma clang loop unroll(disable)\n"
         "#endif\n"
         "  for (std::size_t i = 0; i < full; i += lanes) {\n"
         "    Doubles xv, sv, cv;\n"
         "    std::memcpy(&xv, &x[i], sizeof xv);\n"
         "    trig_detail::sincos_lanes(xv, sv, cv);\n"
         "    std::memcpy(&sin_x[i], &sv, sizeof sv);\n"
         "    std::memcpy(&cos_x[i], &cv, sizeof cv);\n"
         "  }\n"
         "  if constexpr (full < N) {  // the last, partly filled vector\n"
         "    Doubles xv{}, sv, cv;\n"
         "    std::memcpy(&xv, &x[full], (N - full) * sizeof(double));\n"
         "    trig_detail::sincos_lanes(xv, sv, cv);\n"
         "    std::memcpy(&sin_x[full], &sv, (N - full) * sizeof(double));\n"
         "    std::memcpy(&cos_x[full], &cv, (N - full) * sizeof(double));\n"
         "  }\n"
         "#if defined(__clang__)\n"
         "#pragma clang loop unroll(disable)  // a check per angle, each a branch on the fast path\n"
         "#endif\n"
         "  for (std::size_t i = 0; i < N; ++i)\n"
         "    if (!(std::abs(x[i]) <= trig_detail::kFastPathLimit)) {  // rare: huge, infinite or NaN\n"
         "      sin_x[i] = std::sin(x[i]);\n"
         "      cos_x[i] = std::cos(x[i]);\n"
         "    }\n"
         "#else\n"
         "  for (std::size_t i = 0; i < N; ++i) {\n"
         "    sin_x[i] = std::sin(x[i]);\n"
         "    cos_x[i] = std::cos(x[i]);\n"
         "  }\n"
         "#endif\n"
         "}\n\n"
         "// Any other scalar type (float, automatic-differentiation numbers): its own sin and cos, found by\n"
         "// argument-dependent lookup, or std::sin and std::cos. The exactness guarantee above is for double.\n"
         "template <typename Scalar, std::size_t N>\n"
         "inline void sincos(const std::array<Scalar, N>& x, std::array<Scalar, N>& sin_x, std::array<Scalar, N>& cos_x) noexcept {\n"
         "  using std::cos;\n"
         "  using std::sin;\n"
         "  for (std::size_t i = 0; i < N; ++i) {\n"
         "    sin_x[i] = sin(x[i]);\n"
         "    cos_x[i] = cos(x[i]);\n"
         "  }\n"
         "}\n\n";
}

// atan2() of fixed-size arrays: double through the lane kernel (std::atan2 for infinite or NaN
// arguments), float and long double through std::atan2.
std::string atan2_of_arrays() {
  return "// atan2(y, x, angle) fills angle[i] = atan2(y[i], x[i]) for fixed-size arrays, in (-pi, pi]: a half\n"
         "// turn is +pi (y = -0 counts as +0), and the origin gives 0 (pi for x = -0). Accuracy: within\n"
         "// 2 ulp of the result of the correctly rounded values for finite arguments; infinite or NaN ones\n"
         "// go to std::atan2.\n"
         "// Method: octant reduction to t = min/max of |y|, |x| in [0, 1]; atan t = atan(k/8) + atan u with\n"
         "// k/8 the nearest eighth (k = 0 below 1/8), u = (t - k/8) / (1 + t k/8), |u| <= 1/8, and a Taylor\n"
         "// polynomial of atan u;\n"
         "// the octant by bit masks, so the pass is branch-free on SIMD registers like sincos().\n"
         "template <std::size_t N>\n"
         "WLX_GEN_TRIG_INLINE void atan2(const std::array<double, N>& y, const std::array<double, N>& x, std::array<double, N>& angle) noexcept {\n"
         "#if defined(WLX_GEN_SIMD_SINCOS)\n"
         "  using trig_detail::Doubles;\n"
         "  constexpr std::size_t lanes = trig_detail::kLanes, full = N / lanes * lanes;\n"
         "#if defined(__clang__)\n"
         "#pragma clang loop unroll(disable)  // as in sincos()\n"
         "#endif\n"
         "  for (std::size_t i = 0; i < full; i += lanes) {\n"
         "    Doubles yv, xv;\n"
         "    std::memcpy(&yv, &y[i], sizeof yv);\n"
         "    std::memcpy(&xv, &x[i], sizeof xv);\n"
         "    Doubles av;\n"
         "    trig_detail::atan2_lanes(yv, xv, av);\n"
         "    std::memcpy(&angle[i], &av, sizeof av);\n"
         "  }\n"
         "  if constexpr (full < N) {  // the last, partly filled vector\n"
         "    Doubles yv{}, xv{};\n"
         "    std::memcpy(&yv, &y[full], (N - full) * sizeof(double));\n"
         "    std::memcpy(&xv, &x[full], (N - full) * sizeof(double));\n"
         "    Doubles av;\n"
         "    trig_detail::atan2_lanes(yv, xv, av);\n"
         "    std::memcpy(&angle[full], &av, (N - full) * sizeof(double));\n"
         "  }\n"
         "#if defined(__clang__)\n"
         "#pragma clang loop unroll(disable)\n"
         "#endif\n"
         "  for (std::size_t i = 0; i < N; ++i)\n"
         "    if (!(std::abs(y[i]) <= 1.7976931348623157e308 && std::abs(x[i]) <= 1.7976931348623157e308)) {  // rare: inf, NaN\n"
         "      angle[i] = std::atan2(y[i], x[i]);\n"
         "      if (angle[i] == -trig_detail::kPiHead) angle[i] = trig_detail::kPiHead;\n"
         "    }\n"
         "#else\n"
         "  for (std::size_t i = 0; i < N; ++i) {\n"
         "    angle[i] = std::atan2(y[i] + 0.0, x[i]);  // + 0.0: -0 to +0, so a half turn is +pi\n"
         "    if (angle[i] == -trig_detail::kPiHead) angle[i] = trig_detail::kPiHead;\n"
         "  }\n"
         "#endif\n"
         "}\n\n"
         "// float and long double: std::atan2, with the same conventions (a half turn is +pi).\n"
         "template <typename Scalar, std::size_t N>\n"
         "inline void atan2(const std::array<Scalar, N>& y, const std::array<Scalar, N>& x, std::array<Scalar, N>& angle) noexcept {\n"
         "  static_assert(std::is_floating_point_v<Scalar>, \"atan2 of arrays is for floating-point types\");\n"
         "  const Scalar pi = Scalar(trig_detail::kPiHead);\n"
         "  for (std::size_t i = 0; i < N; ++i) {\n"
         "    angle[i] = std::atan2(y[i] + Scalar(0), x[i]);  // + 0: -0 to +0, so a half turn is +pi\n"
         "    if (angle[i] == -pi) angle[i] = pi;\n"
         "  }\n"
         "}\n\n";
}

}  // namespace

EmittedFile emit_trig_header(const Model& m, const EmitOptions& opt) {
  const TrigConstants k = derive_constants();
  std::string t = trig_header_opening(m, opt) + namespace_open(opt);
  t += "\nnamespace trig_detail {\n\n" + trig_constants(k) + lane_kernels(k) + "}  // namespace trig_detail\n\n";
  t += sincos_of_arrays() + atan2_of_arrays() + namespace_close(opt);
  return {"wlx/gen/trig.hpp", t};
}

}  // namespace wlx::codegen
