// Fuzz target: inverse kinematics on arbitrary numbers. Any input either solves with every
// output finite (and the closure satisfied when the numbers are of sane size) or is refused
// with a wlx::Error; nothing else may happen.
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  using namespace wlx;
  if (size < 1) return 0;
  static const Model model;
  static Data data;
  Coordinates s = nominal_inputs();
  const int branch_bits = bytes[0];
  ++bytes;
  --size;
  double sane = 0;
  for (int k = 0; k < kInputCount && size >= sizeof(double); ++k, bytes += sizeof(double), size -= sizeof(double)) {
    double v;
    std::memcpy(&v, bytes, sizeof v);
    s(k) = v;
    sane = std::max(sane, std::abs(v));
  }
  Branches branches;
  for (int l = 0; l < 4; ++l) branches.limb[static_cast<std::size_t>(l)] = (branch_bits >> (2 * l)) & (l < 2 ? 3 : 3);
  try {
    solve_ik_closed_form(model, s, branches);
  } catch (const Error&) {
    return 0;  // refused, with a message
  }
  if (!s.allFinite()) std::abort();  // a NaN escaped without an error
  if (sane < 1e3) {
    closure(model, data, s, false);
    if (!(data.Phi.cwiseAbs().maxCoeff() <= 1e-9 * (1 + sane))) std::abort();
    // Newton from the closed-form solution stays there.
    try {
      solve_ik_newton(model, data, s);
    } catch (const Error& e) {
      std::fprintf(stderr, "Newton left the closed-form solution: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}
