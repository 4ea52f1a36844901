// JSON input of the CLI: the model's names as keys, validated with messages that name the field.
#pragma once

#include "per_model.hpp"
#include <nlohmann/json.hpp>
#include <wlx/ik.hpp>
#include <wlx/model.hpp>

#include <array>
#include <optional>
#include <string>
#include <vector>

WLX_COMMANDS_BEGIN

// Applies {"name": value, ...} to params and validates the result (wlx::Model).
Params parse_params(const nlohmann::json& object, Params params = settings().params);

enum class IkMethod { closed_form, newton };

// The methods by name, as requests and answers spell them: "closed-form", "newton".
const char* method_name(IkMethod method);
// The method that solves each limb (kLimbs order) for a request of `requested`: the closed form
// where it is asked for and wlx-gen derived one (has_closed_form), else Newton's method.
std::array<IkMethod, kLimbCount> limb_methods(IkMethod requested);
// What solved every limb, by name ("closed-form", "newton"), or "mixed" where the limbs differ;
// for a model without limbs (nothing to solve) the requested method's name.
std::string overall_method(const std::array<IkMethod, kLimbCount>& methods, IkMethod requested);
// In words, for text: "the closed-form IK", "Newton's method (wlx-gen derived no closed form for
// any limb)", or "the closed-form IK, and Newton's method for the limbs without a closed form
// (wheel arm)"; "Newton's method" where it was asked for.
std::string methods_in_words(const std::array<IkMethod, kLimbCount>& methods);

struct IkRequest {
  Params params = settings().params;
  Coordinates s;            // inputs set (missing ones from the nominal state), dependents zero
  IkMethod method = IkMethod::closed_form;
  Branches branches;
  std::vector<std::pair<int, double>> start;  // Newton's starting dependents given (index, value)
};

// `base`: the parameters the request's "params" override (the defaults, or those of --params).
IkRequest parse_ik_request(const nlohmann::json& j, const Params& base = settings().params);

// Solves a request: what `wlx ik` prints (the dependents by name, contacts, residual, check error,
// branches, Newton's iterations). `warm`: Newton's start from a previous solution (batch mode), or
// nullptr; `solution`: receives all coordinates, or nullptr. Throws wlx::Error for a target out of
// reach, and for a result that does not satisfy the closure (residual above 1e-9).
nlohmann::ordered_json solve_ik_request(const IkRequest& request, Coordinates* warm, Coordinates* solution = nullptr);

WLX_COMMANDS_END
