// Text from a file, checked where it is read and quoted where it is written: one function per
// output language, so that no string a user or an attacker wrote can end a literal, a comment
// or a line of the file it lands in (a gnuplot script, an HTML page, a JavaScript file, a CSV
// file, a generated C++ header). Every quoting function takes any bytes (NUL, control
// characters, ill-formed UTF-8) and returns text that is valid in its language; readers still
// reject such text with check_one_line() so that the user hears about it instead of reading a
// replaced character. Header-only and free of dependencies: the generator uses it too.
#pragma once

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace wlx::text {

// Length of the well-formed UTF-8 sequence at text[k] (RFC 3629; Unicode table 3-7: no overlong
// forms, no surrogates, nothing above U+10FFFF), or 0 where the bytes are ill-formed.
inline std::size_t utf8_length(std::string_view text, std::size_t k) {
  const auto byte = [&](std::size_t i) { return k + i < text.size() ? static_cast<unsigned char>(text[k + i]) : 0u; };
  const unsigned c = byte(0);
  const auto in = [](unsigned v, unsigned lo, unsigned hi) { return v >= lo && v <= hi; };
  if (c < 0x80) return 1;
  if (in(c, 0xC2, 0xDF)) return in(byte(1), 0x80, 0xBF) ? 2 : 0;
  if (in(c, 0xE0, 0xEF)) {
    const unsigned lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
    return in(byte(1), lo, hi) && in(byte(2), 0x80, 0xBF) ? 3 : 0;
  }
  if (in(c, 0xF0, 0xF4)) {
    const unsigned lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
    return in(byte(1), lo, hi) && in(byte(2), 0x80, 0xBF) && in(byte(3), 0x80, 0xBF) ? 4 : 0;
  }
  return 0;
}

// The code point of the well-formed sequence of `length` bytes at text[k].
inline char32_t utf8_decode(std::string_view text, std::size_t k, std::size_t length) {
  const auto b = [&](std::size_t i) { return static_cast<char32_t>(static_cast<unsigned char>(text[k + i])); };
  switch (length) {
    case 1: return b(0);
    case 2: return (b(0) & 0x1F) << 6 | (b(1) & 0x3F);
    case 3: return (b(0) & 0x0F) << 12 | (b(1) & 0x3F) << 6 | (b(2) & 0x3F);
    default: return (b(0) & 0x07) << 18 | (b(1) & 0x3F) << 12 | (b(2) & 0x3F) << 6 | (b(3) & 0x3F);
  }
}

// C0 controls, DEL, and the C1 controls and line/paragraph separators (U+0085, U+2028, U+2029),
// which some readers take for line ends.
inline bool is_control(char32_t c) { return c < 0x20 || c == 0x7F || (c >= 0x80 && c <= 0x9F) || c == 0x2028 || c == 0x2029; }

// Why `s` is not one line of printable UTF-8 text ("has a newline at byte 3", "has the control
// character U+0000 at byte 0", "is not valid UTF-8 at byte 7"), or "" when it is. Readers call
// this on every text field that reaches an output (labels, titles, names, descriptions).
inline std::string check_one_line(std::string_view s) {
  char buffer[96];
  for (std::size_t k = 0; k < s.size();) {
    const std::size_t length = utf8_length(s, k);
    if (length == 0) {
      std::snprintf(buffer, sizeof buffer, "is not valid UTF-8 at byte %zu", k);
      return buffer;
    }
    const char32_t c = utf8_decode(s, k, length);
    if (c == '\n' || c == '\r') {
      std::snprintf(buffer, sizeof buffer, "has a line break at byte %zu (one line of text expected)", k);
      return buffer;
    }
    if (is_control(c)) {
      std::snprintf(buffer, sizeof buffer, "has the control character U+%04X at byte %zu", static_cast<unsigned>(c), k);
      return buffer;
    }
    k += length;
  }
  return "";
}

// Calls `each(code_point, bytes)` for every character of `s`, with U+FFFD for each ill-formed
// byte and for every control character: the common first step of the quoting functions whose
// languages take any Unicode text (gnuplot, HTML, CSV).
template <class Each>
void for_each_printable(std::string_view s, Each each) {
  constexpr std::string_view kReplacement = "\xEF\xBF\xBD";
  for (std::size_t k = 0; k < s.size();) {
    const std::size_t length = utf8_length(s, k);
    if (length == 0) {
      each(char32_t{0xFFFD}, kReplacement);
      ++k;
      continue;
    }
    const char32_t c = utf8_decode(s, k, length);
    if (is_control(c)) each(char32_t{0xFFFD}, kReplacement);
    else each(c, s.substr(k, length));
    k += length;
  }
}

// A gnuplot single-quoted string literal, quotes included: 'it''s'. In single quotes gnuplot
// expands nothing (no backslash escapes, no `command` substitution, no @macros); a quote is
// doubled, and a line break (which would end the command and start the next) cannot occur.
inline std::string gnuplot_string(std::string_view s) {
  std::string out = "'";
  for_each_printable(s, [&](char32_t c, std::string_view bytes) { out += c == '\'' ? std::string_view("''") : bytes; });
  return out + "'";
}

// Text for HTML element content and for attribute values in double or single quotes.
inline std::string html(std::string_view s) {
  std::string out;
  for_each_printable(s, [&](char32_t c, std::string_view bytes) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += bytes;
    }
  });
  return out;
}

