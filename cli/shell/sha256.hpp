// SHA-256 (FIPS 180-4), for what must not be forged: a plugin's bytes are checked against the
// digest recorded when it was built before dlopen() runs any of its code (model_plugin.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace wlx::cli {

class Sha256 {
 public:
  Sha256() noexcept;
  void add(std::string_view bytes) noexcept;
  // The digest as 64 lowercase hex digits; the object is spent after it.
  std::string hex() noexcept;

 private:
  void block(const unsigned char* p) noexcept;
  std::array<std::uint32_t, 8> state_;
  std::array<unsigned char, 64> pending_{};
  std::size_t pending_size_ = 0;
  std::uint64_t length_ = 0;  // bytes
};

// The digest of a whole string.
std::string sha256_hex(std::string_view bytes);

}  // namespace wlx::cli
