// The CLI's subcommands, one function each.
#pragma once

#include <string>
#include <vector>

namespace wlx::cli {

int run_fk(bool as_json);
int run_ik(bool batch);
int run_verify_ik(const std::string& out_dir, const std::vector<std::string>& sweep_ids);

}  // namespace wlx::cli
