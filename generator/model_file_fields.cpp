// Reading a model file's YAML: a node's text, name, number or list with its place in messages
// (Item), a map's fields (Fields), an axis, and the fingerprint the generated banners quote.
#include "model_file_internal.hpp"

#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>

namespace wlx::codegen::model_file_detail {

void Source::fail(const YAML::Mark& mark, const std::string& path, const std::string& reason) const {
  const std::string field = path.empty() ? "" : path + ": ";
  // The file's name as one line: a name with a line break must not forge a message line.
  std::string shown;
  for (const char c : name) shown += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? fmt::format("\\x{:02x}", static_cast<unsigned char>(c)) : std::string(1, c);
  if (mark.is_null()) throw ModelFileError(fmt::format("{}: {}{}", shown, field, reason));
  throw ModelFileError(fmt::format("{}:{}:{}: {}{}", shown, mark.line + 1, mark.column + 1, field, reason));
}

std::string Item::text() const {
  if (!node_.IsDefined() || node_.IsNull()) fail("missing: give a value");
  if (!node_.IsScalar()) fail("must be a single value, not a list or map");
  const std::string& s = node_.Scalar();
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    const std::size_t close = s[i] == '<' ? s.find('>', i) : std::string::npos;
    if (close != std::string::npos && is_identifier(s.substr(i + 1, close - i - 1))) {
      const std::string var = s.substr(i + 1, close - i - 1);
      const auto it = env_.find(var);
      if (it == env_.end()) {
        std::vector<std::string> names;
        for (const auto& kv : env_) names.push_back(kv.first);
        fail(fmt::format("'<{}>' is not a repetition variable here{}{}", var, suggestion(var, names),
                         env_.empty() ? " (the entry has no `for`)" : ""));
      }
      out += it->second;
      i = close + 1;
    } else {
      out += s[i++];
    }
  }
  // Text reaches generated comments and string literals (quoted there, emit.cpp): one line of
  // printable UTF-8, checked after the repetition variables are put in (their values are text
  // of the file too). A backslash would continue a // comment onto the next generated line.
  if (std::string why = text::check_one_line(out); !why.empty() || out.find('\\') != std::string::npos)
    fail(fmt::format("'{}' {}; text here is one plain line", excerpt(out), why.empty() ? "has a backslash" : why));
  return out;
}

std::string Item::name() const {
  const std::string s = text();
  if (!is_identifier(s))
    fail(fmt::format("'{}' is not a name: use letters, digits and _, not starting with a digit", excerpt(s)));
  // Every name of the file reaches the generated code (as an identifier, a namespace or a
  // string): none may be a keyword, a macro or std/Eigen. K0, the ground, is the one name
  // the file may refer to without defining it.
  if (const std::string why = code_name_reason(s); !why.empty() && s != "K0")
    fail(fmt::format("'{}' cannot be used as a name: {}", s, why));
  return s;
}

double Item::number(bool constant) const {
  const std::string s = text();
  double v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if ((ec != std::errc() || end != s.data() + s.size()) && constant && s.size() < 64 &&
      s.find_first_of("^abcdefghijklmnopqrstuvwxyzABCDFGHIJKLMNOPQRSTUVWXYZ_") == std::string::npos) {
    try {
      GiNaC::parser reader(GiNaC::symtab{}, true);
      const ex e = GiNaC::evalf(reader(s));
      if (GiNaC::is_a<GiNaC::numeric>(e) && GiNaC::ex_to<GiNaC::numeric>(e).is_real()) {
        v = GiNaC::ex_to<GiNaC::numeric>(e).to_double();
        if (!std::isfinite(v)) fail(fmt::format("must be a finite number, got {}", excerpt(s)));
        return v;
      }
    } catch (const std::exception&) {
    }
    fail(fmt::format("'{}' is not a number", excerpt(s)));
  }
  if (ec != std::errc() || end != s.data() + s.size()) fail(fmt::format("'{}' is not a number", excerpt(s)));
  if (!std::isfinite(v)) fail(fmt::format("must be a finite number, got {}", excerpt(s)));
  return v;
}

std::vector<Item> Item::list() const {
  if (!node_.IsSequence()) fail("must be a list [a, b, ...]");
  std::vector<Item> out;
  for (std::size_t k = 0; k < node_.size(); ++k) out.push_back(element(k));
  return out;
}

int Item::branch() const {
  const double v = number();
  if (!(v >= 0 && v <= 1023 && v == std::floor(v))) fail(fmt::format("a branch is a whole number from 0, got {}", v));
  return static_cast<int>(v);
}

Fields::Fields(const Item& item, std::vector<std::string> allowed) : item_(item), allowed_(std::move(allowed)) {
  if (!item.is_map()) item.fail("must be a map of fields (key: value)");
  for (const auto& kv : item.node()) {
    const std::string key = kv.first.Scalar();
    if (key == "for") continue;  // the repetition, already expanded
    if (std::find(allowed_.begin(), allowed_.end(), key) == allowed_.end())
      item.source().fail(kv.first.Mark(), item.path(),
                         fmt::format("unknown field '{}'{}; the fields here are: {}", excerpt(key),
                                     suggestion(key, allowed_), fmt::join(allowed_, ", ")));
  }
}

Axis axis_of(const Item& it) {
  const std::string a = it.text();
  if (a == "x") return Axis::X;
  if (a == "y") return Axis::Y;
  if (a == "z") return Axis::Z;
  it.fail(fmt::format("'{}' is not an axis: use x, y or z", excerpt(a)));
}

std::uint64_t fingerprint(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

}  // namespace wlx::codegen::model_file_detail
