// MuJoCo's model of an MJCF text (MuJoCo 2.2.2, Debian's libmujoco-dev), for the code that links
// MuJoCo: the physics engine (physics_engine.cpp), the check of the export against MuJoCo and the
// benchmarks' MuJoCo rows. MuJoCo 2.2.2 loads XML from files only: the text goes through a private
// temporary file, removed at once.
#pragma once

#include <wlx/error.hpp>

#include <fmt/format.h>
#include <mujoco/mujoco.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>

#include <unistd.h>

namespace wlx::cli {

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using MjModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using MjDataPtr = std::unique_ptr<mjData, MjDataDeleter>;

// MuJoCo's last warning on this thread ("Nan, Inf or huge value in CTRL ..."), kept for its
// caller to report instead of MuJoCo's default, which appends it to MUJOCO_LOG.TXT in whatever
// folder the user ran wlx from. Installed by load_mjcf, before anything of MuJoCo's runs.
inline std::string& mujoco_last_warning() {
  thread_local std::string warning;
  return warning;
}
inline void keep_mujoco_warnings() {
  mju_user_warning = [](const char* message) { mujoco_last_warning() = message == nullptr ? "" : message; };
}

// Throws wlx::Error ("physics engine") for a file that cannot be written, or with MuJoCo's reason.
inline MjModelPtr load_mjcf(const std::string& xml) {
  keep_mujoco_warnings();
  // In the user's temporary folder (TMPDIR, else /tmp), as every other temporary file of wlx's.
  std::error_code ec;
  const std::filesystem::path folder = std::filesystem::temp_directory_path(ec);
  std::string name = ((ec ? std::filesystem::path("/tmp") : folder) / "wlx-mjcf-XXXXXX").string();
  char* path = name.data();
  const int fd = ::mkstemp(path);
  if (fd < 0) throw Error("physics engine", fmt::format("cannot create a temporary file for the MJCF ({})", std::strerror(errno)));
  const bool written = ::write(fd, xml.data(), xml.size()) == static_cast<ssize_t>(xml.size());
  const bool closed = ::close(fd) == 0;
  if (!written || !closed) {
    std::remove(path);
    throw Error("physics engine", fmt::format("cannot write the MJCF to {}", path));
  }
  char error[1000] = "";
  mjModel* m = mj_loadXML(path, nullptr, error, sizeof error);
  std::remove(path);
  if (m == nullptr) throw Error("physics engine", fmt::format("MuJoCo refuses the exported model: {}", error));
  return MjModelPtr(m);
}

}  // namespace wlx::cli
