// generated/ (committed, what users embed) must be exactly what wlx-gen produces now. The build
// regenerates into the build tree whenever the generator or the model changes; this compares.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace {

std::set<std::string> files_below(const fs::path& root) {
  std::set<std::string> out;
  if (!fs::exists(root)) return out;
  for (const auto& e : fs::recursive_directory_iterator(root))
    if (e.is_regular_file()) out.insert(fs::relative(e.path(), root).generic_string());
  return out;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("generated/ is fresh: byte-identical to what wlx-gen produces from the current model") {
  const fs::path fresh = WLX_FRESH_DIR, committed = WLX_COMMITTED_DIR;
  const auto a = files_below(fresh), b = files_below(committed);
  REQUIRE_MESSAGE(!a.empty(), "no freshly generated headers in " << fresh << " (did the build run wlx-gen?)");
  std::string problems;
  for (const auto& f : a) {
    if (!b.count(f)) problems += "  missing in generated/: " + f + "\n";
    else if (slurp(fresh / f) != slurp(committed / f)) problems += "  stale: generated/" + f + "\n";
  }
  for (const auto& f : b)
    if (!a.count(f)) problems += "  not produced by wlx-gen any more: generated/" + f + "\n";
  INFO("generated/ differs from the generator's output:\n"
       << problems << "Run `cmake --build build --target regenerate` and commit generated/.");
  CHECK(problems.empty());
}
