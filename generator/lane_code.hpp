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
  joint_axis,         // (k, c): a joint's twist per unit rate (spatial_axis)
  com_offset,         // (i, c): the body's CoM in K0
  minus_com_offset,   // (i, c)
  com_rotation,       // (i, a, b): the CoM frame's rotation
  mass,               // (i)
  inertia,            // (i, a): principal moment
  bias_acceleration,  // (i, c): the CoM's acceleration at zero u'
  bias_torque,        // (i, a): I alpha_bias + omega x I omega, body axes
  gravity,            // g
  minus_gravity,      // -g
  // Values the code computes (rows of lanes per unit commanded speed in reduced_dynamics,
  // scalars in generalized_forces).
  spatial_velocity,           // (k, c): (omega; velocity at K0's origin) out to node k
  motion_cross,               // (k, c): V_parent x S
  spatial_acceleration,       // (k, c)
  com_velocity,               // (i, c)
  com_acceleration,           // (i, c)
  force,                      // (i, c): the body's force (m times its CoM's velocity or acceleration)
  body_rate,                  // (i, a): omega in body axes
  body_angular_acceleration,  // (i, a)
  angular_momentum,           // (i, a): I omega, body axes
  body_moment,                // (i, a): I alpha + omega x I omega, body axes
  moment,                     // (i, c): about K0's origin, in K0
  wrench,                     // (k, c): the sum over the bodies beyond node k
  joint_force,                // (k): node k's tau
  coordinate_force,           // (j): the sum of coordinate j's joints' taus
  commanded_force,            // (l): Q*_l
  // The composite-rigid-body pass of reduced_dynamics: inertias about its reference point (the
  // first revolute joint's origin), in K0.
  first_moment,               // (i, c): a body's m p
  inertia_difference,         // (i, k): a body's principal moment k less the first (a lane scalar)
  rotated_inertia,            // (i, a, k): R(a, k) times inertia_difference (i, k)
  inertia_shift,              // (i): a body's first principal moment plus m |p|^2
  origin_inertia,             // (i, a, b): a body's rotational inertia about the reference point
  composite_mass,             // (k): the mass of the bodies beyond node k
  composite_first_moment,     // (k, c)
  composite_inertia,          // (k, a, b): rotational, about the reference point
  joint_momentum,             // (k, c): the composite inertia beyond node k times its axis, (force; moment)
  joint_mass,                 // (j, k): M between the joints of nodes j and k, k beyond j
  projected_mass,             // (l, k): (T^T M)(l, the coordinate of node k)
  reduced_mass,               // (l, b): M on the commanded speeds, l <= b
  gravity_force,              // (k): node k's tau from gravity, over -g
  commanded_gravity,          // (l): Q_gravity_l over -g
  // generalized_forces' recursion in the joints' own frames (local_motion in generalized_forces.cpp).
  local_rotation,     // (k, a, b): node k's frame in its parent's (a lane scalar)
  local_offset,       // (k, c): node k's origin in its parent's frame (a lane scalar)
  offset_velocity,       // (k, c): the parent's omega x node k's origin, in the parent's axes
  carried_acceleration,  // (k, c): the parent's acceleration at node k's origin, in the parent's axes
  incoming_motion,       // (k, c): the parent's omega, alpha, a at node k's origin, in node k's axes (3 each)
  transmitted_force,  // (k, c): the force beyond node k in its parent's axes
  // Values of the composite pass' own making (composite_units.cpp), named after another value v:
  lanes_of,  // (v): a row of lanes, v's quantity for each limb of a row unit
  row_sum,   // (v): the row whose lanes add up to v
  negated,   // (v): -v, to be put in a lane
  constant,  // (0): 1, (1): -1, to be put in a lane
  // Rows of the lane code's own: T's row of a dense coordinate j, and the accumulators of the
  // outputs (M's row k, b_velocity, Q_gravity, B_bias's column j).
  rate_row,
  mass_matrix_row,
  velocity_forces,
  gravity_forces,
  bias_column,
};

struct ValueId {
  Quantity what = Quantity::zero;
  std::array<int, 3> index = {0, 0, 0};
  // A row's other copies: wide, its lanes laid out one per commanded speed (a narrow row widened,
  // an accumulator's wide part); part n > 0, an accumulator's n-th narrow part.
  bool wide_copy = false;
  int part = 0;
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

// How a value is held: a scalar, or a row of lanes, narrow (lanes shared by speeds that never move
// a common body: LaneProgram::width of them) or wide (one per commanded speed).
enum class Layout : unsigned char { scalar, narrow, wide };

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
// target += sum of terms.
struct Accumulate {
  ValueId target;
  Layout layout;
  std::vector<Term> terms;
};
// target = base (zero if none), plus `value` in lane `lane`.
struct PlusLane {
  ValueId target;
  Layout layout;
  ValueId base;
  int lane;
  ValueId value;
};
// target (wide) = source's lanes moved: (wide lane, source's lane) per speed.
struct Widen {
  ValueId target, source;
  std::vector<std::pair<int, int>> lanes;
};
// The rate_row `target` (narrow) from T's row: its `lanes` (lane, T's entry), or, when `whole`,
// every entry in the lane of its column.
struct LoadRow {
  ValueId target;
  int row;
  bool whole;
  std::vector<std::pair<int, ValueId>> lanes;
};
// An accumulator's part, zero before the code adds to it.
struct ZeroRow {
  ValueId target;
  Layout layout;
};
// The lane types (LaneProgram's width and speeds).
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

using Step = std::variant<Comment, Define, Accumulate, PlusLane, Widen, LoadRow, ZeroRow, LaneTypes, OpenOutput, CloseOutput, Store>;

// A statement, and the output its operations count for (the derivation's numbering).
struct Statement {
  Step step;
  int output = 0;
};

// The whole code: its lane scalars (in the order they were made: the order of CSE's roots), its
// statements in order, and the lanes of its rows.
struct LaneProgram {
  // Scalar code (generalized_forces) or rows of lanes (reduced_dynamics): the printer's names
  // differ between the two.
  enum class Kind : unsigned char { lanes, scalars } kind = Kind::scalars;
  int width = 1;   // a narrow row's lanes
  int speeds = 1;  // a wide row's (the commanded speeds)
  std::vector<std::pair<ValueId, ex>> scalars;
  std::vector<Statement> statements;
  // A lane scalar of the given value; zero (nothing made) for an exact zero.
  ValueId scalar(const ValueId& id, const ex& value) {
    if (value.is_zero()) return {};
    scalars.emplace_back(id, value);
    return id;
  }
  bool shares_lanes() const { return width < speeds; }
  int lanes(Layout layout) const { return layout == Layout::scalar ? 1 : layout == Layout::wide ? speeds : width; }
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
// for the statements that stay in any case: accumulations, stores, declarations).
std::vector<ValueId> reads(const Step& step);
ValueId defined_unless_unread(const Step& step);
// Its operations, lane by lane.
OpCount operations(const LaneProgram& program, const Step& step);
// What the kept statements cost the machine, in instructions: a row's operation is one per vector
// of 4 lanes (the lanes of detail::Lanes<double, N> in 32-byte vectors), and moving a lane in or
// out of a row (PlusLane, Widen, LoadRow, a Store's lane) one each. Operation counts weigh each lane
// as a scalar; this weighs the code as it runs, to choose between two derivations of one function.
long instructions(const LaneProgram& program);

}  // namespace wlx::codegen::lane_code