// A JavaScript (and JSON) string literal in double quotes, all ASCII: every character beyond
// printable ASCII as \uXXXX (a surrogate pair above U+FFFF), ill-formed bytes as \uFFFD, and
// < > & escaped too, so that the literal can sit inside an HTML <script> element ("</script>").
inline std::string js_string(std::string_view s) {
  std::string out = "\"";
  char buffer[16];
  const auto unit = [&](unsigned u) {
    std::snprintf(buffer, sizeof buffer, "\\u%04x", u);
    out += buffer;
  };
  for (std::size_t k = 0; k < s.size();) {
    const std::size_t length = utf8_length(s, k);
    const char32_t c = length == 0 ? char32_t{0xFFFD} : utf8_decode(s, k, length);
    k += length == 0 ? 1 : length;
    if (c == '"') out += "\\\"";
    else if (c == '\\') out += "\\\\";
    else if (c >= 0x20 && c < 0x7F && c != '<' && c != '>' && c != '&') out += static_cast<char>(c);
    else if (c < 0x10000) unit(static_cast<unsigned>(c));
    else {
      const unsigned v = static_cast<unsigned>(c) - 0x10000;
      unit(0xD800 + (v >> 10));
      unit(0xDC00 + (v & 0x3FF));
    }
  }
  return out + "\"";
}

// One CSV field (RFC 4180): quoted, with quotes doubled, when it holds a comma, a quote or a
// space at either end; control characters (line breaks included) and ill-formed bytes replaced.
// A field that a spreadsheet would run as a formula (=, +, -, @ first) is quoted and led by an
// apostrophe, unless it is a number.
inline std::string csv_field(std::string_view s) {
  std::string body;
  bool quote = !s.empty() && (s.front() == ' ' || s.back() == ' ');
  for_each_printable(s, [&](char32_t c, std::string_view bytes) {
    if (c == '"') body += "\"\"";
    else body += bytes;
    quote = quote || c == ',' || c == '"' || c == 0xFFFD;
  });
  if (!body.empty() && (body[0] == '=' || body[0] == '+' || body[0] == '-' || body[0] == '@')) {
    const bool number = body.find_first_not_of("+-0123456789.eE") == std::string::npos;
    if (!number) {
      body.insert(0, "'");
      quote = true;
    }
  }
  return quote ? "\"" + body + "\"" : body;
}

// A C++ narrow string literal in double quotes, all printable ASCII: other bytes as three-digit
// octal escapes (which, unlike \x, never swallow a following digit), and a '?' after a '?' as
// \? so that no trigraph (??/ is a backslash before C++17) can form. The bytes are kept as they
// are (the literal holds exactly the input); validity is the reader's check.
inline std::string cpp_string(std::string_view s) {
  std::string out = "\"";
  char buffer[8];
  char previous = 0;
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') (out += '\\') += ch;
    else if (c == '?' && previous == '?') out += "\\?";
    else if (c >= 0x20 && c < 0x7F) out += ch;
    else {
      std::snprintf(buffer, sizeof buffer, "\\%03o", static_cast<unsigned>(c));
      out += buffer;
    }
    previous = ch;
  }
  return out + "\"";
}

// Text for the inside of a C++ comment (// or /* */), all printable ASCII on one line: bytes
// outside it and the backslash as the visible text \xNN (so no line can end in a backslash and
// splice the next line into the comment), "*/" as "*\x2f" (it would end a block comment), "/*" as
// "/\x2a" (compilers warn of it inside one) and "??" as "?\x3f" (no trigraph).
inline std::string cpp_comment(std::string_view s) {
  std::string out;
  char buffer[8];
  for (std::size_t k = 0; k < s.size(); ++k) {
    const auto c = static_cast<unsigned char>(s[k]);
    const bool ends_block = (c == '/' && k > 0 && s[k - 1] == '*') || (c == '*' && k > 0 && s[k - 1] == '/');
    const bool trigraph = c == '?' && k > 0 && s[k - 1] == '?';
    if (c >= 0x20 && c < 0x7F && c != '\\' && !ends_block && !trigraph) {
      out += static_cast<char>(c);
    } else {
      std::snprintf(buffer, sizeof buffer, "\\x%02x", static_cast<unsigned>(c));
      out += buffer;
    }
  }
  return out;
}

// A value shown in an error message: its first 60 bytes, control characters as \xNN, "..." when
// cut (the messages of the model-file and URDF readers).
inline std::string excerpt(std::string_view s) {
  std::string out;
  for (char ch : s.substr(0, 60)) {
    const auto u = static_cast<unsigned char>(ch);
    if (u < 0x20 || u == 0x7f) {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      out += hex;
    } else {
      out += ch;
    }
  }
  return s.size() > 60 ? out + "..." : out;
}

// The candidate nearest `key` in edit distance (ASCII case ignored when ignore_case), if within
// max(2, |key| / 3): every "did you mean" of wlx and wlx-gen; "" when none is that close. The
// distance is at least the difference in length, so a candidate that cannot beat the best is not
// compared: a hostile key of megabytes costs its length, not its length times every candidate's
// (a 10 MB scenario key took 7 s, 54 s under the sanitizers).
inline std::string nearest(std::string_view key, const std::vector<std::string>& candidates, bool ignore_case) {
  const auto fold = [&](char c) {
    return ignore_case ? static_cast<char>(std::tolower(static_cast<unsigned char>(c))) : c;
  };
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, key.size() / 3) + 1;
  std::vector<std::size_t> row;
  for (const std::string& c : candidates) {
    if ((key.size() > c.size() ? key.size() - c.size() : c.size() - key.size()) >= best_distance) continue;
    row.resize(c.size() + 1);
    for (std::size_t j = 0; j <= c.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= key.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= c.size(); ++j) {
        const std::size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (fold(key[i - 1]) == fold(c[j - 1]) ? 0 : 1)});
        diagonal = up;
      }
    }
    if (row[c.size()] < best_distance) best_distance = row[c.size()], best = c;
  }
  return best;
}

}  // namespace wlx::text
