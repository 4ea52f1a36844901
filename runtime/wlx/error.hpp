// The one exception type of the runtime: a message that names the offending field and why, and
// what kind of failure it is.
#pragma once

#include <stdexcept>
#include <string>

namespace wlx {

// What kind of failure an error is, for a program that acts on it (a sweep counting the variants
// whose poses are out of reach, a planner backing off a joint limit) rather than reading its words.
enum class ErrorKind {
  other,         // a bad input or anything not below
  out_of_reach,  // the IK found no pose: a target beyond a limb's reach, or Newton's method not converging
  singular,      // a Jacobian the motion needs is singular there (a limb's closure block, J_beta)
  contact,       // a contact lifts off, the machine tips, or the body touches the ground
  limit,         // a joint's range or largest speed is exceeded
};

// The kinds by name, as Python's wlx.Error.kind and the sweep's tables spell them.
constexpr const char* error_kind_name(ErrorKind kind) noexcept {
  switch (kind) {
    case ErrorKind::out_of_reach: return "out-of-reach";
    case ErrorKind::singular: return "singular";
    case ErrorKind::contact: return "contact";
    case ErrorKind::limit: return "limit";
    case ErrorKind::other: break;
  }
  return "other";
}

class Error : public std::runtime_error {
 public:
  Error(std::string field, std::string reason, ErrorKind kind = ErrorKind::other)
      : std::runtime_error(field.empty() ? reason : field + ": " + reason), field_(std::move(field)), reason_(std::move(reason)),
        kind_(kind) {}
  // The input field (a coordinate or parameter name of the model, a JSON key or an option) the
  // error is about; may be empty.
  const std::string& field() const noexcept { return field_; }
  // Why, without the field: to re-raise the error under a longer field name (params.legD).
  const std::string& reason() const noexcept { return reason_; }
  ErrorKind kind() const noexcept { return kind_; }

 private:
  std::string field_;
  std::string reason_;
  ErrorKind kind_;
};

}  // namespace wlx
