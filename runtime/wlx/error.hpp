// The one exception type of the runtime: a message that names the offending field and why.
#pragma once

#include <stdexcept>
#include <string>

namespace wlx {

class Error : public std::runtime_error {
 public:
  Error(std::string field, const std::string& reason)
      : std::runtime_error(field.empty() ? reason : field + ": " + reason), field_(std::move(field)) {}
  // The input field (docs/excavator.md name, JSON key or option) the error is about; may be empty.
  const std::string& field() const noexcept { return field_; }

 private:
  std::string field_;
};

}  // namespace wlx
