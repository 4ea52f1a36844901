// Property test of the closed-form IK (generator/ik_patterns.cpp, ik_steering_leg.cpp): for random
// geometries of every limb shape in ik_shapes.yaml (each offset and fixed turn a parameter, drawn
// here at run time), a target made from random joint angles through the generated closure, every
// branch that returns a solution solves the limb's closure rows to 1e-12 m, and the solution
// Newton's method finds from near those angles is one of the branches (to 1e-9 rad). Newton uses
// the generated dPhi/ds, the closed form nothing of it: the two share only the model's chains.
// A limb has three point rows, and a steering leg a sum row besides (four rows, four joints).
#include <wlx/gen/all.hpp>  // its time stamp moves with any header's (wlx-gen): the build recompiles this
#include <wlx/gen/closure.hpp>
#include <wlx/gen/ik.hpp>
#include <wlx/gen/structure.hpp>

#include <Eigen/Dense>
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

namespace gen = wlx::ik_shapes::gen;

namespace {

double wrap(double a) { return std::remainder(a, 2 * std::numbers::pi); }

double limb_residual(const gen::Coordinates& s, const gen::Params& p, const gen::LimbInfo& limb) {
  gen::ClosureVector Phi;
  gen::closure(s, p, {.Phi = &Phi});
  double r = 0;
  for (int i = 0; i < limb.size; ++i) r = std::max(r, std::abs(Phi(limb.rows[static_cast<std::size_t>(i)])));
  return r;
}

Eigen::MatrixXd limb_jacobian(const gen::Coordinates& s, const gen::Params& p, const gen::LimbInfo& limb) {
  gen::ClosureJacobian J;
  gen::closure(s, p, {.dPhi_ds = &J});
  Eigen::MatrixXd B(limb.size, limb.size);
  for (int i = 0; i < limb.size; ++i)
    for (int j = 0; j < limb.size; ++j) B(i, j) = J(limb.rows[static_cast<std::size_t>(i)], limb.joints[static_cast<std::size_t>(j)]);
  return B;
}

// Newton's method on the limb's rows in its joints, from the joints in s; false if it does not
// reach |Phi| <= 1e-13 in 30 steps.
bool newton(gen::Coordinates& s, const gen::Params& p, const gen::LimbInfo& limb) {
  for (int it = 0; it < 30; ++it) {
    gen::ClosureVector Phi;
    gen::closure(s, p, {.Phi = &Phi});
    Eigen::VectorXd r(limb.size);
    for (int i = 0; i < limb.size; ++i) r(i) = Phi(limb.rows[static_cast<std::size_t>(i)]);
    if (r.cwiseAbs().maxCoeff() <= 1e-13) return true;
    const Eigen::VectorXd step = limb_jacobian(s, p, limb).fullPivLu().solve(-r);
    for (int j = 0; j < limb.size; ++j) s(limb.joints[static_cast<std::size_t>(j)]) += step(j);
  }
  return false;
}

}  // namespace

