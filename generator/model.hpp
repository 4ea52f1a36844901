// What a model description is: parameters, coordinates, frames of interest, bodies, and the
// holonomic (closure) and non-holonomic conditions, all in the vocabulary of vocabulary.hpp.
// The derivations (derivations.hpp) turn a Model into the functions that get emitted.
#pragma once

#include "vocabulary.hpp"

#include <string>
#include <vector>

namespace wlx::gen {

struct NamedFrame {
  std::string name;
  std::string meaning;
  Frame frame;
};

// A rigid body: its centre-of-mass frame (orientation of the body, origin at the CoM) and the
// names of its mass parameters.
struct Body {
  std::string name;
  std::string meaning;
  Frame com_frame;
  std::string mass;
  std::array<std::string, 3> inertia;  // principal moments about the CoM, in the body frame
};

// One scalar holonomic condition Phi_i(s) = 0.
struct ClosureCondition {
  enum class Kind {
    PointEqualsCoordinate,   // component `axis` of the frame origin minus coordinate `target` = 0
    AttachedDirectionLevel,  // component z (K0) of a unit vector fixed in the frame = 0
    CoordinateSum,           // the sum of `coordinates` = 0
  };
  std::string name;
  Kind kind = Kind::PointEqualsCoordinate;
  std::string frame;
  Axis axis = Axis::X;  // PointEqualsCoordinate: K0 component; AttachedDirectionLevel: local axis
  int target = -1;
  std::vector<int> coordinates;
};

// A wheel that may not slide sideways: v_W . n_W = 0 with n_W the contact frame's lateral axis.
struct NonholonomicWheel {
  std::string name;
  std::string contact;  // frame name
  Axis lateral = Axis::Y;
  Axis forward = Axis::X;
  std::string radius;  // parameter name of the rolling radius
};

struct Model {
  std::string name;
  std::string source;  // where the description lives, for the banner
  std::vector<Parameter> parameters;
  std::vector<Coordinate> coordinates;
  int input_count = 0;  // the first input_count coordinates are the independent inputs
  std::vector<NamedFrame> frames;
  std::vector<Body> bodies;
  std::vector<ClosureCondition> closure;
  std::vector<NonholonomicWheel> wheels;

  const Parameter& parameter(const std::string& name) const;
  const Coordinate& coordinate(const std::string& name) const;
  const Frame& frame(const std::string& name) const;
};

// The walking excavator of MODEL.md, built in excavator_model.cpp.
Model make_excavator_model();

}  // namespace wlx::gen
