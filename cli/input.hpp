// JSON input of the CLI: MODEL.md names as keys, validated with messages that name the field.
#pragma once

#include <nlohmann/json.hpp>
#include <wlx/ik.hpp>
#include <wlx/model.hpp>

#include <optional>
#include <string>
#include <vector>

namespace wlx::cli {

// The valid name nearest to `key` (edit distance), for "did you mean" hints; empty if none is close.
std::string nearest(const std::string& key, const std::vector<std::string>& valid);
// Throws wlx::Error for an unknown key, suggesting the nearest valid one.
void reject_unknown_keys(const nlohmann::json& object, const std::vector<std::string>& valid, const std::string& where);
// A finite number at `key`, or an error naming it.
double finite_number(const nlohmann::json& value, const std::string& key);
// Applies {"name": value, ...} to params and validates the result (wlx::Model).
Params parse_params(const nlohmann::json& object, Params params = {});

enum class IkMethod { closed_form, newton };

struct IkRequest {
  Params params;
  Coordinates s;            // inputs set (missing ones from the nominal state), dependents zero
  IkMethod method = IkMethod::closed_form;
  Branches branches;
  std::vector<std::pair<int, double>> start;  // Newton's starting dependents given (index, value)
};

IkRequest parse_ik_request(const nlohmann::json& j);

}  // namespace wlx::cli
