// The dynamics passes' code as an intermediate form: reduced_dynamics and generalized_forces derive
// statements on values (sums of products, rows of lanes, the outputs' entries), and one printer
// (lane_printer.hpp) turns them into C++. A value is named by what it is (ValueId), never by its
// C++ spelling, so that the derivations neither choose nor parse the generated code's names: which
// statement reads which value, what is left unread and how many operations each costs all follow
// from this structure (lane_code.cpp). Internal to the generator.
#pragma once

#include "expr_graph.hpp"  // OpCount
#include "vocabulary.hpp"  // ex

#include <array>
#include <compare>
#include <map>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace wlx::codegen::lane_code {

// What a value is. Its indices (ValueId::index) say whose: a joint's node k, a body i, a coordinate j,
// a commanded speed l, a component c (or a, b of a matrix).
enum class Quantity : unsigned char {
  zero,  // an exact zero: dropped from sums (nothing is computed for it)
  one,   // a product's missing factor (Term)
  // Entries of the function's inputs.
  rate_basis_entry,  // T(j, l)
  rate,              // s'_j
  acceleration,      // s''_j
  // Lane scalars: expressions in s and the parameters, computed with the function's other
  // expressions (common subexpressions shared) before the code reads them.
  joint_axis,     // (k, c): a joint's twist per unit rate (spatial_axis), or its axis in its own frame
  com_offset,     // (i, c): the body's CoM in K0, or in its joint's frame
  com_rotation,   // (i, a, b): the CoM frame's rotation, in K0 or in its joint's frame
  mass,           // (i)
  inertia,        // (i, a): principal moment
  gravity,        // g
  minus_gravity,  // -g
  // Values the code computes (scalars, or rows of lanes for sibling limbs in reduced_dynamics).
  spatial_velocity,           // (k, c): (omega; velocity at K0's origin) out to node k
  motion_cross,               // (k, c): V_parent x S; in a joint's own frame, its e s' (c < 3 angular)
  spatial_acceleration,       // (k, c)
  com_velocity,               // (i, c)
  com_acceleration,           // (i, c)
  force,                      // (i, c): the body's force (m times its CoM's velocity or acceleration)
  body_rate,                  // (i, a): omega in body axes
  body_angular_acceleration,  // (i, a)
  angular_momentum,           // (i, a): I omega, body axes
  body_moment,                // (i, a): I alpha + omega x I omega, body axes
  moment,                     // (i, c): about K0's origin in K0, or its joint's origin in its frame
  wrench,                     // (k, c): the sum over the bodies beyond node k
  joint_force,                // (k): node k's tau
  coordinate_force,           // (j): the sum of coordinate j's joints' taus
  commanded_force,            // (l): Q*_l
  // The composite-rigid-body pass of reduced_dynamics (composite_dynamics.cpp): inertias about
  // each joint's origin, in its frame.
  first_moment,               // (i, c): a body's m p
  inertia_difference,         // (i, k): a body's principal moment k less the first (a lane scalar)
  rotated_inertia,            // (i, a, k): R(a, k) times inertia_difference (i, k)
  inertia_shift,              // (i): a body's first principal moment plus m |p|^2
  origin_inertia,             // (i, a, b): a body's rotational inertia about its joint's origin
  composite_mass,             // (k): the mass of the bodies beyond node k
  composite_first_moment,     // (k, c)
  composite_inertia,          // (k, a, b): rotational, about node k's origin
  joint_momentum,             // (k, c): the composite inertia beyond node k times its axis, (force; moment)
  joint_mass,                 // (j, k): M between the joints of nodes j and k, k beyond j
  projected_mass,             // (l, k): (T^T M)(l, the coordinate of node k)
  reduced_mass,               // (l, b): M on the commanded speeds, l <= b
  gravity_force,              // (k): node k's tau from gravity, over -g
  commanded_gravity,          // (l): Q_gravity_l over -g
  // The recursions in the joints' own frames (generalized_forces' local_motion, reduced_dynamics' b_velocity).
  local_rotation,     // (k, a, b): node k's frame in its parent's (a lane scalar)
  local_offset,       // (k, c): node k's origin in its parent's frame (a lane scalar)
  offset_velocity,       // (k, c): the parent's omega x node k's origin, in the parent's axes
  carried_acceleration,  // (k, c): the parent's acceleration at node k's origin, in the parent's axes
  incoming_motion,       // (k, c): the parent's omega, alpha, a at node k's origin, in node k's axes (3 each)
  transmitted_force,  // (k, c): the force (c < 3) and moment (c >= 3) beyond node k in its parent's axes
  // reduced_dynamics' composite-rigid-body pass in the joints' own frames (composite_dynamics.cpp):
  // node k's composite inertia carried into its parent's frame by its placement (R, r).
  turned_first_moment,   // (k, c): R h
  carried_first_moment,  // (k, c): R h + m r
  turned_inertia,        // (k, a, b): R J
  carried_shift,         // (k): r . (R h + m r) + r . R h
  carried_inertia,       // (k, a, b): R J R^T shifted to the parent's origin
  carried_momentum,      // (j, k, c): node k's I_k S_k, (force; moment), in node j's frame
  up_direction,          // (k, c): K0's z axis in node k's frame (a lane scalar)
  gravity_wrench,        // (k, c): (m up; h x up) of node k's composite
  // Values of the composite pass' own making (composite_units.cpp), named after another value v:
  lanes_of,  // (v): a row of lanes, v's quantity for each limb of a row unit
  row_sum,   // (v): the row whose lanes add up to v
  negated,   // (v): -v, to be put in a lane
  scalar_part,  // (v): the scalar terms of row v's sum, added up
  everywhere,   // (v): a row with scalar v in every lane
  constant,  // (0): 1, (1): -1, to be put in a lane
};

