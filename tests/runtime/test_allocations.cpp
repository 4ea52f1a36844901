// The hot paths allocate nothing once a Model and a Data exist: a counting global operator new
// (this file is its own test program, so the count sees every allocation).
#include <doctest/doctest.h>
#include <wlx/contacts.hpp>
#include <wlx/dynamics.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, std::align_val_t a) {
  ++g_allocations;
  const std::size_t al = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

using namespace wlx;

TEST_CASE("allocations: the counter counts") {
  // A direct call: new-expressions may be elided by the compiler, operator new calls may not.
  const long before = g_allocations;
  void* p = ::operator new(16);
  ::operator delete(p);
  std::vector<double> v(10);
  CHECK(g_allocations - before == 2);
}

TEST_CASE("allocations: kinematic update, dependent rates and accelerations, inverse-dynamics step: none") {
  const Model model;
  auto data = std::make_unique<Data>();
  DynamicsTerms terms;
  Coordinates s = nominal_inputs();
  s(gen::coord::x_C) = 0.2;
  Coordinates sdot = Coordinates::Zero(), sddot = Coordinates::Zero();
  const long before = g_allocations;
  for (int k = 0; k < 100; ++k) {
    s(gen::coord::roll) = 0.001 * k;
    solve_ik_closed_form(model, s);
    kinematic_update(model, *data, s);
    sdot.setZero();
    sdot(gen::coord::roll) = 0.1;
    solve_dependent_rates(model, *data, s, sdot, named_pair("A"));
    solve_dependent_accelerations(model, *data, s, sdot, sddot, named_pair("A"));
    inverse_dynamics(model, *data, s, CommandVector(0, 3, 0.1, 0), CommandVector::Zero(), terms);
    const TorqueVector tau1 = distribute_torques(terms.J_beta, terms.Qstar, Weighting::model_weights());
    const TorqueVector tau2 = distribute_torques(terms.J_beta, terms.Qstar, Weighting::contribution());
    CHECK(tau1.allFinite());
    CHECK(tau2.allFinite());
  }
  CHECK(g_allocations - before == 0);
}

// contacts.hpp says both allocate nothing; the polygon's geometry is compiled once, on workspace
// the model's stability() lends it (support_polygon.hpp).
TEST_CASE("allocations: contact forces and stability (the support polygon and its margins): none") {
  const Model model;
  auto data = std::make_unique<Data>();
  DynamicsTerms terms;
  ContactForces forces;
  Stability st;
  Coordinates s = nominal_inputs();
  const long before = g_allocations;
  for (int k = 0; k < 100; ++k) {
    s(gen::coord::x_C) = 0.002 * k;
    solve_ik_closed_form(model, s);
    inverse_dynamics(model, *data, s, CommandVector(0, 3, 0.1, 0), CommandVector::Zero(), terms);
    const TorqueVector tau = distribute_torques(terms.J_beta, terms.Qstar, Weighting::model_weights());
    contact_forces(model, *data, s, terms, tau, forces);
    stability(model, *data, s, forces, st);
    CHECK(st.polygon_size >= 2);  // the excavator stands on its feet and wheels
    CHECK(std::isfinite(st.tip_angle));
  }
  CHECK(g_allocations - before == 0);
}

TEST_CASE("allocations: Newton IK from a warm start: none") {
  const Model model;
  auto data = std::make_unique<Data>();
  Coordinates s = nominal_inputs();
  solve_ik_closed_form(model, s);
  const long before = g_allocations;
  for (int k = 0; k < 50; ++k) {
    s(gen::coord::x_Fl) = 3.5 + 0.001 * k;
    solve_ik_newton(model, *data, s);
  }
  CHECK(g_allocations - before == 0);
}
