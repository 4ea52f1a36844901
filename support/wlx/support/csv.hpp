// A CSV writer for results: full double precision, and never a NaN or Inf in a file. The file
// appears under its name only when commit() is called (wlx::AtomicFile): a writer destroyed
// before that (an error, an interruption) leaves nothing behind.
#pragma once

#include "wlx/support/atomic_file.hpp"
#include "wlx/error.hpp"
#include "wlx/support/text.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace wlx {

class CsvWriter {
 public:
  CsvWriter(const std::string& path, const std::vector<std::string>& header)
      : path_(path), columns_(header.size()), file_(path) {
    std::string line;
    for (std::size_t k = 0; k < header.size(); ++k) line += (k != 0 ? "," : "") + text::csv_field(header[k]);
    file_.write(line + "\n");
    header_ = header;
  }
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  // `values` appended to a CSV line at full precision, comma-separated (a comma first if asked).
  static void append_numbers(std::string& line, const std::vector<double>& values, bool comma_first) {
    for (std::size_t k = 0; k < values.size(); ++k) {
      if (comma_first || k != 0) line += ',';
      // fmt::format, not format_to: it formats in fmt's compiled library, not in code
      // instantiated here (the per-model commands compile at -O0: a report 1.6x slower).
      line += fmt::format("{:.17g}", values[k]);
    }
  }

  // Puts the finished file in place; throws OutputError naming it if anything was lost.
  void commit() { file_.commit(); }

  // One row; a non-finite value is an error naming its column, and nothing of the row is written.
  void row(const std::vector<double>& values) { row({}, values); }
  // The same after leading text columns (quoted as CSV fields, wlx/support/text.hpp).
  void row(const std::vector<std::string>& labels, const std::vector<double>& values) {
    if (labels.size() + values.size() != columns_)
      throw Error(path_, fmt::format("row has {} values for {} columns", labels.size() + values.size(), columns_));
    for (std::size_t k = 0; k < values.size(); ++k)
      if (!std::isfinite(values[k]))
        throw Error(header_[labels.size() + k], fmt::format("non-finite value {} not written to {}", values[k], path_));
    // One buffer per row, no temporary string per cell: a long run writes ~10^5 cells, and the
    // per-model commands that call this compile at -O0.
    line_.clear();
    for (std::size_t k = 0; k < labels.size(); ++k) {
      if (k != 0) line_ += ',';  // by position: an empty first label still gets its column
      line_ += text::csv_field(labels[k]);
    }
    append_numbers(line_, values, !labels.empty());
    line_ += '\n';
    file_.write(line_);
  }

 private:
  std::string path_;
  std::size_t columns_;
  std::vector<std::string> header_;
  std::string line_;
  AtomicFile file_;
};

}  // namespace wlx
