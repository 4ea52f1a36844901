// Inputs and messages of bounded size: JSON nesting is limited before anything recurses over it,
// lines are capped before they are stored, and an offending value or key is echoed only as a
// short excerpt with control characters escaped.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <istream>
#include <string>
#include <vector>
#include <string_view>

namespace wlx::cli {

// Deeper than any input wlx reads needs (a weight matrix is 3 levels) and far below what the
// recursive parts of nlohmann::json (dump, comparisons) can take without exhausting the stack.
inline constexpr int kMaxJsonDepth = 64;
// An ik request or a scenario is a few kilobytes; a 1 MiB line or a 16 MiB file is a mistake.
inline constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;
inline constexpr std::size_t kMaxFileBytes = std::size_t{16} << 20;
// A report file (claims) is tens of kilobytes; the viewer's run index one line per run.
inline constexpr std::size_t kMaxReportFileBytes = std::size_t{1} << 20;
inline constexpr std::size_t kMaxRunIndexBytes = std::size_t{16} << 20;
// How much of an offending value or key a message shows.
inline constexpr std::size_t kExcerptBytes = 60;

// `text` with control characters escaped (\n, \t, \u0000, ...) and cut after kExcerptBytes at a
// UTF-8 character boundary, with the full length said.
std::string excerpt(std::string_view text);
inline std::string excerpt(const std::string& text) { return excerpt(std::string_view(text)); }
inline std::string excerpt(const char* text) { return excerpt(std::string_view(text)); }
// A JSON value for a message: its compact text, excerpted.
std::string excerpt(const nlohmann::json& value);

// Parses `text` after checking its nesting depth; throws wlx::Error naming `where` with the
// reason (too deep, not valid JSON with an excerpted parser message).
nlohmann::json parse_json_bounded(std::string_view text, const std::string& where);

enum class LineRead { line, end, too_long };
// Reads one line (without its '\n') of at most `limit` bytes. A longer line is consumed to its
// end without being stored, and reported as too_long, so memory stays bounded.
LineRead read_line_capped(std::istream& in, std::string& line, std::size_t limit = kMaxLineBytes);

// Reads all of `in` up to `limit` bytes; throws wlx::Error naming `where` beyond it.
std::string read_all_capped(std::istream& in, const std::string& where, std::size_t limit);

// The valid name nearest to `key` (edit distance), for "did you mean" hints; empty if none is close.
std::string nearest(const std::string& key, const std::vector<std::string>& valid);
// Throws wlx::Error for an unknown key, suggesting the nearest valid one.
void reject_unknown_keys(const nlohmann::json& object, const std::vector<std::string>& valid, const std::string& where);
// A finite number at `key`, or an error naming it.
double finite_number(const nlohmann::json& value, const std::string& key);

}  // namespace wlx::cli
