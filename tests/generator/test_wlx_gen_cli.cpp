// wlx-gen as a user runs it: bad options and bad values exit 2 naming the option and the reason,
// and nothing is written; the emitted namespace and baked values are validated before emission.
#include "../support/run_wlx.hpp"

#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/statvfs.h>

#include <cerrno>
#include <cstring>
#include <map>

namespace {

struct Case {
  const char* what;
  std::vector<std::string> args;  // after the model file and --out
  const char* message;
};

}  // namespace

TEST_CASE("wlx-gen: every bad option or value exits 2 with the reason, and writes nothing") {
  const std::filesystem::path out = wlx_test::work_dir() / "gen";
  const Case cases[] = {
      {"unknown parameter to bake", {"--bake", "lgD=1.6"}, "no parameter 'lgD' (did you mean 'legD'?)"},
      {"negative length baked", {"--bake", "legD=-1"}, "'legD' is a length, which must be positive"},
      {"zero mass baked", {"--bake", "m_M1=0"}, "'m_M1' is a mass, which must be positive"},
      {"negative gravity baked", {"--bake", "g=-9.81"}, "'g' is gravity, which must be non-negative"},
      {"not a number", {"--bake", "legD=abc"}, "the value of 'legD' is not a finite number"},
      {"infinite", {"--bake", "legD=inf"}, "the value of 'legD' is not a finite number"},
      {"no value", {"--bake", "legD"}, "expected NAME=VALUE"},
      {"code in the namespace", {"--namespace", "x { } int evil(){return 1;} namespace y"}, "is not a C++ qualified name"},
      {"namespace starting with a digit", {"--namespace", "1bad"}, "is not a C++ qualified name"},
      {"unknown option", {"--bogus"}, "--bogus"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.what);
    std::filesystem::remove_all(out);
    std::vector<std::string> args = {WLX_MODEL_FILE, "--out", out.string(), "--quiet"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const auto r = wlx_test::run(args);
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.rfind("wlx-gen: error: ", 0) == 0);
    CHECK(r.err.find(c.message) != std::string::npos);
    CHECK(!std::filesystem::exists(out));
  }
  const auto missing = wlx_test::run({"/nonexistent/model.yaml", "--out", out.string()});
  CHECK(missing.code == 2);
  CHECK(missing.err.find("cannot open the model file") != std::string::npos);
  const auto version = wlx_test::run({"--version"});
  CHECK(version.code == 0);
  CHECK(version.out.find('.') != std::string::npos);
}

TEST_CASE("wlx-gen: a baked parameter's field in params.hpp holds the baked value") {
  const std::filesystem::path out = wlx_test::work_dir() / "baked";
  const auto r = wlx_test::run({WLX_MODEL_FILE, "--out", out.string(), "--quiet", "--bake", "legD=1.75"});
  REQUIRE(r.code == 0);
  const std::string params = wlx_test::slurp(out / "wlx" / "gen" / "params.hpp");
  CHECK(params.find("double legD = 1.75;  // m: knee-to-foot length of a leg (baked:") != std::string::npos);
  CHECK(params.find("double legD = 1.5;") == std::string::npos);
}

TEST_CASE("wlx-gen: a header an earlier wlx-gen wrote and this one no longer produces is removed; others stay") {
  const std::filesystem::path out = wlx_test::work_dir() / "stale";
  std::filesystem::remove_all(out);
  REQUIRE(wlx_test::run({WLX_MODEL_FILE, "--out", out.string(), "--quiet"}).code == 0);
  const std::filesystem::path dir = out / "wlx" / "gen";
  const std::string kinematics = wlx_test::slurp(dir / "kinematics.hpp");
  // A dropped function's header: the banner of a real one under another name.
  wlx_test::write(dir / "dropped_function.hpp", kinematics);
  wlx_test::write(dir / "users_own.hpp", "// mine\n//\n// not generated\n");
  const auto r = wlx_test::run({WLX_MODEL_FILE, "--out", out.string()});
  REQUIRE(r.code == 0);
  CHECK(r.out.find("1 stale removed") != std::string::npos);
  CHECK(!std::filesystem::exists(dir / "dropped_function.hpp"));
  CHECK(std::filesystem::exists(dir / "users_own.hpp"));
  CHECK(wlx_test::slurp(dir / "kinematics.hpp") == kinematics);
}

// ---- hostile model files (issue 26) ----

