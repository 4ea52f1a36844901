#include "plugin_cache.hpp"

#include "bounded_input.hpp"
#include "interrupt.hpp"
#include "sha256.hpp"

#include <fmt/format.h>
#include <wlx/support/atomic_file.hpp>
#include <wlx/support/bounded_file.hpp>
#include <wlx/support/diagnostics.hpp>

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sstream>
#include <sys/file.h>
#include <sys/mman.h>
#include <unistd.h>
#include <vector>

namespace wlx::cli {

namespace fs = std::filesystem;

fs::path index_path(const fs::path& cache) { return cache / "index"; }

namespace {

// The index's text: absent is empty; anything but a private regular file within its bound is an
// error naming it, before any entry is judged by it (a damaged index must not cost good plugins).
constexpr std::uintmax_t kMaxIndexBytes = std::uintmax_t{16} << 20;
std::string index_text(const fs::path& cache) {
  const fs::path index = index_path(cache);
  check_private(index, "index", false);
  struct stat st {};
  if (::lstat(index.c_str(), &st) != 0) return {};
  if (!S_ISREG(st.st_mode))
    throw Error("--model-file", fmt::format("the cache's index {} is not a regular file: remove it (every plugin of the cache is "
                                            "then built again on its next use)",
                                            index.string()));
  if (static_cast<std::uintmax_t>(st.st_size) > kMaxIndexBytes)
    throw Error("--model-file", fmt::format("the cache's index {} is larger than {} bytes: remove it (every plugin of the cache is "
                                            "then built again on its next use)",
                                            index.string(), kMaxIndexBytes));
  const BoundedRead r = read_bounded_file(index.string(), kMaxIndexBytes);
  if (!r.ok()) throw Error("--model-file", fmt::format("the cache's index {} cannot be read ({})", index.string(), r.error));
  return r.text;
}

}  // namespace

std::string manifest_value(const std::string& manifest, const std::string& key) {
  std::istringstream in(manifest);
  for (std::string l; std::getline(in, l);)
    if (l.rfind(key + " ", 0) == 0) return l.substr(key.size() + 1);
  return {};
}

void check_private(const fs::path& path, const char* what, bool follow) {
  struct stat st {};
  if ((follow ? ::stat(path.c_str(), &st) : ::lstat(path.c_str(), &st)) != 0) return;  // absent: nothing to trust yet
  if (!follow && S_ISLNK(st.st_mode))
    throw Error("--model-file", fmt::format("the cache's {} {} is a symbolic link: a cache entry is never followed elsewhere; "
                                            "remove it",
                                            what, path.string()));
  check_private_stat(st, path, what);
}

// The owner and mode of what `st` describes (the cache's `what` at `path`).
void check_private_stat(const struct stat& st, const fs::path& path, const char* what) {
  // A sticky folder others may write (/tmp) or a folder of another user cannot be made private by
  // its user: only another cache folder helps.
  const bool only_elsewhere = (st.st_mode & S_ISVTX) != 0 || st.st_uid != ::geteuid();
  if (st.st_uid != ::geteuid())
    throw Error("--model-file", fmt::format("the cache's {} {} belongs to another user (uid {}): code in it would run inside wlx; "
                                            "set WLX_CACHE_DIR to a folder of your own",
                                            what, path.string(), st.st_uid));
  if ((st.st_mode & (S_IWGRP | S_IWOTH)) != 0)
    throw Error("--model-file", fmt::format("the cache's {} {} may be written by others (mode {:04o}): code planted in it would run "
                                            "inside wlx; {}set WLX_CACHE_DIR to a folder of your own",
                                            what, path.string(), st.st_mode & 07777,
                                            only_elsewhere ? std::string() : fmt::format("chmod go-w {}, or ", path.string())));
}


std::string indexed_digest(const fs::path& cache, const std::string& stem) {
  std::istringstream in(index_text(cache));
  for (std::string line; std::getline(in, line);)
    if (line.size() == stem.size() + 65 && line.compare(0, stem.size(), stem) == 0 && line[stem.size()] == ' ') return line.substr(stem.size() + 1);
  return {};
}


// A file's SHA-256 and size, read from a descriptor from its start.
std::string fd_checksum(int fd, std::uintmax_t& size) {
  Sha256 h;
  size = 0;
  std::vector<char> buffer(1 << 16);
  for (;;) {
    const ssize_t n = ::pread(fd, buffer.data(), buffer.size(), static_cast<off_t>(size));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n == 0 ? h.hex() : std::string();
    h.add(std::string_view(buffer.data(), static_cast<std::size_t>(n)));
    size += static_cast<std::uintmax_t>(n);
  }
}

// A file's SHA-256 and size (the plugin just built, for its manifest and the index): by its descriptor.
std::string file_checksum(const fs::path& path, std::uintmax_t& size) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  size = 0;
  if (fd < 0) return {};
  const std::string digest = fd_checksum(fd, size);
  ::close(fd);
  return digest;
}

