// Numeric CSV files read back by column name: the trajectories `wlx simulate` writes (for the
// viewer) and the torque tables a scenario reads. The text is already bounded by its reader.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace wlx::cli {

// The columns named in `wanted` (each once, by name), every value parsed and finite, from a CSV
// of a header row and numeric rows (blank lines skipped; CR LF accepted). Throws wlx::Error with
// `where` as its field and `what` naming the file in the reason ("the trajectory CSV"): a missing
// column (with the nearest name), a row of another width, a cell that is not a finite number
// (row counted as an editor counts lines), no rows at all. `header_out`, if given, gets the header.
std::map<std::string, std::vector<double>> read_csv_columns(std::string_view text, const std::string& where,
                                                            const std::string& what, const std::vector<std::string>& wanted,
                                                            std::vector<std::string>* header_out = nullptr);

// A CSV line's cells (no quoting: the numeric files above never quote).
std::vector<std::string> split_csv_line(std::string_view line);

}  // namespace wlx::cli
