// An output file that is either complete under its name or not there at all: written to a
// temporary name in the same folder (so the final rename cannot cross file systems), every write
// checked, renamed into place by commit(). Without commit() (an error, an interruption) the
// destructor removes the temporary, so a cut file never sits under a name that looks finished.
// Header-only: it is no part of the model-specific runtime libraries.
#pragma once

#include "wlx/error.hpp"

#include <fmt/format.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <string>
#include <string_view>
#include <unistd.h>

namespace wlx {

// An output that could not be written (full disk, closed pipe, no permission); names the file.
// Distinct from a bad input: the CLI gives it its own exit code.
class OutputError : public Error {
 public:
  using Error::Error;
};

class AtomicFile {
 public:
  // Creates "<path>.<pid>-<n>.tmp" beside `path`; throws OutputError naming `path`.
  explicit AtomicFile(std::string path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();

  void write(std::string_view text);
  // Flushes, syncs and closes the temporary (errors such as ENOSPC often surface only here); the
  // file stays under its temporary name. For a set of files replacing another as a whole (wlx-gen's
  // headers): finish() every one, then commit() each, so a full disk leaves the old set intact.
  void finish();
  // finish(), then renames the temporary to the final path. Throws OutputError naming the final path.
  void commit();

  const std::string& path() const noexcept { return path_; }
  const std::string& temporary_path() const noexcept { return temporary_; }

 private:
  void flush();
  [[noreturn]] void fail(const std::string& what, int error_number);

  std::string path_, temporary_;
  int fd_ = -1;
  std::string buffer_;  // writes go out in blocks: one system call per row would be slow
  bool committed_ = false;
  bool finished_ = false;
};

// Writes `text` as the whole content of `path`, atomically.
void write_file_atomically(const std::string& path, std::string_view text);

namespace detail {
inline constexpr std::size_t kAtomicFileBlock = 1 << 16;
inline std::atomic<unsigned> temporary_counter{0};  // distinct names for files written from several threads
}  // namespace detail

inline AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  if (path_.empty()) throw OutputError("(empty path)", "cannot write a file without a name");
  for (int attempt = 0; attempt < 100 && fd_ < 0; ++attempt) {
    temporary_ = fmt::format("{}.{}-{}.tmp", path_, static_cast<long>(::getpid()), detail::temporary_counter++);
    // O_EXCL: never reuse (or follow a symlink planted at) a temporary name; O_NOFOLLOW says the
    // same to systems whose O_EXCL would not. 0666: the umask applies, so the finished file gets
    // the same permissions as one written directly.
    fd_ = ::open(temporary_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd_ < 0 && errno != EEXIST) break;
  }
  if (fd_ < 0) {
    const int e = errno;
    temporary_.clear();
    throw OutputError(path_, fmt::format("cannot open for writing ({})", std::strerror(e)));
  }
  buffer_.reserve(detail::kAtomicFileBlock);
}

inline AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !temporary_.empty()) ::unlink(temporary_.c_str());
}

inline void AtomicFile::fail(const std::string& what, int error_number) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temporary_.empty()) ::unlink(temporary_.c_str());
  temporary_.clear();
  throw OutputError(path_, fmt::format("{} failed ({}); the file was not written", what, std::strerror(error_number)));
}

inline void AtomicFile::write(std::string_view text) {
  if (fd_ < 0) throw OutputError(path_, "write after the file was closed");
  buffer_.append(text);
  if (buffer_.size() >= detail::kAtomicFileBlock) flush();
}

inline void AtomicFile::flush() {
  std::size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;  // a signal arrived; the caller checks for interruption itself
      fail("write", errno);
    }
    done += static_cast<std::size_t>(n);
  }
  buffer_.clear();
}

inline void AtomicFile::finish() {
  if (finished_) return;
  if (fd_ < 0) throw OutputError(path_, "commit after the file was closed");
  flush();
  // Some file systems report a full disk only when the data reach it: sync before the rename so
  // the name never points at data that were lost.
  if (::fsync(fd_) != 0 && errno != EINVAL) fail("fsync", errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail("close", errno);
  finished_ = true;
}

inline void AtomicFile::commit() {
  finish();
  if (committed_) throw OutputError(path_, "committed twice");
  if (::rename(temporary_.c_str(), path_.c_str()) != 0) fail("rename into place", errno);
  committed_ = true;
}

inline void write_file_atomically(const std::string& path, std::string_view text) {
  AtomicFile file(path);
  file.write(text);
  file.commit();
}

}  // namespace wlx
