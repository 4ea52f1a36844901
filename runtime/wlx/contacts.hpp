// Will it tip, will it slip: the forces the ground exerts at every contact (each frame the closure
// ties to the ground, each wheel), the support polygon, the tip-over and friction margins.
//
// The constraint forces are the multipliers of the equations of motion on all coordinates s,
//   tau_bodies = B^T tau + dPhi/ds^T lambda + C^T mu + E_held^T nu,
// with tau_bodies the bodies' inertia, velocity and gravity forces on s (generalized_forces' tau),
// B^T tau the actuators' (joints, and wheel drives through their drive rows), lambda the closure
// rows', mu the rolling rows' and nu the held inputs'. On the dependent joints dPhi/ds is the limbs'
// block diagonal, on the dependent pair the reduced wheel rows are J_beta: both are factorized by the
// step already (nonholonomic.hpp), so the multipliers cost two small triangular solves. The rows of
// each contact (gen::kContacts) turn them into forces: a point row's multiplier is the K0 component
// of the ground's force on the frame's origin, a level row's a moment about (axis x e_z), a rolling
// row's the lateral force along n_W, a drive's torque / radius the longitudinal force.
// docs/architecture.md ("Contact forces and stability") derives it; the tests check the machine's
// momentum balance with them against the bodies' accelerations, a second formulation.
#pragma once

#include "wlx/dynamics.hpp"
#include "wlx/support_polygon.hpp"

#include <array>
#include <cstddef>
#include <string>

WLX_MODEL_NAMESPACE_BEGIN

inline constexpr int kContactCount = gen::kContactCount;
namespace contacts_detail {
// A contact's or body's slot in the generated tables (std::arrays) from a loop's int.
constexpr std::size_t at(int i) noexcept { return static_cast<std::size_t>(i); }
}  // namespace contacts_detail
// One slot per contact, and one unused slot for a model without contacts: Eigen refuses a column of
// a 3 x 0 matrix at compile time even where no loop reaches it. Loops run to kContactCount.
inline constexpr int kContactSlots = kContactCount > 0 ? kContactCount : 1;
using ContactVector = Eigen::Matrix<double, kContactSlots, 1>;
using ContactPoints = Eigen::Matrix<double, 3, kContactSlots>;  // one K0 vector per contact

struct ContactForces {
  ContactPoints point;   // where each contact is (the frame's origin), K0
  ContactPoints force;   // the ground's force on the machine there, K0
  ContactPoints moment;  // the ground's moment there (level rows; zero for a point contact), K0
  ContactVector normal;        // force . e_z (the ground's normal is K0's z): negative pulls on the ground
  ContactVector tangential;    // |force - normal e_z|
  ContactVector lateral;       // wheels: force . n_W (the contact frame's lateral axis); feet 0
  ContactVector longitudinal;  // wheels: force . t_W (its forward axis); feet 0
  // mu normal - tangential (N): how far the force is inside the friction cone; negative: it slips.
  // For a contact that does not support the machine (no z row), 0.
  ContactVector friction_margin;
  // The equations of the commanded speeds (not used to find the multipliers) at the solution,
  // largest |residual| relative to the largest generalized force: rounding when tau produces Q*.
  double consistency = 0;
};

// The contact forces of an inverse-dynamics step: `terms` from inverse_dynamics() at s (whose
// factorizations data still holds), `tau` the actuator torques applied (any that produce terms.Qstar:
// the forces depend on the distribution). Allocates nothing. Throws wlx::Error for a model without
// a dynamics section.
void contact_forces(const Model& model, Data& data, const Coordinates& s, const DynamicsTerms& terms,
                    const TorqueVector& tau, ContactForces& out);

// The affine map from the torques to the contact forces at one step: for every tau with
// J_beta^T tau = Q*, force.col(c) = offset.col(c) + gain[c] * tau (column-major over contacts:
// rows 3c..3c+2 of gain). What a torque distribution that keeps the machine on its contacts needs.
struct ContactForceMap {
  ContactPoints offset;
  Eigen::Matrix<double, 3 * kContactSlots, kActuatedCount> gain;
};
void contact_force_map(const Model& model, Data& data, const Coordinates& s, const DynamicsTerms& terms,
                       ContactForceMap& out);

// The margins (wlx/support_polygon.hpp: the polygon's size, the static and ZMP margins with the
// ZMP, the tip angle and its edge), with the centre of mass and the polygon they are taken on.
struct Stability : support::Margins {
  Eigen::Vector3d com = Eigen::Vector3d::Zero();  // the machine's centre of mass, K0
  // The support polygon: the supporting contacts in load (normal force > 0), counter-clockwise seen
  // from above, its first polygon_size entries.
  std::array<int, kContactCount> polygon{};
};

// Stability of the step whose contact forces are `forces` (data's frame positions from
// contact_forces()). With nothing in load (polygon_size 0) the margins and the tip angle are 0 and
// the ZMP is the CoM's projection. Allocates nothing.
void stability(const Model& model, Data& data, const Coordinates& s, const ContactForces& forces, Stability& out);

// The whole machine's momentum balance, by the bodies' accelerations (a formulation apart from the
// multipliers): sum of contact forces + gravity - d/dt momentum, and the moments about the CoM
// likewise, each relative to the largest term of its sum. Both vanish to rounding when the
// contact forces are right. For the tests and `wlx verify`.
struct MomentumBalance {
  double force = 0, moment = 0;
};
MomentumBalance momentum_balance(const Model& model, Data& data, const Coordinates& s, const Coordinates& sdot,
                                 const Coordinates& sddot, const ContactForces& forces);

// The smallest contact margin of a step: over the supporting contacts, the smaller of the normal
// force and the friction margin (mu f_n - |f_t|), divided by the machine's weight; negative when a
// contact would lift or slip. What the contact-keeping distribution maximises.
double smallest_contact_margin(const Model& model, const ContactForces& forces);

// The torque distribution that keeps the machine on its contacts (Weighting::contacts(), "weighting
// 3"): among the torques that produce Q*, those that maximise smallest_contact_margin() within the
// actuators' limits (gen::kTorqueLimits), ties broken by the least change from the model file's weights'
// torques (a penalty of `regularization` times that change squared, in units of the largest of
// those torques). The friction cones enter as tangent planes added where the solution leaves them
// (a cutting-plane loop of small quadratic programmes, numerics.hpp) until every cone holds to
// `tolerance` (relative to the weight). Throws wlx::Error when no torques within the limits
// produce Q*. Allocates (dynamic-size matrices of a few hundred entries).
struct ContactDistribution {
  TorqueVector tau = TorqueVector::Zero();
  double margin = 0;  // smallest_contact_margin() of tau
  int iterations = 0;  // interior-point iterations, all programmes
  int programmes = 0;  // quadratic programmes solved (1 + the rounds of cuts)
};
struct ContactDistributionOptions {
  double regularization = 1e-7;
  double tolerance = 1e-10;
  int max_rounds = 40;
};
ContactDistribution distribute_torques_on_contacts(const Model& model, Data& data, const Coordinates& s,
                                                   const DynamicsTerms& terms, const ContactDistributionOptions& options = {});

// A contact's name in output columns (gen::kContacts[c].name: f_n_Fl, ...).
std::string contact_name(int contact);

WLX_MODEL_NAMESPACE_END
