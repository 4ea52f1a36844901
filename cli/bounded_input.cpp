#include "bounded_input.hpp"

#include <fmt/format.h>
#include <wlx/error.hpp>

namespace wlx::cli {

std::string excerpt(std::string_view text) {
  std::string out;
  std::size_t k = 0;
  for (; k < text.size() && out.size() < kExcerptBytes; ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    switch (c) {
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20 || c == 0x7f) out += fmt::format("\\u{:04x}", c);
        else out += static_cast<char>(c);
    }
  }
  // Finish a UTF-8 character that was cut: its continuation bytes are 10xxxxxx.
  while (k < text.size() && (static_cast<unsigned char>(text[k]) & 0xC0) == 0x80) out += text[k++];
  if (k < text.size()) out += fmt::format("... ({} bytes in all)", text.size());
  return out;
}

std::string excerpt(const nlohmann::json& value) {
  // Replace invalid UTF-8 rather than throw: the message must not fail.
  return excerpt(value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

nlohmann::json parse_json_bounded(std::string_view text, const std::string& where) {
  // A linear scan for the depth of [ and { outside strings, before the parser (iterative) builds
  // a value that recursive code would later walk.
  int depth = 0;
  bool in_string = false, escaped = false;
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') in_string = true;
    else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth)
        throw Error(where, fmt::format("JSON nested deeper than {} levels (at byte {})", kMaxJsonDepth, k + 1));
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // The parser's message quotes the token it read last, which can be the whole input.
    const std::string message = e.what();
    const std::size_t last = message.find("; last read: '");
    std::string shown = message;
    if (last != std::string::npos) {
      const std::size_t begin = last + 14, end = message.rfind('\'');
      const std::string token = message.substr(begin, end > begin ? end - begin : std::string::npos);
      shown = message.substr(0, begin) + excerpt(token) + "'";
    }
    if (shown.size() > 400) shown = shown.substr(0, 400) + "...";
    throw Error(where, fmt::format("not valid JSON ({})", shown));
  }
}

LineRead read_line_capped(std::istream& in, std::string& line, std::size_t limit) {
  line.clear();
  bool any = false, too_long = false;
  for (int c; (c = in.get()) != std::char_traits<char>::eof();) {
    any = true;
    if (c == '\n') return too_long ? LineRead::too_long : LineRead::line;
    if (too_long) continue;
    if (line.size() == limit) {
      too_long = true;
      line.clear();
      line.shrink_to_fit();
      continue;
    }
    line.push_back(static_cast<char>(c));
  }
  if (too_long) return LineRead::too_long;
  return any ? LineRead::line : LineRead::end;
}

std::string read_all_capped(std::istream& in, const std::string& where, std::size_t limit) {
  std::string text;
  char block[65536];
  while (in.read(block, sizeof block) || in.gcount() > 0) {
    text.append(block, static_cast<std::size_t>(in.gcount()));
    if (text.size() > limit)
      throw Error(where, fmt::format("longer than {} bytes: not an input wlx reads", limit));
  }
  return text;
}

}  // namespace wlx::cli
