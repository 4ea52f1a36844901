// The one exception type of the runtime: a message that names the offending field and why.
#pragma once

#include <stdexcept>
#include <string>

namespace wlx {

class Error : public std::runtime_error {
 public:
  Error(std::string field, std::string reason)
      : std::runtime_error(field.empty() ? reason : field + ": " + reason), field_(std::move(field)), reason_(std::move(reason)) {}
  // The input field (a coordinate or parameter name of the model, a JSON key or an option) the
  // error is about; may be empty.
  const std::string& field() const noexcept { return field_; }
  // Why, without the field: to re-raise the error under a longer field name (params.legD).
  const std::string& reason() const noexcept { return reason_; }

 private:
  std::string field_;
  std::string reason_;
};

}  // namespace wlx
