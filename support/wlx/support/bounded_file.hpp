// Reading an input file whole, bounded: the one reader of model files, report files, parameter
// files and the viewer's run index. Only a regular file is read: a FIFO without a writer would
// block forever, /dev/zero would never end, a folder is a mistake; each is refused with its
// reason. The size is checked before reading and again while reading (a file may grow), so no
// more than `limit` + 1 bytes are ever held. Header-only, POSIX: the generator uses it too, and
// each caller wraps the reason in its own error type.
#pragma once

#include <cerrno>
#include <cstddef>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace wlx {

struct BoundedRead {
  std::string text;
  std::string error;  // empty when the file was read; else why not ("is a FIFO, not a regular file")
  bool ok() const { return error.empty(); }
};

inline BoundedRead read_bounded_file(const std::string& path, std::size_t limit) {
  BoundedRead r;
  // O_NONBLOCK: opening a FIFO that has no writer returns at once instead of waiting for one.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) {
    r.error = std::string("cannot open it (") + std::strerror(errno) + ")";
    return r;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    r.error = std::string("cannot read it (") + std::strerror(errno) + ")";
  } else if (S_ISDIR(st.st_mode)) {
    r.error = "is a folder, not a file";
  } else if (S_ISFIFO(st.st_mode)) {
    r.error = "is a pipe (FIFO), not a regular file: its end is unknown, and without a writer it never comes";
  } else if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) {
    r.error = "is a device, not a regular file (/dev/zero and the like never end)";
  } else if (!S_ISREG(st.st_mode)) {
    r.error = "is not a regular file";
  } else if (static_cast<unsigned long long>(st.st_size) > limit) {
    r.error = "is " + std::to_string(st.st_size) + " bytes, more than the limit of " + std::to_string(limit) + " bytes";
  }
  if (!r.error.empty()) {
    ::close(fd);
    return r;
  }
  char block[65536];
  for (;;) {
    const ssize_t n = ::read(fd, block, sizeof block);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      r.error = std::string("cannot read it (") + std::strerror(errno) + ")";
      break;
    }
    if (n == 0) break;
    if (r.text.size() + static_cast<std::size_t>(n) > limit) {
      r.error = "grew past the limit of " + std::to_string(limit) + " bytes while being read";
      break;
    }
    r.text.append(block, static_cast<std::size_t>(n));
  }
  ::close(fd);
  if (!r.error.empty()) r.text.clear();
  return r;
}

}  // namespace wlx