TEST_CASE("closed-form IK on random geometries of every limb shape: every branch solves the closure, one is Newton's") {
  std::mt19937_64 rng(24);
  std::uniform_real_distribution<double> unit(-1, 1);
  constexpr int kGeometries = 300;
  for (std::size_t l = 0; l < gen::kLimbs.size(); ++l) {
    const gen::LimbInfo& limb = gen::kLimbs[l];
    const gen::ClosedFormInfo& cf = gen::kClosedForm[l];
    CAPTURE(limb.name);
    REQUIRE(static_cast<bool>(cf.solve));  // every shape in the file has a closed form
    double worst_residual = 0, worst_difference = 0;
    int solved = 0, ill_conditioned = 0, branches_ok = 0, newton_failed = 0;
    for (int g = 0; g < kGeometries; ++g) {
      gen::Params p;
      for (const gen::ParamInfo& info : gen::kParamInfo) {
        if (info.kind == gen::ParamKind::offset) p.*info.member = 0.4 * unit(rng);
        if (info.kind == gen::ParamKind::length) p.*info.member = 0.05 + 0.3 * std::abs(unit(rng));  // a wheel's radius
        if (info.kind == gen::ParamKind::angle) p.*info.member = std::numbers::pi * unit(rng);
      }
      gen::Coordinates s = gen::Coordinates::Zero();
      for (int k = 6; k < gen::kInputCount; ++k) s(k) = unit(rng);  // the other inputs (the targets are set below)
      for (int k = 0; k < 3; ++k) s(k) = unit(rng);  // base position
      s(3) = std::numbers::pi * unit(rng);          // yaw
      s(4) = 0.6 * unit(rng);                       // pitch and roll tilt a wheel's axle
      s(5) = 0.6 * unit(rng);
      gen::Coordinates truth = s;
      for (int j = 0; j < limb.size; ++j) truth(limb.joints[static_cast<std::size_t>(j)]) = std::numbers::pi * unit(rng);
      // A point row's target is the input whose dPhi/ds entry is -1 (the base's own inputs move the
      // point, +1); a row without one is a sum row, which the limb's last joint in it then meets.
      gen::ClosureVector Phi;
      gen::ClosureJacobian J;
      gen::closure(truth, p, {.Phi = &Phi, .dPhi_ds = &J});
      std::vector<std::pair<int, int>> targets;  // row, input
      for (int i = 0; i < limb.size; ++i) {
        const int row = limb.rows[static_cast<std::size_t>(i)];
        int target = -1;
        for (int k = 6; k < gen::kInputCount; ++k)
          if (J(row, k) == -1.0) target = k;
        if (target >= 0) {
          targets.emplace_back(row, target);
          continue;
        }
        int last = -1;
        for (int j = 0; j < limb.size; ++j)
          if (J(row, limb.joints[static_cast<std::size_t>(j)]) == 1.0) last = limb.joints[static_cast<std::size_t>(j)];
        REQUIRE(last >= 0);
        truth(last) -= Phi(row);  // the sum of its coordinates, now zero
      }
      // The targets: set to zero, each point row is the point's component.
      for (const auto& [row, target] : targets) truth(target) = 0;
      gen::closure(truth, p, {.Phi = &Phi});
      for (const auto& [row, target] : targets) truth(target) = Phi(row);
      for (int k = 0; k < gen::kInputCount; ++k) s(k) = truth(k);
      REQUIRE(limb_residual(truth, p, limb) <= 1e-13);

      // Newton's method from near the drawn angles.
      gen::Coordinates n = truth;
      for (int j = 0; j < limb.size; ++j) n(limb.joints[static_cast<std::size_t>(j)]) += 0.05 * unit(rng);
      if (!newton(n, p, limb)) {
        ++newton_failed;
        continue;
      }
      const Eigen::VectorXd sv = limb_jacobian(n, p, limb).jacobiSvd().singularValues();
      const bool well_conditioned = sv(limb.size - 1) >= 1e-3;
      double nearest = std::numeric_limits<double>::infinity();
      for (int b = 0; b < cf.branches; ++b) {
        gen::Coordinates out = s;
        gen::IkDiagnostics why;
        const gen::IkStatus status = cf.solve(s, p, b, out, why);
        CAPTURE(b);
        CHECK(status != gen::IkStatus::residual);  // the closed form never misses its own rows
        if (status != gen::IkStatus::ok) continue;
        ++branches_ok;
        const double residual = limb_residual(out, p, limb);
        worst_residual = std::max(worst_residual, residual);
        CHECK(residual <= 1e-12);
        double difference = 0;
        for (int j = 0; j < limb.size; ++j) {
          const int k = limb.joints[static_cast<std::size_t>(j)];
          difference = std::max(difference, std::abs(wrap(out(k) - n(k))));
        }
        nearest = std::min(nearest, difference);
      }
      if (!well_conditioned) {
        ++ill_conditioned;
        continue;
      }
      ++solved;
      worst_difference = std::max(worst_difference, nearest);
      CHECK(nearest <= 1e-9);  // Newton's solution is one of the branches
    }
    MESSAGE(limb.name << " (" << cf.pattern << "): " << solved << " geometries compared with Newton (" << ill_conditioned
                      << " near-singular skipped, " << newton_failed << " Newton failures), " << branches_ok
                      << " branch solutions, worst residual " << worst_residual << " m, worst |closed form - Newton| "
                      << worst_difference << " rad");
    CHECK(solved >= kGeometries * 8 / 10);  // the skips stay exceptions
  }
}
