// `wlx report` end to end: every run, every figure, a checks table without failures, valid HTML.
#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Well-formedness of the XHTML-style markup the report writes: every element closed, properly
// nested; returns the first problem or an empty string.
std::string markup_problem(const std::string& html) {
  std::vector<std::string> open;
  std::size_t pos = 0;
  while ((pos = html.find('<', pos)) != std::string::npos) {
    const std::size_t end = html.find('>', pos);
    if (end == std::string::npos) return "unterminated tag at " + std::to_string(pos);
    const std::string tag = html.substr(pos + 1, end - pos - 1);
    pos = end + 1;
    if (tag.empty()) return "empty tag";
    if (tag[0] == '!') continue;  // <!DOCTYPE html>
    if (tag.back() == '/') continue;  // <img ... />
    const bool closing = tag[0] == '/';
    const std::string name = tag.substr(closing ? 1 : 0, tag.find_first_of(" \t\n", closing ? 1 : 0) - (closing ? 1 : 0));
    if (!closing) {
      open.push_back(name);
    } else {
      if (open.empty() || open.back() != name) return "</" + name + "> closes " + (open.empty() ? "nothing" : "<" + open.back() + ">");
      open.pop_back();
    }
  }
  return open.empty() ? "" : "<" + open.back() + "> never closed";
}

}  // namespace

TEST_CASE("report: the full report runs, every image exists, every check passes, the HTML is well formed") {
  const fs::path dir = fs::temp_directory_path() / "wlx_report_test";
  fs::remove_all(dir);
  const std::string cmd = std::string(WLX_BINARY) + " report --out " + dir.string() + " > " + (dir.string() + ".log") + " 2>&1";
  const int status = std::system(cmd.c_str());
  INFO(slurp(dir.string() + ".log"));
  REQUIRE(WEXITSTATUS(status) == 0);
  const std::string html = slurp(dir / "index.html");
  REQUIRE(!html.empty());
  CHECK(markup_problem(html).empty());
  INFO(markup_problem(html));
  CHECK(html.find("class=\"fail\"") == std::string::npos);
  CHECK(html.find("class=\"pass\"") != std::string::npos);
  // Every referenced file exists and is not empty.
  const std::regex ref("(src|href)=\"([^\"#]+)\"");
  int images = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), ref); it != std::sregex_iterator(); ++it) {
    const fs::path file = dir / (*it)[2].str();
    CAPTURE(file);
    REQUIRE(fs::exists(file));
    CHECK(fs::file_size(file) > 100);
    images += file.extension() == ".png";
  }
  CHECK(images >= 50);
  // The CSV files behind the figures never hold NaN or Inf.
  for (const auto& e : fs::directory_iterator(dir / "data")) {
    const std::string text = slurp(e.path());
    CHECK(text.find("nan") == std::string::npos);
    CHECK(text.find("inf") == std::string::npos);
  }
  const std::string log = slurp(dir.string() + ".log");
  // Progress was shown, and its last step is numbered as the last of all.
  CHECK(std::regex_search(log, std::regex(R"(\[(\d+)/\1\] rendering)")));
  CHECK(html.find("Integrators compared") != std::string::npos);
  CHECK(log.find("open " + fs::absolute(dir / "index.html").string()) != std::string::npos);
}
