// Fuzz target: the JSON input paths of the CLI (wlx ik requests and scenario files). Any text
// either parses into a valid request or scenario, or is refused with a wlx::Error or a JSON
// parse error; a valid one then runs without a NaN in its results.
#include <input.hpp>
#include <scenario_io.hpp>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>

#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  using namespace wlx;
  const std::string text(reinterpret_cast<const char*>(bytes), size);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    return 0;
  }
  try {
    const commands::IkRequest r = commands::parse_ik_request(j);
    const Model model(r.params);
    Coordinates s = r.s;
    solve_ik_closed_form(model, s, r.branches);
    if (!s.allFinite()) std::abort();
  } catch (const Error&) {
  }
  try {
    Scenario sc = commands::parse_scenario(j);
    if (sc.samples() > 200) sc.duration = sc.dt * 200;  // keep each input fast
    const Trajectory tr = simulate(sc);
    for (const auto& smp : tr.samples)
      if (!smp.s.allFinite() || !smp.sdot.allFinite() || !smp.tau.allFinite()) std::abort();
  } catch (const Error&) {
  }
  return 0;
}
