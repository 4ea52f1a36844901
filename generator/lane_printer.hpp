// The one printer of the dynamics passes' code (lane_code.hpp): it names the values (the names
// starting with kane_ are its own), spells the lane type L and the rows' lanes, and lays
// the statements out; unread values and the scalars only they read are left out.
#pragma once

#include "lane_code.hpp"
#include "model.hpp"

#include <string>
#include <utility>
#include <vector>

namespace wlx::codegen::lane_code {

// Throws when a coordinate's or parameter's name could be one of the printer's (the generated
// function's arguments and its code share a scope).
void reserve_printer_names(const Model& m);

struct PrintedCode {
  std::string code;
  std::vector<std::pair<std::string, ex>> scalars;  // the lane scalars the code reads, named, in the program's order
  std::vector<OpCount> ops;                         // per output (Statement::output)
};
PrintedCode print(const LaneProgram& program, std::size_t outputs);
// The operations of the lane scalars the printed code reads, each distinct subexpression once, as
// the emitted function computes them (before the code: a pass in K0 spends much of its work there).
long scalar_operations(const PrintedCode& printed);

}  // namespace wlx::codegen::lane_code
