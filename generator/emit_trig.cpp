// Emission of trig.hpp: sin and cos of all of a function's angles in one vectorized pass.
//
// Why: every generated function needs sin and cos of up to 21 joint and cabin angles, and the
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
  GiNaC::Digits = saved_digits;
  return k;
}

// Horner form c0 + r2*(c1 + r2*(...)) of the coefficients.
std::string horner(const std::vector<double>& c, std::size_t i = 0) {
  if (i + 1 == c.size()) return literal(c[i]);
  return fmt::format("{} + r2 * ({})", literal(c[i]), horner(c, i + 1));
}

}  // namespace

EmittedFile emit_trig_header(const Model& m, const EmitOptions& opt) {
  const TrigConstants k = derive_constants();
  std::string t = banner(m, opt, "sin and cos of many angles in one vectorized pass (used by every generated function).");
  t += R"(//
// sincos(x, sin_x, cos_x) fills sin_x[i] = sin(x[i]) and cos_x[i] = cos(x[i]) for a fixed-size
// array of angles. Accuracy: within 1 ulp of 1 (absolute error <= 2.3e-16) of the correctly
// rounded values for |x| <= 1e6; larger, infinite or NaN angles go to std::sin / std::cos.
// Method: x = n pi/2 + r with |r| <= pi/4 (Cody-Waite reduction with pi/2 split in three parts),
// Taylor polynomials of sin r and cos r, the quadrant n mod 4 picked by bit masks, so the whole
// pass is branch-free and runs on SIMD registers (2 lanes with SSE2, 4 with AVX).
// Compilers without GCC vector extensions, and -ffast-math builds (whose reassociation would undo
// the rounding trick), get the std:: functions.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

)";
  t += namespace_open(opt);
  t += "\nnamespace trig_detail {\n\n";
  t += fmt::format(
      "inline constexpr double kTwoOverPi = {};\n"
      "inline constexpr double kRoundToInteger = 6755399441055744.0;  // 1.5 * 2^52: x + this - this rounds x\n"
      "inline constexpr double kHalfPiHi = {};  // 33 bits\n"
      "inline constexpr double kHalfPiMid = {};  // 31 bits\n"
      "inline constexpr double kHalfPiLo = {};\n"
      "inline constexpr double kFastPathLimit = 1e6;  // |n| < 2^21 keeps n * kHalfPiHi and n * kHalfPiMid exact\n\n",
      literal(k.two_over_pi), literal(k.half_pi_hi), literal(k.half_pi_mid), literal(k.half_pi_lo));
  t += "#if (defined(__GNUC__) || defined(__clang__)) && !defined(__FAST_MATH__)\n"
       "#define WLX_GEN_SIMD_SINCOS 1\n"
       "#if defined(__AVX__)\n"
       "inline constexpr std::size_t kLanes = 4;\n"
       "typedef double Doubles __attribute__((vector_size(32)));\n"
       "typedef std::uint64_t Bits __attribute__((vector_size(32)));\n"
       "#else\n"
       "inline constexpr std::size_t kLanes = 2;\n"
       "typedef double Doubles __attribute__((vector_size(16)));\n"
       "typedef std::uint64_t Bits __attribute__((vector_size(16)));\n"
       "#endif\n\n"
       "inline void sincos_lanes(Doubles x, Doubles& sin_x, Doubles& cos_x) noexcept {\n"
       "  const Doubles shifted = x * kTwoOverPi + kRoundToInteger;\n"
       "  const Doubles n = shifted - kRoundToInteger;          // nearest integer to x / (pi/2)\n"
       "  const Bits quadrant = (Bits)shifted;  // its low bits: n mod 4\n"
       "  const Doubles r = ((x - n * kHalfPiHi) - n * kHalfPiMid) - n * kHalfPiLo;\n"
       "  const Doubles r2 = r * r;\n";
  // r * (1 + r2 p) rather than r + r r2 p keeps the sign of sin(-0) = -0.
  t += fmt::format("  const Doubles s = r * (1.0 + r2 * ({}));\n", horner(k.sin_coefficients));
  t += fmt::format("  const Doubles c = 1.0 - 0.5 * r2 + r2 * r2 * ({});\n", horner(k.cos_coefficients));
  t += "  const Bits s_bits = (Bits)s, c_bits = (Bits)c;\n"
       "  const Bits swap = Bits{} - (quadrant & 1);  // odd quadrants exchange sin and cos\n"
       "  const Bits sin_bits = ((c_bits & swap) | (s_bits & ~swap)) ^ ((quadrant & 2) << 62);  // quadrants 2, 3: -\n"
       "  const Bits cos_bits = ((s_bits & swap) | (c_bits & ~swap)) ^ (((quadrant + 1) & 2) << 62);  // 1, 2: -\n"
       "  sin_x = (Doubles)sin_bits;\n"
       "  cos_x = (Doubles)cos_bits;\n"
       "}\n"
       "#endif\n\n"
       "}  // namespace trig_detail\n\n"
       "template <std::size_t N>\n"
       "inline void sincos(const std::array<double, N>& x, std::array<double, N>& sin_x, std::array<double, N>& cos_x) noexcept {\n"
       "#if defined(WLX_GEN_SIMD_SINCOS)\n"
       "  using trig_detail::Doubles;\n"
       "  constexpr std::size_t lanes = trig_detail::kLanes, full = N / lanes * lanes;\n"
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
       "}\n\n";
  t += namespace_close(opt);
  return {"wlx/gen/trig.hpp", t};
}

}  // namespace wlx::codegen
