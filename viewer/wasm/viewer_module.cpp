// The viewer's WebAssembly module: one model's generated headers and the generic runtime's own
// sources (forward kinematics, the closed-form IK, the closure), compiled with emscripten exactly
// as the native runtime is compiled per model (WLX_MODEL=<name>, generated/<name> on the include
// path). The page (viewer/src/) calls the C functions below through the module's heap; it restates
// nothing about a robot: names, the frame tree, limbs, wheels, the clearance box and the nominal pose
// all come from wlx_model_info_json().
//
// Calls are single-threaded and reuse one Model and one Data (no allocation per call).
#include "limits.hpp"  // cli/: the CLI's bounds on input values, so the page rejects what `wlx ik` rejects

#include <fmt/format.h>
#include <wlx/error.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/model.hpp>

#include <Eigen/Geometry>  // AngleAxisd
#include <emscripten/emscripten.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

namespace {

using namespace wlx;

const Model& model() {
  static const Model m{};
  return m;
}

Data& data() {
  static Data d;
  return d;
}

std::string& last_error() {
  static std::string message;
  return message;
}

// JSON string literal (the tables hold identifiers and short English text; escape anyway).
std::string quoted(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", static_cast<unsigned>(static_cast<unsigned char>(c)));
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// Shortest text that reads back as the same double (fmt's default); the tables are finite.
std::string number(double v) { return fmt::format("{}", v); }

template <typename Range, typename Print>
std::string array(const Range& range, Print print) {
  std::string out = "[";
  bool first = true;
  for (const auto& item : range) {
    if (!first) out += ",";
    first = false;
    out += print(item);
  }
  return out + "]";
}

std::string integer(int v) { return std::to_string(v); }

// The box of the generated clearance function (the model file's `clearance`: a frame and a size):
// The clearance box as the model file gives it: its frame (structure.hpp) and its half sizes, which
// the generated clearance() evaluates from the parameters.
struct ClearanceBox {
  int frame = -1;
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();
};

ClearanceBox clearance_box() {
#if __has_include(<wlx/gen/clearance.hpp>)
  ClearanceBox box{gen::kClearanceFrame, Eigen::Vector3d::Zero()};
  gen::clearance(nominal_inputs(), model().params(), {.half_extents = &box.half_extents});
  return box;
#else
  return {};
#endif
}

// Whether the first six inputs are the pose of frame 0 as position and Rz(yaw) Ry(pitch) Rx(roll)
// (the convention the page's base handles use): checked on the model's own forward kinematics at
// an arbitrary pose, so a model built otherwise gets no base handles rather than wrong ones.
bool base_pose_is_first_six_inputs() {
  Coordinates s = nominal_inputs();
  s.head<6>() << 0.3, -0.2, 1.7, 0.4, -0.25, 0.15;
  forward_kinematics(model(), data(), s);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(s(3), Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(s(4), Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(s(5), Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  return (frame_position(data(), 0) - s.head<3>()).norm() < 1e-12 && (frame_rotation(data(), 0) - R).norm() < 1e-12;
}

std::string build_info_json() {
  const Params& p = model().params();
  std::string j = "{";
  j += "\"name\":" + quoted(gen::kModelName);
  j += ",\"description\":" + quoted(gen::kModelDescription);
  j += ",\"inputCount\":" + integer(gen::kInputCount);
  j += ",\"coordinates\":" + array(std::array<int, gen::kCoordinateCount>{}, [k = 0](int) mutable {
         const auto i = static_cast<std::size_t>(k++);
         return "{\"name\":" + quoted(gen::kCoordinateNames[i]) + ",\"unit\":" + quoted(gen::kCoordinateUnits[i]) + "}";
       });
  j += ",\"frames\":" + array(std::array<int, gen::kFrameCount>{}, [k = 0](int) mutable {
         const auto i = static_cast<std::size_t>(k++);
         return "{\"name\":" + quoted(gen::kFrameNames[i]) + ",\"parent\":" + integer(gen::kFrameParent[i]) + "}";
       });
  // Each limb's branch where none is chosen: the model's at the nominal inputs (its file's
  // default, else the first within the joints' ranges), as `wlx ik` takes it.
  const Branches model_choice = resolve_branches(model(), nominal_inputs());
  j += ",\"limbs\":" + array(gen::kLimbs, [&](const gen::LimbInfo& l) {
         std::string s = "{\"name\":" + quoted(l.name) + ",\"title\":" + quoted(l.title);
         s += ",\"joints\":" + array(std::vector<int>(l.joints.begin(), l.joints.begin() + l.size), integer);
         s += ",\"inputs\":" + array(std::vector<int>(l.inputs.begin(), l.inputs.begin() + l.input_count), integer);
         const int limb = static_cast<int>(&l - gen::kLimbs.data());
         return s + ",\"branches\":" + integer(branch_count(limb)) +
                ",\"defaultBranch\":" + integer(model_choice.limb[static_cast<std::size_t>(limb)]) + "}";
       });
  j += ",\"wheels\":" + array(gen::kWheels, [&](const gen::WheelInfo& w) {
         return "{\"name\":" + quoted(w.name) + ",\"contactFrame\":" + integer(w.contact_frame) +
                ",\"ground\":" + integer(w.ground) + ",\"radius\":" + number(p.*w.radius) +
                ",\"forwardAxis\":" + integer(w.forward_axis) + ",\"lateralAxis\":" + integer(w.lateral_axis) + "}";
       });
  // The contacts with the ground, in the order of a run's f_*_<name> columns (the force overlay).
  j += ",\"contacts\":" + array(gen::kContacts, [&, k = 0](const gen::ContactInfo& c) mutable {
         return "{\"name\":" + quoted(c.name) + ",\"kind\":" + (c.kind == gen::ContactKind::wheel ? "\"wheel\"" : "\"foot\"") +
                ",\"frame\":" + integer(c.frame) + ",\"supports\":" + (c.supports ? "true" : "false") +
                ",\"friction\":" + number(settings().friction[static_cast<std::size_t>(k++)]) + "}";
       });
  j += ",\"bodies\":" + array(std::array<int, gen::kBodyCount>{}, [k = 0](int) mutable {
         const auto i = static_cast<std::size_t>(k++);
         return "{\"name\":" + quoted(gen::kBodyNames[i]) + ",\"meaning\":" + quoted(gen::kBodyMeanings[i]) + "}";
       });
  const auto kind = [](gen::RowKind k) {
    return k == gen::RowKind::point ? "\"point\"" : k == gen::RowKind::level ? "\"level\"" : "\"sum\"";
  };
  j += ",\"closureRows\":" + array(std::array<int, gen::kClosureCount>{}, [&, k = 0](int) mutable {
         const auto i = static_cast<std::size_t>(k++);
         const gen::ClosureRowInfo& r = gen::kClosureRows[i];
         return "{\"name\":" + quoted(gen::kClosureNames[i]) + ",\"kind\":" + kind(r.kind) + ",\"frame\":" + integer(r.frame) +
                ",\"axis\":" + integer(r.axis) + ",\"target\":" + integer(r.target) + "}";
       });
  j += ",\"nominalInputs\":" + array(settings().nominal_inputs, number);
  if (gen::kHasClearance) {
    const ClearanceBox box = clearance_box();
    if (box.frame >= 0)
      j += ",\"clearanceBox\":{\"frame\":" + integer(box.frame) + ",\"halfExtents\":" +
           array(std::array<double, 3>{box.half_extents(0), box.half_extents(1), box.half_extents(2)}, number) + "}";
  }
  j += ",\"basePoseInputs\":" + std::string(base_pose_is_first_six_inputs() ? "true" : "false");
  j += ",\"ikTolerance\":" + number(gen::kIkTolerance);
  return j + "}";
}

}  // namespace

extern "C" {

// The model's tables as one JSON object (see build_info_json); valid for the module's lifetime.
EMSCRIPTEN_KEEPALIVE const char* wlx_model_info_json() {
  static const std::string info = build_info_json();
  return info.c_str();
}

// The message of the last failed call: what `wlx ik` prints on stderr for the same request.
EMSCRIPTEN_KEEPALIVE const char* wlx_last_error() { return last_error().c_str(); }

// Closed-form IK of every limb: inputs[kInputCount] and branches[kLimbCount] in, all coordinates
// out (s_out[kCoordinateCount]). Returns 1 on success; 0 on failure, leaving s_out untouched and
// the message in wlx_last_error(). The checks are those of `wlx ik` (cli/commands/ik_commands.cpp,
// solve_ik_request): the inputs' bounds, the runtime's reach and residual errors, and the whole
// closure's residual at most 1e-9.
EMSCRIPTEN_KEEPALIVE int wlx_solve_ik(const double* inputs, const int* branches, double* s_out) {
  try {
    Coordinates s = Coordinates::Zero();
    for (int k = 0; k < kInputCount; ++k) {
      s(k) = inputs[k];
      if (!std::isfinite(s(k)))
        throw Error(std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]), "must be a finite number");
      commands::check_input_bound(k, s(k), std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]));
    }
    Branches b;
    for (int limb = 0; limb < kLimbCount; ++limb) {
      if (branches[limb] < 0 || branches[limb] >= branch_count(limb))
        throw Error("branch." + std::string(gen::kLimbs[static_cast<std::size_t>(limb)].name),
                    fmt::format("{} has branches 0 to {}, got {}", limb_name(limb), branch_count(limb) - 1, branches[limb]));
      b.limb[static_cast<std::size_t>(limb)] = branches[limb];
    }
    solve_ik_closed_form(model(), s, b);
    closure(model(), data(), s, false);
    const double residual = data().Phi.cwiseAbs().maxCoeff();
    if (!(residual <= 1e-9))
      throw Error("closure_residual", fmt::format("{:.3e}: the solution does not satisfy the model's closure", residual));
    s.array() += 0.0;  // no "-0.0" shown
    for (int k = 0; k < kCoordinateCount; ++k) s_out[k] = s(k);
    last_error().clear();
    return 1;
  } catch (const Error& e) {
    last_error() = std::string("wlx: error: ") + e.what();  // main.cpp's prefix: the CLI's line verbatim
    return 0;
  }
}

// Frame origins (positions[3 * kFrameCount], frame after frame) and orientations
// (rotations[9 * kFrameCount], each 3 x 3 column-major: the frame's axes) in K0.
EMSCRIPTEN_KEEPALIVE void wlx_forward_kinematics(const double* s_in, double* positions, double* rotations) {
  const Coordinates s = Eigen::Map<const Coordinates>(s_in);
  forward_kinematics(model(), data(), s);
  Eigen::Map<gen::FramePositions> positions_out(positions);
  positions_out = data().frame_positions;
  for (int f = 0; f < gen::kFrameCount; ++f)
    Eigen::Map<Eigen::Matrix3d>{rotations + 9 * f} = data().frame_rotations[static_cast<std::size_t>(f)];
}

// max |Phi(s)| over the closure rows: m or rad.
EMSCRIPTEN_KEEPALIVE double wlx_closure_residual(const double* s_in) {
  const Coordinates s = Eigen::Map<const Coordinates>(s_in);
  closure(model(), data(), s, false);
  return data().Phi.cwiseAbs().maxCoeff();
}

// Each body's centre of mass in K0 (com[3 * kBodyCount]).
EMSCRIPTEN_KEEPALIVE void wlx_body_centres(const double* s_in, double* com) {
  const Coordinates s = Eigen::Map<const Coordinates>(s_in);
  gen::BodyVectors c;
  gen::bodies(s, Coordinates::Zero().eval(), model().params(), {.com = &c});
  Eigen::Map<gen::BodyVectors> com_out(com);
  com_out = c;
}

}  // extern "C"
