// A CSV file of numbers as the CLI and the report write them: the header line and the rows.
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace wlx_test {

// The header line and every further line's cells as numbers (std::stod: a cell that is no number
// throws, which fails the test that reads it).
inline std::pair<std::string, std::vector<std::vector<double>>> read_csv(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::string header, line;
  std::getline(file, header);
  std::vector<std::vector<double>> rows;
  while (std::getline(file, line)) {
    std::vector<double> row;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return {header, rows};
}

}  // namespace wlx_test