// An anonymous copy (memfd) of the library open at `fd`, for a second description, checked
// against the digest the original was checked against. Nothing is written to the cache.
int private_copy(int fd, const std::string& checksum) {
  const int copy = ::memfd_create("wlx-plugin", MFD_CLOEXEC);
  if (copy < 0) throw Error("--model-file", fmt::format("cannot make a copy of a plugin for a second set of numbers ({})", std::strerror(errno)));
  std::vector<char> buffer(1 << 16);
  for (off_t at = 0;;) {
    const ssize_t n = ::pread(fd, buffer.data(), buffer.size(), at);
    if (n < 0 && errno == EINTR) continue;
    if (n == 0) break;
    if (n < 0 || ::write(copy, buffer.data(), static_cast<std::size_t>(n)) != n) {
      ::close(copy);
      throw Error("--model-file", fmt::format("cannot make a copy of a plugin for a second set of numbers ({})", std::strerror(errno)));
    }
    at += n;
  }
  std::uintmax_t size = 0;
  if (fd_checksum(copy, size) != checksum) {
    ::close(copy);
    throw Error("--model-file", "the copy of a plugin for a second set of numbers does not match its manifest");
  }
  return copy;
}



// Build folders of processes that died while compiling (kill -9): <stem>.build-*. Called with the
// entry's lock held, which every build of that entry holds for its whole length, so none of them
// belongs to a build that still runs (whatever pid namespace it ran in). Removed before building
// again, so that nothing of them is left for good.
void remove_abandoned_builds(const fs::path& cache, const std::string& stem) {
  std::error_code ec;
  const std::string prefix = stem + ".build-";
  for (fs::directory_iterator it(cache, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().filename().string().rfind(prefix, 0) == 0) {
      std::error_code removed;
      fs::remove_all(it->path(), removed);
    }
}



// Records a plugin's SHA-256 in the cache's index (under its own lock: entries of other models are
// built at the same time), replacing the entry's earlier line.
void record_digest(const fs::path& cache, const std::string& stem, const std::string& digest) {
  const FileLock lock(cache / "index.lock", "wlx: waiting for another wlx writing the cache's index");
  std::istringstream in(index_text(cache));
  std::string kept;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line.rfind(stem + " ", 0) != 0) kept += line + "\n";
  write_file_atomically(index_path(cache).string(), kept + stem + " " + digest + "\n");
  ::chmod(index_path(cache).c_str(), 0600);  // whatever the umask: the index is the user's alone
}

FileLock::FileLock(const fs::path& path, const std::string& waiting_message) {
  fd_ = ::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd_ < 0) throw Error("--model-file", fmt::format("cannot open the cache's lock {} ({})", path.string(), std::strerror(errno)));
  if (::flock(fd_, LOCK_EX | LOCK_NB) == 0) return;
  wlx::diagnose("{}\n", waiting_message);
  while (::flock(fd_, LOCK_EX) != 0) {
    if (errno != EINTR) throw Error("--model-file", fmt::format("cannot lock {} ({})", path.string(), std::strerror(errno)));
    throw_if_interrupted();
  }
}

}  // namespace wlx::cli
