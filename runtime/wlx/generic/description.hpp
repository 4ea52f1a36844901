// A model's description as the runtime compiled once for every model reads it: model.json, the
// data wlx-gen writes beside the code (docs/model-format.md, "The description"), typed. Its names,
// structure and the model file's run-time settings; the code that goes with it is a ModelCode
// (wlx/model_code.hpp).
#pragma once

#include "wlx/parameter_checks.hpp"

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace wlx::generic {

// The largest description read: beyond these the file is not one wlx-gen writes for a machine
// (a 97-link robot has about 130 coordinates and frames), and every per-limb array of the
// algorithms is bounded by kMaxLimbs.
inline constexpr int kMaxCoordinates = 1024;
inline constexpr int kMaxFrames = 1024;
inline constexpr int kMaxParameters = 16384;
inline constexpr int kMaxLimbs = 64;
inline constexpr int kMaxLimbSize = 8;  // the limb steps are compiled for sizes 1 to 8
inline constexpr int kMaxWheels = 64;

struct Coordinate {
  std::string name;
  std::string unit;  // "m" or "rad"
  bool input = false;
};

struct Frame {
  std::string name;
  int parent = -1;  // index in frames; -1: the ground frame K0
};

struct Parameter {
  std::string name;
  std::string unit;
  ParameterKind kind = ParameterKind::other;
  double value = 0;  // the model file's value
};

struct Body {
  std::string name;
  int frame = -1;
  int mass = -1;                   // parameter index
  std::array<int, 3> inertia{};    // parameter indices of the principal moments
};

struct Limb {
  std::string name;
  std::string title;         // for messages
  std::vector<int> joints;   // dependent coordinates, in the order of the rows' unknowns
  std::vector<int> rows;     // closure rows (as many as joints)
  std::vector<int> inputs;   // the input coordinates those rows read
};

struct Wheel {
  std::string name;
  int contact_frame = -1;  // the frame at its contact point
  int hub_frame = -1;      // -1: none (the contact frame's own turn is the wheel's)
  int radius = -1;         // parameter index
  int forward_axis = 0, lateral_axis = 1, axle_axis = 1;  // 0 x, 1 y, 2 z: of the contact frame (axle: of the hub)
  int ground = -1;         // the input its ground level is, or -1
};

// A choice of the input rates the wheels' rolling determines, one per wheel.
struct Pair {
  std::string name;
  std::vector<int> coordinates;  // the rates' coordinates, one per wheel
};

// The model file's numbers that no generated function holds (model.json's settings).
struct Settings {
  std::vector<double> nominal_inputs;   // per input
  std::vector<double> dependent_start;  // per coordinate: Newton's start of the dependent joints (inputs: 0)
  std::vector<double> lower, upper;     // per coordinate; -inf, inf: no range
  std::vector<double> velocity_limit;   // per coordinate; 0: none
  std::vector<int> default_branch;      // per limb; -1: none given
};

struct Description {
  std::string model;
  std::string code_key;
  int input_count = 0;
  std::vector<Coordinate> coordinates;  // the inputs first
  std::vector<Frame> frames;
  std::vector<Parameter> parameters;
  std::vector<Body> bodies;
  std::vector<Limb> limbs;
  std::vector<std::string> closure_rows;
  std::vector<Wheel> wheels;
  std::vector<int> pair_candidates;  // the inputs whose rates may be a pair's
  std::vector<Pair> pairs;           // the named choices (one, of no rates, without wheels)
  int default_pair = 0;
  Settings settings;

  int coordinate_count() const noexcept { return static_cast<int>(coordinates.size()); }
  // The size of the largest limb (at least 1: the limb steps' size).
  int max_limb_size() const noexcept;
  // By name, or -1.
  int coordinate_index(std::string_view name) const noexcept;
  int frame_index(std::string_view name) const noexcept;
  int parameter_index(std::string_view name) const noexcept;
  int limb_index(std::string_view name) const noexcept;
  int wheel_count() const noexcept { return static_cast<int>(wheels.size()); }
};

// Reads model.json's text (at most kMaxDescriptionBytes). Throws wlx::Error (field "model.json")
// naming what is missing or wrong and where: a description of another format, or one whose parts
// do not fit together (validate).
inline constexpr std::size_t kMaxDescriptionBytes = std::size_t{4} << 20;  // the largest models' are under 1 MB
Description read_description(std::string_view json_text);

// Throws wlx::Error (field "model.json") unless every part fits: sizes within the bounds above,
// unique names, units "m" or "rad", the inputs first, every index in range (a frame's parent
// before it, a body's frame and parameters, a limb's joints dependent, its inputs inputs, its rows
// closure rows, as many rows as joints), every setting sized to what it is for, ranges ordered. A
// Model validates its description so (one made in code too).
void validate(const Description& description);

}  // namespace wlx::generic
