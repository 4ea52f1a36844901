#include "bounded_input.hpp"
#include "interrupt.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <unordered_set>
#include <cctype>
#include <cmath>
#include <wlx/error.hpp>
#include <wlx/support/text.hpp>

namespace wlx::cli {

using text::utf8_length;

std::string excerpt(std::string_view text) {
  // Valid UTF-8 out, always: messages go into JSON (ik --batch's error lines), whose writer
  // refuses ill-formed bytes. Those are shown as \xNN, control characters as \n, \u0000, ...
  std::string out;
  std::size_t k = 0;
  while (k < text.size() && out.size() < kExcerptBytes) {
    const auto c = static_cast<unsigned char>(text[k]);
    const std::size_t length = utf8_length(text, k);
    if (length > 1) {
      out.append(text.substr(k, length));
      k += length;
      continue;
    }
    ++k;
    switch (c) {
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (length == 0) out += fmt::format("\\x{:02x}", c);
        else if (c < 0x20 || c == 0x7f) out += fmt::format("\\u{:04x}", c);
        else out += static_cast<char>(c);
    }
  }
  if (k < text.size()) out += fmt::format("... ({} bytes in all)", text.size());
  return out;
}

std::string excerpt(const nlohmann::json& value) {
  // Replace invalid UTF-8 rather than throw: the message must not fail.
  return excerpt(value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

namespace {

// nlohmann::json's own DOM builder, told each object's keys: a key given twice is an error.
class KeysOnce : public nlohmann::detail::json_sax_dom_parser<nlohmann::json> {
  using Base = nlohmann::detail::json_sax_dom_parser<nlohmann::json>;

 public:
  KeysOnce(nlohmann::json& root, const std::string& where) : Base(root, true), where_(where) {}
  bool start_object(std::size_t elements) {
    keys_.emplace_back();
    return Base::start_object(elements);
  }
  bool end_object() {
    if (!keys_.empty()) keys_.pop_back();
    return Base::end_object();
  }
  bool key(nlohmann::json::string_t& name) {
    // Hashed: a hostile object has a million keys.
    if (!keys_.empty() && !keys_.back().insert(name).second)
      throw Error(where_.empty() ? excerpt(name) : where_ + ": " + excerpt(name), "given twice in one object (give each key once)");
    return Base::key(name);
  }

 private:
  std::string where_;
  std::vector<std::unordered_set<std::string>> keys_;  // the keys seen so far, per open object
};

}  // namespace

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
  // A key given twice in one object: nlohmann::json keeps the last one without a word, so a
  // request like {"z_C": 1.8, "z_C": 2.0} would run on a value its writer may not have meant. The
  // check rides on the parser's own SAX events (per key, not per value: a 1e6-row table costs
  // nothing more).
  try {
    nlohmann::json result;
    KeysOnce sax(result, where);
    nlohmann::json::sax_parse(text, &sax);
    return result;
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
  std::size_t bytes = 0;
  for (int c; (c = in.get()) != std::char_traits<char>::eof();) {
    any = true;
    // A line that never ends (data arriving without a '\n') never blocks, so no read is cut short
    // by a signal: the signal is asked for every 64 KiB instead.
    if ((++bytes & 0xFFFF) == 0) throw_if_interrupted();
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

namespace {

std::string type_name(const nlohmann::json& v) { return v.type_name(); }

}  // namespace

std::string nearest(const std::string& key, const std::vector<std::string>& valid) {
  return text::nearest(key, valid, true);
}

void reject_unknown_keys(const nlohmann::json& object, const std::vector<std::string>& valid, const std::string& where) {
  for (const auto& [key, value] : object.items()) {
    if (std::find(valid.begin(), valid.end(), key) != valid.end()) continue;
    const std::string hint = nearest(key, valid);
    throw Error(where + excerpt(key), hint.empty() ? "unknown key" : fmt::format("unknown key; did you mean '{}'?", hint));
  }
}

double finite_number(const nlohmann::json& value, const std::string& key) {
  if (!value.is_number())
    throw Error(key, fmt::format("must be a number, got {} {}", type_name(value), excerpt(value)));
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw Error(key, fmt::format("must be a finite number, got {}", v));
  return v;
}

}  // namespace wlx::cli
