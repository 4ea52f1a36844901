#include "csv_columns.hpp"

#include "bounded_input.hpp"

#include <fmt/format.h>
#include <wlx/error.hpp>

#include <charconv>
#include <cmath>
#include <utility>

namespace wlx::cli {

namespace {

// A CSV line's cells, as views into it (no quoting: the numeric files read here never quote).
void split_into(std::string_view line, std::vector<std::string_view>& cells) {
  cells.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}

// The next line of `text` from `offset` (without its LF or CR LF), advancing `offset` past it;
// false at the end. Views into the text: the rows are read without a copy per line or per cell
// (a long run's trajectory has ~10^5 cells, read back for the viewer).
bool next_line(std::string_view text, std::size_t& offset, std::string_view& line) {
  if (offset >= text.size()) return false;
  const std::size_t newline = text.find('\n', offset);
  const std::size_t stop = newline == std::string_view::npos ? text.size() : newline;
  line = text.substr(offset, stop - offset);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  offset = stop + 1;
  return true;
}

}  // namespace

std::vector<std::string> split_csv_line(std::string_view line) {
  std::vector<std::string_view> cells;
  split_into(line, cells);
  return {cells.begin(), cells.end()};
}

std::map<std::string, std::vector<double>> read_csv_columns(std::string_view text, const std::string& where,
                                                            const std::string& what, const std::vector<std::string>& wanted,
                                                            std::vector<std::string>* header_out) {
  std::size_t offset = 0;
  std::string_view line;
  if (!next_line(text, offset, line)) throw Error(where, what + " is empty");
  const std::vector<std::string> header = split_csv_line(line);
  if (header_out != nullptr) *header_out = header;
  std::map<std::string, std::size_t> position;
  for (std::size_t k = 0; k < header.size(); ++k) position.emplace(header[k], k);
  std::map<std::string, std::vector<double>> columns;
  std::vector<std::pair<std::size_t, std::vector<double>*>> targets;
  for (const auto& name : wanted) {
    const auto it = position.find(name);
    if (it == position.end()) {
      const std::string hint = nearest(name, header);
      throw Error(where, fmt::format("{} has no column '{}'{}", what, excerpt(name),
                                     hint.empty() ? "" : " (did you mean '" + hint + "'?)"));
    }
    if (!columns.contains(name)) targets.emplace_back(it->second, &columns[name]);
  }
  long row = 1;  // the header is row 1, as an editor counts lines
  long samples = 0;
  std::vector<std::string_view> cells;
  cells.reserve(header.size());
  while (next_line(text, offset, line)) {
    ++row;
    if (line.empty()) continue;
    ++samples;
    split_into(line, cells);
    if (cells.size() != header.size())
      throw Error(where, fmt::format("row {} of {} has {} values for {} columns", row, what, cells.size(), header.size()));
    for (const auto& [index, values] : targets) {
      const std::string_view cell = cells[index];
      double v = 0;
      const auto [end, error] = std::from_chars(cell.data(), cell.data() + cell.size(), v);
      if (error != std::errc() || end != cell.data() + cell.size() || !std::isfinite(v))
        throw Error(where, fmt::format("row {}, column '{}' of {}: '{}' is not a finite number", row, header[index], what,
                                       excerpt(cell)));
      values->push_back(v);
    }
  }
  if (samples == 0) throw Error(where, what + " has no samples");
  return columns;
}

}  // namespace wlx::cli
