// A 10^6-step run: the holonomic closure does not drift, the wheel residual stays bounded, and
// memory stays flat.
#include <doctest/doctest.h>
#include <wlx/kinematics.hpp>
#include <wlx/simulation.hpp>

#include <fstream>
#include <numbers>
#include <string>

using namespace wlx;
namespace c = gen::coord;

namespace {

long resident_kib() {
  std::ifstream status("/proc/self/status");
  std::string key;
  long value = 0;
  while (status >> key) {
    if (key == "VmRSS:") {
      status >> value;
      return value;
    }
    status.ignore(4096, '\n');
  }
  return -1;
}

#ifdef WLX_SANITIZED
// Under AddressSanitizer a step costs some 70 times as much: the sanitized tree runs 10^5 steps,
// which take every path of the 10^6 (the memory checks are the sanitizers' own there); the normal
// tree runs all 10^6, which is what shows drift and growth.
constexpr long kSteps = 100000;
#else
constexpr long kSteps = 1000000;
#endif

}  // namespace

TEST_CASE("long run: ST-A1+ in 10^6 RK4 steps: closure residual <= 1e-12 all the way, memory flat, same end state") {
  // The thesis' steering-by-roll run (roll' = 5 deg/s for 2 s, (y_C', yaw') dependent and far
  // from zero) with a 2 microsecond step: 10^6 steps of integration.
  Scenario sc;
  sc.rates(c::roll) = 5 * std::numbers::pi / 180;
  sc.duration = 2.0;
  sc.dt = sc.duration / kSteps;
  const Model model;
  Data data;
  double worst_closure = 0, worst_nh = 0;
  long samples = 0, rss_at_10_percent = 0;
  Coordinates last;
  const Trajectory status = simulate_each(sc, [&](const Sample& smp) {
    ++samples;
    if (samples % 97 == 0) {  // the closure is solved in closed form every step; check a spread of them
      closure(model, data, smp.s, false);
      worst_closure = std::max(worst_closure, data.Phi.cwiseAbs().maxCoeff());
    }
    worst_nh = std::max(worst_nh, smp.nh_residual.cwiseAbs().maxCoeff());
    if (samples == kSteps / 10) rss_at_10_percent = resident_kib();
    last = smp.s;
  });
  const long rss_at_end = resident_kib();
  MESSAGE(samples << " samples; max closure residual " << worst_closure << ", max |v_W . n_W| " << worst_nh
                  << "; resident memory " << rss_at_10_percent << " KiB at 10%, " << rss_at_end << " KiB at the end");
  REQUIRE(status.complete);
  CHECK(samples == kSteps + 1);
  CHECK(worst_closure <= 1e-12);
  CHECK(worst_nh <= 1e-12);
  CHECK(rss_at_end - rss_at_10_percent <= 256);  // KiB: no growth with the number of steps
  // RK4 is converged at 1 ms already (docs/excavator.md section 5): a step 500 (sanitized: 50)
  // times finer lands on the same state.
  const double fine_dt = sc.dt;
  sc.dt = 1e-3;
  const Trajectory coarse = simulate(sc);
  const double difference = (coarse.samples.back().s - last).cwiseAbs().maxCoeff();
  MESSAGE("|end state (1 ms) - end state (" << fine_dt * 1e6 << " us)| = " << difference);
  CHECK(difference <= 1e-11);
  CHECK(std::abs(last(c::yaw)) > 0.2);  // the dependent pair really moved (yaw ~ -13.5 deg)
}
