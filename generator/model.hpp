// What a model is, in memory: parameters, coordinates, frames, bodies, the holonomic (closure)
// and non-holonomic conditions, and the structure the runtime needs (limbs, dependent pairs,
// inverse-dynamics set-up, nominal state), all in the vocabulary of vocabulary.hpp.
// model_file.hpp builds a Model from a model file; derivations.hpp turns it into functions.
#pragma once

#include "vocabulary.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace wlx::codegen {

// What a parameter is, which fixes its unit and the values the runtime accepts for it.
enum class ParameterKind { length, offset, angle, mass, inertia, gravity, other };
const char* kind_name(ParameterKind kind) noexcept;

// One elementary transform of a frame's chain, as the model file gives it (kept for the
// inverse-kinematics derivation, which matches patterns on the chain).
struct ChainStep {
  enum class Kind { Translate, Rotate, Slide, Turn };  // fixed offset, joint, prismatic joint, fixed angle
  Kind kind = Kind::Translate;
  Axis axis = Axis::X;
  Vec3 offset;          // Translate
  int coordinate = -1;  // Rotate, Slide
  int sign = 1;         // Rotate, Slide: -1 for a step written `rz: -q` (about, along the negative axis)
  ex angle;             // Turn
};

struct NamedFrame {
  std::string name;
  std::string meaning;
  std::string parent;  // "K0" for the ground
  std::vector<ChainStep> chain;
  Frame frame;
  // >= 0: the contact frame wlx-gen derives for wheel `derived_from_wheel` (a wheel on a hub): no
  // chain, its parent is the hub frame, its origin the rim point nearest the ground.
  int derived_from_wheel = -1;
};

// A rigid body: its centre-of-mass frame (orientation of the body, origin at the CoM) and the
// names of its mass parameters.
struct Body {
  std::string name;
  std::string meaning;
  std::string frame;  // the frame it moves with
  Frame com_frame;
  // The same, relative to `frame` (the description's data): the CoM in the frame's axes, and the
  // fixed turns from the frame's axes to the principal axes, in order.
  Vec3 com;
  std::vector<std::pair<Axis, ex>> principal_turns;
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
// Either the file gives the contact frame (with virtual joints and level rows that keep it on the
// rim's lowest point), or the wheel sits on a hub frame and wlx-gen derives the contact frame.
struct NonholonomicWheel {
  std::string name;
  std::string contact;  // frame name (derived for a wheel on a hub)
  Axis lateral = Axis::Y;
  Axis forward = Axis::X;
  std::string radius;  // parameter name of the rolling radius
  int ground = -1;     // the input holding the ground level under the wheel
  std::string hub;     // the hub frame (wheel centre, not spinning), or empty
  Axis axle = Axis::Y;  // the hub frame's axis the wheel turns about
  std::string offset;   // parameter name of the rolling plane's place along the axle from the hub, or empty: 0
};

// Closure rows and the dependent joints they determine: a square diagonal block of dPhi/ds.
struct Limb {
  std::string name;
  std::string title;  // for messages: "left leg"
  std::vector<int> rows;
  std::vector<int> joints;
  int branch = -1;           // the model file's default branch of its closed form, or -1: none given
  std::string branch_place;  // where the file gives it (file:line:column: field), for messages
};

// The input rates, one per wheel, that the wheels' rolling rows determine.
struct DependentPair {
  std::string name;
  std::vector<int> coordinates;
};

// An actuator: a joint (a coordinate), or the drive of a wheel on a hub (a motor between the hub
// and the wheel, whose rate is the wheel's spin relative to the hub).
struct Actuator {
  int coordinate = -1;  // the joint's coordinate, or -1 for a wheel's drive
  int wheel = -1;       // the wheel (index into Model::wheels), or -1 for a joint
  std::string name;     // the joint's name, or spin_<wheel>
};

struct Dynamics {
  std::string gravity;  // parameter name; gravity acts along -z of K0
  std::vector<int> commanded;
  std::string pair;  // name of the dependent pair
  std::vector<Actuator> actuated;
  std::vector<double> weights;  // default weighting, one per actuator
  std::vector<double> torque_limits;  // the largest |torque| of each actuator (N m), or empty: unlimited
  bool torque_limits_from_efforts = false;  // torque_limits are the joints' and drives' efforts (`limits`, URDF)
};

// A box attached to a frame (centred on its origin, along its axes) whose lowest corner must
// stay above the ground.
struct ClearanceBox {
  std::string frame;
  std::array<ex, 3> size;
};

// One sweep of the IK verification: one input moved over a range, one limb checked.
struct IkSweep {
  std::string id;
  int input = -1;
  double from = 0, to = 0, step = 0;  // SI (radians for angles)
  bool degrees = false;               // quoted in degrees
  int limb = -1;
  int branch = -1;  // the limb's branch along the sweep, or -1: the model's choice at the start pose
};

// Coulomb friction coefficients of the contacts with the ground, per kind of contact (the model
// file's `contacts.friction`; the defaults are documented in docs/model-format.md).
struct ContactFriction {
  double feet = 0.5;
  double wheels = 0.5;
};

struct Model {
  std::string name;
  std::string description;
  std::string source;  // where the description lives, for the banner
  // The files it was read from (the model file, then the URDF it names): wlx-gen --depfile lists them,
  // so that a build knows its inputs without reading the model file itself.
  std::vector<std::string> input_files;
  std::vector<Parameter> parameters;
  std::vector<ParameterKind> parameter_kinds;  // one per parameter
  std::vector<Coordinate> coordinates;
  int input_count = 0;  // the first input_count coordinates are the independent inputs
  std::vector<NamedFrame> frames;
  std::vector<Body> bodies;
  std::vector<ClosureCondition> closure;
  std::vector<NonholonomicWheel> wheels;
  std::vector<Limb> limbs;
  std::vector<int> pair_candidates;
  std::vector<DependentPair> pairs;
  std::string default_pair;
  std::optional<Dynamics> dynamics;
  std::optional<ClearanceBox> clearance;
  ContactFriction friction;
  std::vector<double> nominal;  // one value per coordinate: the inputs' nominal values, the dependent
                                // joints' start values for Newton's method (0 where none is given)
  std::vector<double> sweep_start;  // the IK sweeps' initial inputs (nominal with overrides)
  std::vector<IkSweep> sweeps;
  // The joints' limits, one entry per coordinate (the `limits` section and a URDF's <limit>s):
  // the range [lower, upper] (-inf, inf: none), the largest effort and speed (0: none).
  std::vector<double> lower, upper, effort, velocity;

  const Parameter& parameter(const std::string& name) const;
  const Coordinate& coordinate(const std::string& name) const;
  const Frame& frame(const std::string& name) const;
  int frame_index(const std::string& name) const;  // -1 if absent
  const DependentPair& pair(const std::string& name) const;
};

}  // namespace wlx::codegen
