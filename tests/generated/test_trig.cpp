// trig.hpp: the batched sin/cos every generated function uses, against the C library.
#include <doctest/doctest.h>
#include <wlx/gen/trig.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace {

// glibc's sin and cos are within 1 ulp of the true values; the batched pass promises an absolute
// error of at most 1 ulp of 1 (2^-52) more, so the two differ by at most 2 * 2^-52 ~ 4.4e-16.
constexpr double kTolerance = 2 * std::numeric_limits<double>::epsilon();

template <std::size_t N>
double worst_error(const std::array<double, N>& x) {
  std::array<double, N> s, c;
  wlx::gen::sincos(x, s, c);
  double worst = 0;
  for (std::size_t i = 0; i < N; ++i)
    worst = std::max({worst, std::abs(s[i] - std::sin(x[i])), std::abs(c[i] - std::cos(x[i]))});
  return worst;
}

template <std::size_t N>
double worst_random_error(double range, std::mt19937_64& rng, int rounds) {
  std::uniform_real_distribution<double> u(-range, range);
  double worst = 0;
  for (int r = 0; r < rounds; ++r) {
    std::array<double, N> x;
    for (auto& v : x) v = u(rng);
    worst = std::max(worst, worst_error(x));
  }
  return worst;
}

}  // namespace

TEST_CASE("trig: sin and cos of random angles agree with the C library to 2 ulp of 1") {
  std::mt19937_64 rng(11);
  for (double range : {0.1, 1.0, std::numbers::pi, 10.0, 1e3, 1e6}) {
    CAPTURE(range);
    // Full vectors and every kind of partly filled last vector (2 or 4 lanes).
    CHECK(worst_random_error<1>(range, rng, 20000) <= kTolerance);
    CHECK(worst_random_error<3>(range, rng, 20000) <= kTolerance);
    CHECK(worst_random_error<21>(range, rng, 5000) <= kTolerance);
  }
}

TEST_CASE("trig: quadrant boundaries, their neighbours and signed zero") {
  std::array<double, 64> x{};
  std::size_t k = 0;
  for (int n = -8; n <= 8; n += 1) {
    if (k + 3 > x.size()) break;
    const double b = n * std::numbers::pi / 4;  // octant boundaries: where the reduction switches
    x[k++] = b;
    x[k++] = std::nextafter(b, 1e9);
    x[k++] = std::nextafter(b, -1e9);
  }
  CHECK(worst_error(x) <= kTolerance);
  std::array<double, 2> zeros{0.0, -0.0}, s, c;
  wlx::gen::sincos(zeros, s, c);
  CHECK(s[0] == 0.0);
  CHECK(!std::signbit(s[0]));
  CHECK(std::signbit(s[1]));  // sin(-0) = -0, as in the C library
  CHECK(c[0] == 1.0);
  CHECK(c[1] == 1.0);
}

TEST_CASE("trig: huge, infinite and NaN angles take the C library's values") {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  std::array<double, 5> x{2e6, -1e300, inf, -inf, nan}, s, c;
  wlx::gen::sincos(x, s, c);
  CHECK(s[0] == std::sin(2e6));
  CHECK(c[0] == std::cos(2e6));
  CHECK(s[1] == std::sin(-1e300));
  CHECK(c[1] == std::cos(-1e300));
  for (std::size_t i = 2; i < 5; ++i) {
    CHECK(std::isnan(s[i]));
    CHECK(std::isnan(c[i]));
  }
}
