// wlx/support/text.hpp: every quoting function fed every dangerous character, and checked by the language
// itself where one is at hand (gnuplot runs the quoted strings, the C++ compiler compiles the
// literals and comments), otherwise by decoding the output back (HTML, JSON/JS, CSV).
#include <doctest/doctest.h>
#include <nlohmann/json.hpp>
#include <wlx/support/csv.hpp>
#include <wlx/support/text.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace std::string_literals;

namespace {

// What an attacker or a careless user puts in a label: a line break followed by a command, quotes
// of each kind, backslashes (also at the end), a script end tag, NUL, ill-formed UTF-8, trigraphs,
// a comment end, Unicode line separators, gnuplot's command substitution and macros, a formula.
const std::vector<std::string>& hostile() {
  static const std::vector<std::string> all{
      "a label\nsystem('touch PWNED')",
      "cr\rsystem('touch PWNED')",
      "it's 'quoted'",
      "say \"hi\"",
      "back\\slash",
      "ends in a backslash\\",
      "</script><script>alert(1)</script>",
      "nul\0after"s,
      "bad \xff\xfe utf-8 \xc0\xaf overlong",
      "cut \xe2\x82",
      "tri?\?/graph ?\?= ?\?' ?\?!",  // trigraphs' characters, escaped so compilers do not warn
      "comment */ end /* start",
      "line\xe2\x80\xa8separator\xe2\x80\xa9paragraph",
      "`touch PWNED` @macro",
      "=cmd|'/c calc'!A1",
      "a,b",
      " padded ",
      "tab\there",
      "\x7f del \xc2\x85 nel",
      "emoji \xf0\x9f\x98\x80 and \xc3\xa9",
      "",
  };
  return all;
}

// The text each quoting function promises to carry unchanged: valid UTF-8 without controls. For
// others, the promise is only that the output is well-formed; what it shows is U+FFFD instead.
bool clean(const std::string& s) { return wlx::text::check_one_line(s).empty(); }

std::string replaced(const std::string& s) {
  std::string out;
  wlx::text::for_each_printable(s, [&](char32_t, std::string_view bytes) { out += bytes; });
  return out;
}

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("wlx-text-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

}  // namespace

TEST_CASE("check_one_line names what is wrong and where") {
  using wlx::text::check_one_line;
  CHECK(check_one_line("plain text, it's \"fine\" \xc3\xa9 \xf0\x9f\x98\x80").empty());
  CHECK(check_one_line("a\nb") == "has a line break at byte 1 (one line of text expected)");
  CHECK(check_one_line("a\rb") == "has a line break at byte 1 (one line of text expected)");
  CHECK(check_one_line("ab\0"s) == "has the control character U+0000 at byte 2");
  CHECK(check_one_line("\t") == "has the control character U+0009 at byte 0");
  CHECK(check_one_line("x\xe2\x80\xa8") == "has the control character U+2028 at byte 1");
  CHECK(check_one_line("ok \xff") == "is not valid UTF-8 at byte 3");
  CHECK(check_one_line("\xc0\xaf") == "is not valid UTF-8 at byte 0");       // overlong '/'
  CHECK(check_one_line("\xed\xa0\x80") == "is not valid UTF-8 at byte 0");   // a surrogate
  CHECK(check_one_line("\xf4\x90\x80\x80") == "is not valid UTF-8 at byte 0");  // above U+10FFFF
}

TEST_CASE("gnuplot_string: gnuplot prints each string back and runs nothing") {
  if (std::system("gnuplot --version > /dev/null 2>&1") != 0) {
    MESSAGE("gnuplot not installed: only the structure is checked");
  }
  const fs::path script = scratch("strings.gp"), out = scratch("strings.out");
  const fs::path pwned = out.parent_path() / "PWNED";
  std::string gp;
  for (const auto& s : hostile()) {
    const std::string q = wlx::text::gnuplot_string(s);
    REQUIRE(q.size() >= 2);
    CHECK(q.front() == '\'');
    CHECK(q.back() == '\'');
    CHECK(q.find_first_of("\n\r"s + '\0') == std::string::npos);
    gp += "print " + q + "\nprint '--'\n";
  }
  std::ofstream(script, std::ios::binary) << gp;
  const std::string command = "cd '" + out.parent_path().string() + "' && gnuplot '" + script.string() + "' > '" + out.string() + "' 2>&1";
  if (std::system("gnuplot --version > /dev/null 2>&1") == 0) {
    REQUIRE(std::system(command.c_str()) == 0);
    CHECK_FALSE(fs::exists(pwned));
    std::istringstream printed(read(out));
    for (const auto& s : hostile()) {
      std::string line, sep;
      std::getline(printed, line);
      std::getline(printed, sep);
      CHECK(sep == "--");
      // gnuplot prints the string as it is: the input where it was clean, the replacement
      // character where it was not.
      CHECK(line == (clean(s) ? s : replaced(s)));
    }
  }
  fs::remove_all(out.parent_path());
}

TEST_CASE("html: the page shows the text and no markup from it") {
  const auto unescape = [](const std::string& h) {
    std::string out;
    for (std::size_t k = 0; k < h.size();) {
      if (h[k] != '&') {
        out += h[k++];
        continue;
      }
      const std::size_t end = h.find(';', k);
      REQUIRE(end != std::string::npos);
      const std::string entity = h.substr(k, end + 1 - k);
      if (entity == "&amp;") out += '&';
      else if (entity == "&lt;") out += '<';
      else if (entity == "&gt;") out += '>';
      else if (entity == "&quot;") out += '"';
      else if (entity == "&#39;") out += '\'';
      else FAIL("unexpected entity " << entity);
      k = end + 1;
    }
    return out;
  };
  for (const auto& s : hostile()) {
    const std::string h = wlx::text::html(s);
    CHECK(h.find_first_of("<>\"'\n\r"s + '\0') == std::string::npos);
    CHECK(wlx::text::check_one_line(h).empty());  // valid UTF-8, no controls
    CHECK(unescape(h) == (clean(s) ? s : replaced(s)));
  }
}

TEST_CASE("js_string: a JSON parser reads the literal back; no </script>, all ASCII") {
  for (const auto& s : hostile()) {
    const std::string j = wlx::text::js_string(s);
    for (const char c : j) CHECK((static_cast<unsigned char>(c) >= 0x20 && static_cast<unsigned char>(c) < 0x7f));
    CHECK(j.find_first_of("<>&") == std::string::npos);
    const auto parsed = nlohmann::json::parse(j);
    REQUIRE(parsed.is_string());
    // Controls survive as \u escapes (JavaScript carries them safely); ill-formed bytes become U+FFFD.
    if (wlx::text::check_one_line(s).find("UTF-8") == std::string::npos) CHECK(parsed.get<std::string>() == s);
    else CHECK(parsed.get<std::string>().find("\xef\xbf\xbd") != std::string::npos);
  }
  CHECK(wlx::text::js_string("\xf0\x9f\x98\x80") == "\"\\ud83d\\ude00\"");  // a surrogate pair, as JavaScript wants
}

TEST_CASE("csv_field: an RFC 4180 reader gets one field back, and no formula") {
  const auto read_field = [](const std::string& f) {
    if (f.empty() || f.front() != '"') {
      CHECK(f.find_first_of(",\"\n\r") == std::string::npos);
      return f;
    }
    REQUIRE(f.size() >= 2);
    REQUIRE(f.back() == '"');
    std::string out;
    for (std::size_t k = 1; k + 1 < f.size(); ++k) {
      if (f[k] == '"') {
        REQUIRE(f[k + 1] == '"');  // a lone quote would end the field early
        ++k;
      }
      out += f[k];
    }
    return out;
  };
  for (const auto& s : hostile()) {
    const std::string f = wlx::text::csv_field(s);
    CHECK(f.find_first_of("\n\r"s + '\0') == std::string::npos);
    const std::string back = read_field(f);
    if (s.starts_with("=")) CHECK(back == "'" + s);  // shown as text by spreadsheets
    else CHECK(back == (clean(s) ? s : replaced(s)));
  }
  CHECK(wlx::text::csv_field("-1.5e3") == "-1.5e3");  // numbers stay numbers
  CHECK(wlx::text::csv_field("+SUM(A1)") == "\"'+SUM(A1)\"");
}

TEST_CASE("cpp_string and cpp_comment: the compiler reads the literals back byte for byte, the comments stay comments") {
#ifndef WLX_TEST_CXX
  MESSAGE("no compiler given: only the structure is checked");
#endif
  std::string source = "#include <cstdio>\n#include <cstring>\nint main() {\n  int failures = 0;\n";
  for (std::size_t k = 0; k < hostile().size(); ++k) {
    const std::string& s = hostile()[k];
    const std::string lit = wlx::text::cpp_string(s), comment = wlx::text::cpp_comment(s);
    for (const std::string& out : {lit, comment})
      for (const char c : out) CHECK((static_cast<unsigned char>(c) >= 0x20 && static_cast<unsigned char>(c) < 0x7f));
    CHECK(comment.find("*/") == std::string::npos);
    CHECK(comment.find("??") == std::string::npos);
    CHECK(lit.find("??") == std::string::npos);
    CHECK((comment.empty() || comment.back() != '\\'));
    // A comment that ended early or let a line break through would leave `system('touch PWNED')`
    // or "end /* start" as code: the program would not compile.
    source += "  // " + comment + "\n  /* " + comment + " */\n";
    source += "  {\n    static const unsigned char expected[] = {";
    for (const char c : s) source += std::to_string(static_cast<int>(static_cast<unsigned char>(c))) + ",";
    source += "0};\n    static const char got[] = " + lit + ";\n";
    source += "    if (sizeof got != sizeof expected || std::memcmp(got, expected, sizeof got) != 0) { std::printf(\"case " +
              std::to_string(k) + "\\n\"); ++failures; }\n  }\n";
  }
  source += "  return failures;\n}\n";
#ifdef WLX_TEST_CXX
  const fs::path cpp = scratch("literals.cpp"), exe = scratch("literals");
  std::ofstream(cpp) << source;
  // -trigraphs: the language before C++17 (the generated headers are C++17, but a user's build may
  // ask for trigraphs); -Wcomment -Werror: a "/*" inside a comment or a spliced line is an error.
  for (const char* standard : {"-std=c++14 -trigraphs", "-std=c++17"}) {
    const std::string compile = std::string(WLX_TEST_CXX) + " " + standard + " -Wall -Wcomment -Werror -o '" + exe.string() + "' '" +
                                cpp.string() + "'";
    INFO(compile);
    REQUIRE(std::system(compile.c_str()) == 0);
    CHECK(std::system(exe.string().c_str()) == 0);
  }
  fs::remove_all(cpp.parent_path());
#endif
}

TEST_CASE("text: nearest suggests the closest name within a third of the key's length, case folded on request") {
  const std::vector<std::string> names{"duration", "dependent", "rates", "initial"};
  CHECK(wlx::text::nearest("duraton", names, false) == "duration");
  CHECK(wlx::text::nearest("RATES", names, true) == "rates");
  CHECK(wlx::text::nearest("RATES", names, false).empty());  // five substitutions: too far
  CHECK(wlx::text::nearest("xyz", names, true).empty());
  CHECK(wlx::text::nearest("", names, true).empty());
  // A key of a million characters is farther than its length's third from every name: none.
  CHECK(wlx::text::nearest(std::string(1'000'000, 'd'), names, true).empty());
  // ...and one near a long name is still found.
  const std::vector<std::string> long_names{std::string(300, 'a') + "b"};
  CHECK(wlx::text::nearest(std::string(300, 'a') + "c", long_names, false) == long_names[0]);
}

TEST_CASE("CsvWriter: every cell in its column, an empty text cell first included; full precision; nothing non-finite") {
  const fs::path path = fs::temp_directory_path() / ("wlx_csv_writer_" + std::to_string(::getpid()) + ".csv");
  {
    wlx::CsvWriter csv(path.string(), {"", "label", "x", "y"});
    csv.row({"", "b,c"}, {0.1, -2.5e-300});
    csv.row({"a", ""}, {1.0 / 3.0, 7});
    CHECK_THROWS_AS(csv.row({"a", "b"}, {1.0, std::nan("")}), wlx::Error);
    CHECK_THROWS_AS(csv.row({"a"}, {1.0, 2.0}), wlx::Error);  // three cells for four columns
    csv.commit();
  }
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  fs::remove(path);
  CHECK(text.str() == ",label,x,y\n,\"b,c\",0.10000000000000001,-2.5e-300\na,,0.33333333333333331,7\n");
}
