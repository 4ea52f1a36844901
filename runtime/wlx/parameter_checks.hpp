// The checks a model's parameters must pass, whatever the model: each value against its kind
// (lengths and masses positive, ...) and each body's principal inertias against the triangle
// inequality. Both runtimes call them (the model's own Model, wlx/model.hpp, and the one compiled
// once for every model, wlx/generic/model.hpp), so that a value refused by one is refused by the
// other with the same words.
#pragma once

#include <array>
#include <string_view>

namespace wlx {

// What a parameter measures (the model file's kinds; model.json's parameters[].kind).
enum class ParameterKind { length, mass, inertia, gravity, offset, angle, other };

// The kind of that name ("length", ...), or false for a name that is none.
bool parameter_kind_of(std::string_view name, ParameterKind& kind) noexcept;

// Throws wlx::Error naming the parameter when `value` is not finite or not a value of its kind.
void check_parameter(std::string_view name, ParameterKind kind, double value);

// Throws wlx::Error naming the offending parameter when one of a body's principal moments exceeds
// the sum of the other two: no rigid body has such an inertia.
void check_principal_inertias(const std::array<double, 3>& moments, const std::array<std::string_view, 3>& names);

}  // namespace wlx