namespace {

std::string arm_text() { return wlx_test::slurp(WLX_ARM_MODEL_FILE); }

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE_MESSAGE(at != std::string::npos, "anchor not in arm.yaml: " << from);
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("wlx-gen: text from the model file cannot add code to the headers: they compile and hold the text as written") {
  // A body meaning that closes its string and the array, a parameter meaning that ends a block
  // comment and forms a trigraph, a description with quotes, and a file name with a line break
  // and a #define (it is in every banner).
  const std::string meaning = R"(x", "y"}}; int injected = 1; //)";
  const std::string param_meaning = R"(*/ #define evil 1 /* ??/)";
  std::string text = replaced(arm_text(), "{name: upper, frame: upper,", "{name: upper, meaning: '" + meaning + "', frame: upper,");
  text = replaced(text, "meaning: upper arm length}", "meaning: '" + param_meaning + "'}");
  text = replaced(text, "description: a fixed three-joint arm (no closure, no wheels)", R"(description: 'say "hi" \ there')");
  const std::filesystem::path dir = wlx_test::work_dir() / "hostile-text";
  std::filesystem::create_directories(dir);
  const std::filesystem::path model = dir / "arm\n#define upper 0\n.yaml";
  wlx_test::write(model, text);
  const std::filesystem::path out = dir / "out";
  const auto r = wlx_test::run({model.string(), "--out", out.string(), "--quiet"});
  CAPTURE(r.err);
  REQUIRE(r.code == 2);  // the backslash in the description: text is one plain line
  CHECK(r.err.find("description: 'say \"hi\" \\ there' has a backslash") != std::string::npos);
  // The message shows the file name's line breaks escaped: one line on the terminal.
  CHECK(r.err.find("error: arm\\x0a#define upper 0\\x0a.yaml:4:14: description") != std::string::npos);
  text = replaced(text, R"(description: 'say "hi" \ there')", R"(description: 'say "hi" there')");
  wlx_test::write(model, text);
  const auto ok = wlx_test::run({model.string(), "--out", out.string(), "--quiet"});
  CAPTURE(ok.err);
  REQUIRE(ok.code == 0);
  const std::string types = wlx_test::slurp(out / "wlx" / "gen" / "types.hpp");
  CHECK(types.find("from model \"arm\" (arm\\x0a#define upper 0\\x0a.yaml, fingerprint") != std::string::npos);
  // The compiler is the judge: the headers compile (with trigraphs on too), nothing was defined,
  // and the strings are the file's text byte for byte.
  const std::filesystem::path check = dir / "check.cpp";
  wlx_test::write(check, "#include <wlx/gen/types.hpp>\n#include <wlx/gen/params.hpp>\n"
                         "#ifdef evil\n#error a comment let a #define through\n#endif\n"
                         "using namespace wlx::arm::gen;\n"
                         "static_assert(kBodyMeanings[body::upper] == std::string_view(R\"~(" + meaning + ")~\"));\n"
                         "static_assert(kParamInfo[1].meaning == std::string_view(R\"~(" + param_meaning + ")~\"));\n"
                         "static_assert(kModelDescription == std::string_view(R\"~(say \"hi\" there)~\"));\n"
                         "int main() { return 0; }\n");
  for (const char* standard : {"-std=c++17 -trigraphs", "-std=c++17"}) {
    const std::string compile = std::string(WLX_TEST_CXX) + " " + standard + " -fsyntax-only -Wall -Werror -isystem " + WLX_EIGEN_INCLUDE +
                                " -I'" + out.string() + "' '" + check.string() + "' 2>&1";
    INFO(compile);
    CHECK(std::system(compile.c_str()) == 0);
  }
}

TEST_CASE("wlx-gen: names that are keywords or macros of the compiler or the headers exit 2 before anything is written") {
  const std::filesystem::path dir = wlx_test::work_dir() / "reserved";
  std::filesystem::create_directories(dir);
  const std::filesystem::path model = dir / "arm.yaml", out = dir / "out";
  // Each would compile into a header that does not compile (unix and linux are 1 under GNU
  // modes; M_PI, EOF, errno are macros of <cmath> and the C library).
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"model: arm", "model: unix"},
      {"{name: column, parent: K0", "{name: linux, parent: K0"},
      {"{name: upper, frame: upper,", "{name: M_PI, frame: upper,"},
      {"{name: tip, parent: fore", "{name: EOF, parent: fore"},
      {"{name: turn, unit: rad", "{name: errno, unit: rad"},
      {"{name: forearm, value", "{name: std, value"},
      {"{name: fore, frame: fore", "{name: Eigen, frame: fore"},
      {"model: arm", "model: gen"},
  };
  for (const auto& [from, to] : cases) {
    CAPTURE(to);
    std::filesystem::remove_all(out);
    wlx_test::write(model, replaced(arm_text(), from, to));
    const auto r = wlx_test::run({model.string(), "--out", out.string(), "--quiet"});
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("cannot be") != std::string::npos);
    CHECK(r.err.rfind("wlx-gen: error: arm.yaml:", 0) == 0);
    CHECK(!std::filesystem::exists(out));
  }
  for (const char* ns : {"std", "mine::unix", "Eigen::x", "M_PI", "a::int"}) {
    CAPTURE(ns);
    const auto r = wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet", "--namespace", ns});
    CHECK(r.code == 2);
    CHECK(r.err.find("--namespace: '") != std::string::npos);
    CHECK(r.err.find("cannot be used") != std::string::npos);
  }
  CHECK(wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet", "--namespace", "mine::robot"}).code == 0);
}

