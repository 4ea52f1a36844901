#include "output_checks.hpp"

#include <fmt/format.h>
#include <wlx/support/diagnostics.hpp>
#include <wlx/support/atomic_file.hpp>
#include <wlx/error.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>

namespace wlx::cli {

namespace fs = std::filesystem;

void prepare_out_dir(const std::string& option, const std::string& path) {
  if (path.empty()) throw Error(option, "an empty path names no folder");
  if (path == "-") throw Error(option, "'-' would be a folder named '-': wlx writes several files, not to stdout; give a folder");
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (fs::exists(status) && !fs::is_directory(status))
    throw Error(option, fmt::format("'{}' exists and is not a folder", path));
  fs::create_directories(path, ec);
  if (ec) throw OutputError(path, fmt::format("cannot create the folder ({})", ec.message()));
}

bool stdout_ok(std::string& reason) {
  std::cout.flush();
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int error_number = errno;
  if (flushed && !std::ferror(stdout) && std::cout.good()) return true;
  if (error_number != 0) {
    reason = std::strerror(error_number);
    return false;
  }
  // The failing write was earlier and its errno is gone: one more byte, to an output that is
  // incomplete anyway, tells why (ENOSPC, EPIPE, ...).
  std::clearerr(stdout);
  errno = 0;
  const bool retried = std::fputc('\n', stdout) != EOF && std::fflush(stdout) == 0;
  reason = !retried && errno != 0 ? std::strerror(errno) : "an earlier write failed";
  return false;
}

}  // namespace wlx::cli

namespace wlx::cli {

int finish(int code) {
  std::string reason;
  if (stdout_ok(reason)) return code;
  wlx::diagnose("wlx: error: stdout: writing the output failed ({}); the output is incomplete\n", reason);
  return kExitOutputError;
}

}  // namespace wlx::cli
