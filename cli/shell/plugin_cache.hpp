// The model plugins' cache (model_plugin.cpp): what is trusted in it, its index of the plugins'
// digests, the plugins' checksums, and the locks and temporary folders of its builds.
//
// What the cache holds runs inside wlx (a plugin is dlopen()ed), so only what is the user's and
// what nobody else may write is trusted: the cache folder (followed if it is a link) and each
// entry's folder, plugin and manifest (never links). Anything else is an error naming it, never
// used and never removed (it is not ours to remove); the README says how to mend it.
#pragma once

#include <wlx/error.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <sys/stat.h>

namespace wlx::cli {

// The value of a manifest's "KEY value" line ("" if there is none).
std::string manifest_value(const std::string& manifest, const std::string& key);

// Refuses (wlx::Error naming --model-file and the cache's `what`) what at `path` another user
// owns, others may write, or (unless `follow`) is a symbolic link; an absent path passes.
void check_private(const std::filesystem::path& path, const char* what, bool follow);
// The owner and mode of what `st` describes (the cache's `what` at `path`).
void check_private_stat(const struct stat& st, const std::filesystem::path& path, const char* what);

// The cache's index: the SHA-256 of every plugin this cache built, one "<entry> <digest>" line
// each, in the cache folder (which only its user may write: check_private). A plugin is
// dlopen()ed only when its bytes have the digest recorded here when it was built, so an entry
// whose plugin.so and manifest were replaced together, or copied in from elsewhere, is never run.
std::filesystem::path index_path(const std::filesystem::path& cache);
// The SHA-256 the cache's index recorded for the entry `stem` when it was built ("" if none).
std::string indexed_digest(const std::filesystem::path& cache, const std::string& stem);
// Records a plugin's SHA-256 in the cache's index, replacing the entry's earlier line.
void record_digest(const std::filesystem::path& cache, const std::string& stem, const std::string& digest);

// A file's SHA-256 and size, read from a descriptor from its start ("" if it cannot be read).
std::string fd_checksum(int fd, std::uintmax_t& size);
// A file's SHA-256 and size, by its path ("" if it cannot be read).
std::string file_checksum(const std::filesystem::path& path, std::uintmax_t& size);
// An anonymous copy (memfd) of the library open at `fd`, checked against `checksum`.
int private_copy(int fd, const std::string& checksum);

// Removes the build folders (<stem>.build-*) of processes that died while compiling the entry.
void remove_abandoned_builds(const std::filesystem::path& cache, const std::string& stem);

// An exclusive lock on a file, held while the object lives (flock: released if the process dies).
class FileLock {
 public:
  // Waits for the lock (saying so with `waiting_message` on stderr) unless it is free.
  FileLock(const std::filesystem::path& path, const std::string& waiting_message);
  ~FileLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

// A folder removed when the object goes, unless kept.
struct TemporaryFolder {
  std::filesystem::path path;
  bool keep = false;
  ~TemporaryFolder() {
    std::error_code ec;
    if (!keep && !path.empty()) std::filesystem::remove_all(path, ec);
  }
};

}  // namespace wlx::cli