TEST_CASE("wlx-gen: a model file that never ends or is not a file exits 2 at once, naming it") {
  const std::filesystem::path dir = wlx_test::work_dir() / "not-a-file";
  std::filesystem::create_directories(dir);
  const std::filesystem::path fifo = dir / "model.fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"/dev/zero", "is a device, not a regular file"},
      {fifo.string(), "is a pipe (FIFO), not a regular file"},  // no writer: must not wait for one
      {dir.string(), "is a folder"},
  };
  for (const auto& [path, reason] : cases) {
    CAPTURE(path);
    const auto r = wlx_test::run({path, "--out", (dir / "out").string(), "--quiet"});
    CAPTURE(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(reason) != std::string::npos);
  }
  // 10^5 frames in a cycle (the file that overflowed the stack) is beyond the size bound.
  std::string frames;
  for (int k = 0; k < 100000; ++k) frames += "  - {name: f" + std::to_string(k) + ", parent: f" + std::to_string((k + 1) % 100000) + ", chain: []}\n";
  wlx_test::write(dir / "cycle.yaml", replaced(arm_text(), "frames:\n", "frames:\n" + frames));
  const auto r = wlx_test::run({(dir / "cycle.yaml").string(), "--out", (dir / "out").string(), "--quiet"});
  CHECK(r.signal == 0);
  CHECK(r.code == 2);
  CHECK(r.err.find("more than the limit of 1048576 bytes") != std::string::npos);
}

// ---- wlx-gen's writes (issue 26) ----

namespace {

// The files under `dir` (relative path -> content).
std::map<std::string, std::string> tree(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.is_regular_file() || e.is_symlink()) files[std::filesystem::relative(e.path(), dir).string()] = wlx_test::slurp(e.path());
  return files;
}

}  // namespace

TEST_CASE("wlx-gen: a planted symlink is never written through; a link under a header's name is replaced, its target untouched") {
  const std::filesystem::path dir = wlx_test::work_dir() / "symlinks", out = dir / "out", gen = out / "wlx" / "gen";
  std::filesystem::create_directories(gen);
  wlx_test::write(dir / "victim", "precious");
  wlx_test::write(dir / "victim2", "precious too");
  // The fixed temporary name an earlier wlx-gen used, and a header's own name.
  std::filesystem::create_symlink(dir / "victim", gen / "types.hpp.tmp");
  std::filesystem::create_symlink(dir / "victim2", gen / "params.hpp");
  const auto r = wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet"});
  CAPTURE(r.err);
  REQUIRE(r.code == 0);
  CHECK(wlx_test::slurp(dir / "victim") == "precious");
  CHECK(wlx_test::slurp(dir / "victim2") == "precious too");
  CHECK(!std::filesystem::is_symlink(gen / "params.hpp"));
  CHECK(wlx_test::slurp(gen / "params.hpp").find("struct Params") != std::string::npos);
  for (const auto& e : std::filesystem::directory_iterator(gen))
    if (e.path().filename() != "types.hpp.tmp") CHECK(e.path().extension() == ".hpp");  // no temporary of this run left
}

TEST_CASE("wlx-gen: a full disk exits 74 naming the header; the previous header set stays whole, no temporary left") {
  const std::filesystem::path disk = wlx_test::work_dir() / "small-disk";
  std::filesystem::create_directories(disk);
  if (::mount("tmpfs", disk.c_str(), "tmpfs", 0, "size=512k") != 0) {
    MESSAGE("skipped: cannot mount a tmpfs here (" << std::strerror(errno) << "): needs root or CAP_SYS_ADMIN");
    return;
  }
  const std::filesystem::path out = disk / "out", model = wlx_test::work_dir() / "arm-changed.yaml";
  REQUIRE(wlx_test::run({WLX_ARM_MODEL_FILE, "--out", out.string(), "--quiet"}).code == 0);
  const auto before = tree(out);
  REQUIRE(before.size() > 5);
  // Another model text: every header changes (its banner's fingerprint). Then the disk is filled
  // to within 32 KiB, less than the set needs.
  wlx_test::write(model, replaced(arm_text(), "value: 0.6, unit: m", "value: 0.61, unit: m"));
  struct statvfs fs {};
  REQUIRE(::statvfs(disk.c_str(), &fs) == 0);
  const std::size_t free_bytes = fs.f_bavail * fs.f_frsize;
  REQUIRE(free_bytes > 32768);
  wlx_test::write(disk / "filler", std::string(free_bytes - 32768, 'x'));
  const auto r = wlx_test::run({model.string(), "--out", out.string(), "--quiet"});
  CAPTURE(r.err);
  CHECK(r.code == 74);
  CHECK(r.err.find(".hpp: ") != std::string::npos);
  CHECK(r.err.find("No space left on device") != std::string::npos);
  CHECK(tree(out) == before);  // byte for byte the earlier set, nothing added
  ::umount2(disk.c_str(), MNT_DETACH);
}
