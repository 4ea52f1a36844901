// `wlx export mjcf`: a model as MuJoCo's MJCF, from its description (model.json) alone. Compiled
// once into wlx: it names no model and reads no generated function.
//
// What is written (docs/export.md says the same for users):
//   - a body per frame, named as the frame, placed by its chain at zero joint values; the chain's
//     joints as hinge and slide joints named as their coordinates, their axes and anchors in the
//     body's axes (MuJoCo applies a body's joints in order, each about axes moved by the ones
//     before: the chain's product of joint motions with the fixed steps gathered in front);
//   - a floating base as a free joint (named as the frame) where a frame under K0 is exactly three
//     slides along x, y, z and three rotations about different axes;
//   - each frame's bodies as one inertial (mass, centre of mass, full inertia about it);
//   - each wheel on a hub as a child body spinning about the axle (a hinge named as its drive), a
//     cylinder of the wheel's radius; a wheel whose contact frame the file builds, a cylinder on
//     that frame; each foot a small sphere at its contact point; a ground plane; friction per contact;
//   - a motor per actuator (a joint's, or a wheel's drive), named as the actuator;
//   - the closure's sums of two coordinates as joint equalities; rows that place a contact on the
//     ground are the contacts themselves. Any other row is an error: the export cannot express it.
// MuJoCo refuses a moving body without mass: a moving frame that carries no body (a virtual joint's)
// gets a placeholder of kPlaceholderMassRatio of the machine's mass, named in a comment.
#pragma once

#include <string>

namespace wlx::cli {

// The placeholder mass of a moving frame without a body, relative to the machine's mass (and its
// inertia, that mass at 1 m): small enough to change no compared quantity beyond 1e-12 relative.
inline constexpr double kPlaceholderMassRatio = 1e-13;

struct MjcfExport {
  std::string model;  // its name
  std::string xml;
  // What MuJoCo's bodies hold that the model does not: one line per placeholder (for messages).
  std::string placeholders;
};

// The MJCF of the model `description_json` describes (model.json's text). Throws wlx::Error naming
// the description's field for what it cannot express.
MjcfExport mjcf_of_description(const std::string& description_json);

}  // namespace wlx::cli
