// An output file that is either complete under its name or not there at all: written to a
// temporary name in the same folder (so the final rename cannot cross file systems), every write
// checked, renamed into place by commit(). Without commit() (an error, an interruption) the
// destructor removes the temporary, so a cut file never sits under a name that looks finished.
#pragma once

#include "wlx/error.hpp"

#include <string>
#include <string_view>

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
  // Flushes, syncs and closes the temporary (errors such as ENOSPC often surface only here), then
  // renames it to the final path. Throws OutputError naming the final path.
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
};

// Writes `text` as the whole content of `path`, atomically.
void write_file_atomically(const std::string& path, std::string_view text);

}  // namespace wlx