struct ValueId {
  Quantity what = Quantity::zero;
  std::array<int, 3> index = {0, 0, 0};
  bool is_zero() const { return what == Quantity::zero; }
  auto operator<=>(const ValueId&) const = default;
};
inline ValueId value_id(Quantity what, int a = 0, int b = 0, int c = 0) { return {what, {a, b, c}}; }
inline const ValueId kOne = value_id(Quantity::one);

// factor * value (factor one: the value alone), of lane `lane` of a row when it is not -1, negated
// in a sum when `negate`.
struct Term {
  ValueId factor = kOne;
  ValueId value;
  int lane = -1;
  bool negate = false;
};

// How a value is held: a scalar, or a row of LaneProgram::width lanes (one per limb of a row unit).
enum class Layout : unsigned char { scalar, row };

// The statements. A comment's text is quoted by the printer.
struct Comment {
  std::string text;
};
// target = sum of terms (each term's value of the target's layout).
struct Define {
  ValueId target;
  Layout layout;
  std::vector<Term> terms;
};
// A row `target` from scalars: its `lanes` (lane, value), the others zero.
struct LoadRow {
  ValueId target;
  std::vector<std::pair<int, ValueId>> lanes;
};
// The lane type (LaneProgram's width).
struct LaneTypes {};
// The outputs: the block that writes output `output` when it is requested, and its entries.
struct OpenOutput {
  std::string output;
  std::string note;  // a comment on the block's first line, or empty
  enum class Prologue : unsigned char { none, zero, zero_if_asked } prologue = Prologue::none;
  bool indent_body = true;  // false: the block's statements at the level of the code around it
};
struct CloseOutput {};
// (*output)(row[, column]) = sum of terms (Scalar(0) for none); mirrored: also (column, row).
struct Store {
  std::string output;
  int row, column = -1;
  bool mirrored = false;
  std::vector<Term> terms;
};

using Step = std::variant<Comment, Define, LoadRow, LaneTypes, OpenOutput, CloseOutput, Store>;

// A statement, and the output its operations count for (the derivation's numbering).
struct Statement {
  Step step;
  int output = 0;
};

// The whole code: its lane scalars (in the order they were made: the order of CSE's roots), its
// statements in order, and the lanes of its rows.
struct LaneProgram {
  int width = 1;  // a row's lanes
  std::vector<std::pair<ValueId, ex>> scalars;
  std::vector<Statement> statements;
  // The values of the composite builder's own making (lanes_of, row_sum, negated, scalar_part,
  // everywhere): the value each is named after.
  std::map<ValueId, ValueId> named_after;
  // A lane scalar of the given value; zero (nothing made) for an exact zero.
  ValueId scalar(const ValueId& id, const ex& value) {
    if (value.is_zero()) return {};
    scalars.emplace_back(id, value);
    return id;
  }
  int lanes(Layout layout) const { return layout == Layout::scalar ? 1 : width; }
};

// A visitor of a Step from one lambda per kind of statement (std::visit).
template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;  // clang 14 deduces no aggregate's arguments

// ---- what follows from the structure (lane_code.cpp) --------------------------------------------

// The statements the code keeps: without the values nothing reads (a dense joint's wrench sums
// feed only the components its twist has; of a link's I omega, the component along its axis),
// over and over until each value left is read.
std::vector<bool> kept_statements(const LaneProgram& program);
// The values a statement reads (with repeats), and the value it defines that may go unread (zero
// for the statements that stay in any case: stores, declarations).
std::vector<ValueId> reads(const Step& step);
ValueId defined_unless_unread(const Step& step);
// Its operations, lane by lane.
OpCount operations(const LaneProgram& program, const Step& step);

}  // namespace wlx::codegen::lane_code
