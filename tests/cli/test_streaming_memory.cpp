// `wlx simulate` streams its samples to the CSV: peak memory does not grow with the number of
// steps. Its own program: the peak RSS a parent reads for a spawned child includes the parent's
// own at the time of the spawn (Linux carries it across exec), so the parent must stay small.
#include "../helpers/run_wlx.hpp"

#include <doctest/doctest.h>

#include <fstream>
#include <string>

using namespace wlx_test;

namespace {

long own_peak_kib() {
  std::ifstream status("/proc/self/status");
  std::string key;
  long value = 0;
  while (status >> key) {
    if (key == "VmHWM:") {
      status >> value;
      return value;
    }
    status.ignore(4096, '\n');
  }
  return -1;
}

}  // namespace

TEST_CASE("streaming: peak memory of wlx simulate is flat from 10^3 to 10^5 steps") {
#ifdef WLX_SANITIZED
  // AddressSanitizer keeps freed blocks in a quarantine of up to 256 MB: the memory measured would
  // be the sanitizer's, not wlx's. The release build runs this test.
  MESSAGE("skipped in a sanitized build");
  return;
#endif
  const fs::path dir = work_dir() / "rss";
  fs::create_directories(dir);
  long peak[2] = {0, 0};
  const char* steps[2] = {"1e-3", "1e-5"};
  for (int k = 0; k < 2; ++k) {
    write(dir / "s.json", std::string(R"({"rates": {"roll": 0.0872664626}, "dependent": ["y_C", "yaw"], "duration": 1, "dt": )") +
                              steps[k] + "}");
    const Result r = run({"simulate", (dir / "s.json").string(), "--out", (dir / "out").string()});
    REQUIRE(r.code == 0);
    peak[k] = r.peak_rss_kib;
    fs::remove_all(dir / "out");  // 80 MB of CSV at 10^5 steps
  }
  const long parent = own_peak_kib();
  MESSAGE("peak RSS of wlx simulate: " << peak[0] << " KiB at 10^3 steps, " << peak[1] << " KiB at 10^5 steps (this test: "
                                       << parent << " KiB)");
  // The numbers are wlx's own only if this process was smaller.
  REQUIRE(parent < peak[0]);
  // Keeping the samples took ~740 bytes each: 72 MiB more at 10^5 steps. Streaming adds nothing
  // per step; 4 MiB allows for allocator and page-cache noise.
  CHECK(peak[1] - peak[0] <= 4 * 1024);
}

TEST_CASE("streaming: ik --batch does not store a line beyond its cap: 32 MiB without a newline costs no memory") {
#ifdef WLX_SANITIZED
  MESSAGE("skipped in a sanitized build");
  return;
#endif
  // Written in blocks: a 32 MiB string here would raise this process's peak, which the child's
  // measured peak includes.
  const fs::path input = work_dir() / "endless-line";
  {
    std::ofstream out(input, std::ios::binary);
    out << "{}\n";
    const std::string block(1u << 16, ' ');
    for (int k = 0; k < 512; ++k) out << block;
  }
  Io small_input;
  small_input.input = "{}\n";
  Io endless_input;
  endless_input.stdin_path = input;
  const Result small = run({"ik", "--batch"}, small_input);
  const Result endless = run({"ik", "--batch"}, endless_input);
  fs::remove(input);
  REQUIRE(small.code == 0);
  CHECK(endless.code == 2);
  CHECK(endless.err.find("line 2: longer than 1048576 bytes") != std::string::npos);
  const long parent = own_peak_kib();
  REQUIRE(parent < small.peak_rss_kib);
  MESSAGE("peak RSS of wlx ik --batch: " << small.peak_rss_kib << " KiB for one short line, " << endless.peak_rss_kib
                                         << " KiB with a 32 MiB line (this test: " << parent << " KiB)");
  // Stored, the line would take 32 MiB or more (std::string doubles its capacity as it grows).
  CHECK(endless.peak_rss_kib - small.peak_rss_kib <= 4 * 1024);
}
