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

// Every square root the generated functions take is detail::square_root (types.hpp), which for
// double is one instruction: the library's sqrt must set errno for a negative argument, and clang
// then keeps a library call beside each one (a wheeled quadruped's kinematic_update ran 1.4x slower
// under clang than under GCC for it; tools/kernels_by_compiler.sh). Exempt: comments, square_root's
// own definition (Eigen's for double and float, the scalar type's own else) and the one square root
// of a constant (the IK's tolerance for float).
TEST_CASE("generated/: square roots through detail::square_root, none through the library's errno path") {
  const fs::path committed = WLX_COMMITTED_DIR;
  std::string found;
  long roots = 0;
  for (const auto& f : files_below(committed)) {
    if (fs::path(f).extension() != ".hpp") continue;
    std::istringstream in(slurp(committed / f));
    int number = 0;
    for (std::string line; std::getline(in, line);) {
      ++number;
      const std::string code = line.substr(0, line.find("//"));
      for (std::size_t at = code.find("square_root("); at != std::string::npos; at = code.find("square_root(", at + 1)) ++roots;
      if (code.find("sqrt(") == std::string::npos) continue;
      const bool definition = fs::path(f).filename() == "types.hpp" &&
                              (code.find("Eigen::numext::sqrt(x)") != std::string::npos || code == "  return sqrt(x);");
      if (!definition && code.find("kIkTolerance") == std::string::npos)
        found += "  generated/" + f + ":" + std::to_string(number) + ": " + line + "\n";
    }
  }
  INFO("square roots outside detail::square_root:\n" << found);
  CHECK(found.empty());
  CHECK(roots > 100);  // the built-in models take square roots (their IK and contact normals): the scan saw them
}
