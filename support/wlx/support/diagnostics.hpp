// Messages on stderr that never throw. fmt::print(stderr, ...) throws when stderr cannot be
// written (a closed pipe, /dev/full); in a catch handler of main that ends the program with abort
// (exit 134) instead of its exit code. A lost message must not change what the exit code says.
#pragma once

#include <fmt/format.h>

#include <cerrno>
#include <string>
#include <string_view>
#include <unistd.h>
#include <utility>

namespace wlx {

inline void write_stderr(std::string_view text) noexcept {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(STDERR_FILENO, text.data() + done, text.size() - done);
    if (n > 0) done += static_cast<std::size_t>(n);
    else if (n < 0 && errno == EINTR) continue;
    else return;  // nowhere to say it
  }
}

template <class... Args>
void diagnose(fmt::format_string<Args...> format, Args&&... args) noexcept {
  try {
    write_stderr(fmt::format(format, std::forward<Args>(args)...));
  } catch (...) {  // formatting's bad_alloc: the message is lost, the exit code stays
  }
}

}  // namespace wlx
