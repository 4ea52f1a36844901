// trig.hpp: the batched sin/cos every generated function uses, against the C library.
#include <doctest/doctest.h>
#include <wlx/gen/trig.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

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

namespace {

// Distance in units of the last place of the reference value.
double ulps(double value, double reference) {
  const double a = std::abs(reference);
  const double ulp = std::nextafter(a, std::numeric_limits<double>::infinity()) - a;
  return std::abs(value - reference) / ulp;
}

// The batched atan2 is within 1.5 ulp of the correctly rounded value, glibc's within 1 ulp: the
// two differ by at most 2.5 ulp.
constexpr double kAtan2Ulps = 2.5;

template <std::size_t N>
double worst_atan2_ulps(const std::array<double, N>& y, const std::array<double, N>& x) {
  std::array<double, N> angle;
  wlx::gen::atan2(y, x, angle);
  double worst = 0;
  for (std::size_t i = 0; i < N; ++i) {
    double reference = std::atan2(y[i], x[i]);
    // A half turn is +pi, y = -0 included (see below); -pi + tiny still rounds to -pi.
    if (reference == -std::numbers::pi && y[i] == 0) reference = std::numbers::pi;
    worst = std::max(worst, ulps(angle[i], reference));
  }
  return worst;
}

template <std::size_t N>
double worst_random_atan2(double y_scale, double x_scale, std::mt19937_64& rng, int rounds) {
  std::uniform_real_distribution<double> u(-1, 1);
  double worst = 0;
  for (int r = 0; r < rounds; ++r) {
    std::array<double, N> y, x;
    for (std::size_t i = 0; i < N; ++i) y[i] = y_scale * u(rng), x[i] = x_scale * u(rng);
    worst = std::max(worst, worst_atan2_ulps(y, x));
  }
  return worst;
}

}  // namespace

TEST_CASE("trig: atan2 of random points agrees with the C library to 2.5 ulp, at every scale and octant") {
  std::mt19937_64 rng(17);
  for (double y_scale : {1e-300, 1e-8, 1.0, 1e8, 1e300})
    for (double x_scale : {1e-300, 1e-8, 1.0, 1e8, 1e300}) {
      CAPTURE(y_scale);
      CAPTURE(x_scale);
      CHECK(worst_random_atan2<1>(y_scale, x_scale, rng, 4000) <= kAtan2Ulps);
      CHECK(worst_random_atan2<3>(y_scale, x_scale, rng, 4000) <= kAtan2Ulps);
      CHECK(worst_random_atan2<12>(y_scale, x_scale, rng, 1000) <= kAtan2Ulps);
    }
}

TEST_CASE("trig: atan2 at the reduction's boundaries: the diagonals, the eighths and their neighbours") {
  // t = |y| / |x| at k/8 and (2k - 1)/16 (where the nearest eighth switches), 1/8 (where the
  // reduction starts), on the diagonal and off it by one ulp, in all four quadrants.
  std::vector<double> ts;
  for (int k = 0; k <= 16; ++k) {
    const double t = k / 16.0;
    ts.insert(ts.end(), {t, std::nextafter(t, 0.0), std::nextafter(t, 2.0)});
  }
  double worst = 0;
  for (double t : ts)
    for (double sy : {1.0, -1.0})
      for (double sx : {1.0, -1.0}) {
        const std::array<double, 2> y{sy * t * 0.7, sy * 0.7}, x{sx * 0.7, sx * t * 0.7};  // below and above the diagonal
        worst = std::max(worst, worst_atan2_ulps(y, x));
      }
  CHECK(worst <= kAtan2Ulps);
}

TEST_CASE("trig: atan2 on the axes and at the origin: angles in (-pi, pi], a half turn is +pi") {
  const double pi = std::numbers::pi;
  std::array<double, 10> y{0.0, -0.0, 0.0, -0.0, 1.0, -1.0, 0.0, -0.0, 0.0, -0.0};
  std::array<double, 10> x{1.0, 1.0, -1.0, -1.0, 0.0, 0.0, 0.0, 0.0, -0.0, -0.0};
  std::array<double, 10> angle;
  wlx::gen::atan2(y, x, angle);
  CHECK(angle[0] == 0.0);
  CHECK(angle[1] == 0.0);
  CHECK(angle[2] == pi);
  CHECK(angle[3] == pi);  // the C library gives -pi; the joints' convention is (-pi, pi]
  CHECK(angle[4] == pi / 2);
  CHECK(angle[5] == -pi / 2);
  CHECK(angle[6] == 0.0);  // the origin: no direction, angle 0 (as the C library for +0)
  CHECK(angle[7] == 0.0);
  CHECK(angle[8] == pi);
  CHECK(angle[9] == pi);
}

TEST_CASE("trig: atan2 of infinite and NaN arguments takes the C library's values") {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  std::array<double, 6> y{inf, 1.0, -inf, nan, 1.0, inf}, x{1.0, -inf, -inf, 1.0, nan, inf}, angle;
  wlx::gen::atan2(y, x, angle);
  CHECK(angle[0] == std::atan2(inf, 1.0));
  CHECK(angle[1] == std::numbers::pi);
  CHECK(angle[2] == std::atan2(-inf, -inf));
  CHECK(std::isnan(angle[3]));
  CHECK(std::isnan(angle[4]));
  CHECK(angle[5] == std::atan2(inf, inf));
}
