// The plugin cache's trust checks on its folder (cli/shell/model_plugin.cpp), which run in wlx
// before anything is generated, compiled or loaded: here they run in the sanitized tree too
// (ASan, UBSan), where test_model_file_plugin, which compiles plugins, does not. CXX=/bin/false:
// a check that let a bad folder pass would end in a failed compile, never in a minute's build.
#include "../helpers/run_wlx.hpp"

#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace fs = std::filesystem;
using wlx_test::run;

namespace {

// Runs `wlx --model-file FILE fk` with the cache in `cache`; the file is no model (wlx-gen refuses
// it), so a folder the checks let pass ends at wlx-gen's error, and nothing is compiled.
wlx_test::Result run_with_cache(const fs::path& cache) {
  const fs::path model = wlx_test::work_dir() / "not_a_model.yaml";
  wlx_test::write(model, "model: not_a_model\n");
  ::setenv("WLX_CACHE_DIR", cache.c_str(), 1);
  ::setenv("CXX", "/bin/false", 1);
  const wlx_test::Result r = run({"--model-file", model.string(), "fk"}, {.input = "{}"});
  ::unsetenv("WLX_CACHE_DIR");
  ::unsetenv("CXX");
  return r;
}

}  // namespace

TEST_CASE("--model-file: a cache folder others may write, or another user's, or a link to one, is refused before wlx-gen runs (exit 2)") {
  const fs::path open = wlx_test::work_dir() / "open-cache";
  fs::create_directories(open);
  fs::permissions(open, fs::perms::all);  // 0777: anyone could plant a plugin.so
  auto r = run_with_cache(open);
  CHECK(r.code == 2);
  CHECK(r.err.find("the cache's folder " + open.string() + " may be written by others (mode 0777)") != std::string::npos);
  CHECK(r.err.find("wlx-gen") == std::string::npos);  // refused before the model file was read by wlx-gen

  fs::permissions(open, fs::perms::owner_all | fs::perms::group_all);  // 0770: the group may write
  r = run_with_cache(open);
  CHECK(r.code == 2);
  CHECK(r.err.find("may be written by others (mode 0770)") != std::string::npos);

  // A link is followed to the folder it names, and that folder is judged.
  const fs::path link = wlx_test::work_dir() / "linked-cache";
  fs::create_directory_symlink(open, link);
  r = run_with_cache(link);
  CHECK(r.code == 2);
  CHECK(r.err.find("may be written by others (mode 0770)") != std::string::npos);

  // The user's own, private folder passes: the run reaches wlx-gen, which refuses the file.
  fs::permissions(open, fs::perms::owner_all);
  r = run_with_cache(open);
  CHECK(r.code == 2);
  CHECK(r.err.find("may be written by others") == std::string::npos);
  CHECK(r.err.find("missing field 'parameters'") != std::string::npos);

  if (::geteuid() == 0) {  // root can give a folder away: another user's cache
    REQUIRE(::chown(open.c_str(), 65534, 65534) == 0);
    r = run_with_cache(open);
    CHECK(r.code == 2);
    CHECK(r.err.find("the cache's folder " + open.string() + " belongs to another user (uid 65534)") != std::string::npos);
  }
}
