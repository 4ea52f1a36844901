// Fuzz target: the URDF reader (TinyXML's pre-pass, then urdfdom). Any text either reads into a
// robot whose links all hang from its root, or is refused with a ModelFileError; no other exception,
// crash, hang or sanitizer finding, and no more memory than its bounds allow.
#include "../../generator/model_file.hpp"
#include "../../generator/urdf_import.hpp"

#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(bytes), size);
  try {
    const wlx::codegen::UrdfRobot robot = wlx::codegen::read_urdf_text(text, "fuzz.urdf");
    // One joint per link but the root, each link reached from the root (its parent joint's child).
    if (robot.links.empty() || robot.joints.size() + 1 != robot.links.size()) std::abort();
    for (std::size_t k = 1; k < robot.links.size(); ++k) {
      const int j = robot.links[k].parent_joint;
      if (j < 0 || static_cast<std::size_t>(j) >= robot.joints.size() || robot.joints[static_cast<std::size_t>(j)].child != robot.links[k].name)
        std::abort();
    }
  } catch (const wlx::codegen::ModelFileError&) {
  }
  return 0;
}
