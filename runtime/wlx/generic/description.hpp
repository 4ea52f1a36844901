// A model's description as the runtime compiled once for every model reads it: model.json, the
// data wlx-gen writes beside the code (docs/model-format.md, "The description"), typed. Its names,
// structure and the model file's run-time settings; the code that goes with it is a ModelCode
// (wlx/model_code.hpp).
#pragma once

#include "wlx/parameter_checks.hpp"

#include <array>
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
  Settings settings;

  int coordinate_count() const noexcept { return static_cast<int>(coordinates.size()); }
  // The size of the largest limb (at least 1: the limb steps' size).
  int max_limb_size() const noexcept;
  // By name, or -1.
  int coordinate_index(std::string_view name) const noexcept;
  int frame_index(std::string_view name) const noexcept;
  int parameter_index(std::string_view name) const noexcept;
  int limb_index(std::string_view name) const noexcept;
};

// Reads model.json's text. Throws wlx::Error (field "model.json") naming what is missing or wrong
// and where: a description of another format, or one whose parts do not fit together.
Description read_description(std::string_view json_text);

}  // namespace wlx::generic
