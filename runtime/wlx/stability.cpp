// Will it tip: the support polygon of the loaded contacts, the static, ZMP and force-angle margins
// (their geometry compiled once: support_polygon.hpp), and the smallest contact margin (contacts.hpp).
#include "wlx/contacts.hpp"

#include "wlx/support_polygon.hpp"

#include <algorithm>
#include <limits>

WLX_MODEL_NAMESPACE_BEGIN

using contacts_detail::at;

void stability(const Model& model, Data& d, const Coordinates& s, const ContactForces& forces, Stability& out) {
  const Params& p = model.params();
  gen::bodies(s, Coordinates::Zero(), p, {.com = &d.body_com}, false);
  out.com = centre_of_mass(model, d);

  // The polygon and the margins: geometry on the contacts alone, compiled once (support_polygon.hpp),
  // on workspace of this model's sizes.
  static constexpr std::array<bool, kContactSlots> kSupports = [] {
    std::array<bool, kContactSlots> supports{};
    for (int c = 0; c < kContactCount; ++c) supports[at(c)] = gen::kContacts[at(c)].supports;
    return supports;
  }();
  std::array<int, kContactSlots> loaded{};
  std::array<int, 2 * kContactSlots + 1> hull{};
  std::array<Eigen::Vector2d, kContactSlots> corners{};
  static_cast<support::Margins&>(out) = support::margins(kContactCount, forces.point.data(), forces.force.data(), forces.moment.data(),
                                                         forces.normal.data(), kSupports.data(), out.com, out.polygon, loaded, hull,
                                                         corners);
}

double smallest_contact_margin(const Model& model, const ContactForces& forces) {
  const double weight = model.total_mass() * (gen::kHasDynamics ? model.params().*gen::kGravity : 1.0);
  double margin = std::numeric_limits<double>::infinity();
  for (int c = 0; c < kContactCount; ++c)
    if (gen::kContacts[at(c)].supports) margin = std::min({margin, forces.normal(c), forces.friction_margin(c)});
  return margin / weight;
}

WLX_MODEL_NAMESPACE_END
