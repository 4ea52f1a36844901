// The numeric way, for comparison (issue: performance): what a numeric multibody library does
// without generated code. Frames by composing elementary transforms at run time, Jacobians by
// central finite differences, convective terms by differentiating J s' numerically along s',
// Newton IK with finite-difference Jacobians. Used by the benchmarks and checked by a test.
#pragma once

#include <wlx/model.hpp>

#include <array>

namespace wlx::baseline {

struct Frames {
  std::array<Eigen::Matrix3d, gen::kFrameCount> R;
  std::array<Eigen::Vector3d, gen::kFrameCount> r;
  std::array<Eigen::Matrix3d, gen::kBodyCount> body_R;
  std::array<Eigen::Vector3d, gen::kBodyCount> body_r;
};

void frames(const Params& p, const Coordinates& s, Frames& out);
gen::ClosureVector closure(const Params& p, const Coordinates& s, Frames& work);
// Central differences, step h per coordinate.
void closure_jacobian(const Params& p, const Coordinates& s, gen::ClosureJacobian& J, Frames& work);
void nonholonomic_rows(const Params& p, const Coordinates& s, gen::WheelRows& C, Frames& work);
// (d/dt dPhi/ds) s' = second directional derivative of Phi along s', and (d/dt C) s'.
void convective(const Params& p, const Coordinates& s, const Coordinates& sdot, gen::ClosureVector& phi_conv,
                gen::WheelVector& C_conv, Frames& work);
// CoM velocity and angular velocity Jacobians of every body.
void body_jacobians(const Params& p, const Coordinates& s, gen::BodyJacobians& Jv, gen::BodyJacobians& Jw, Frames& work);
// Newton on all 14 closure equations with the finite-difference Jacobian; returns iterations.
int newton_ik(const Params& p, Coordinates& s, Frames& work, double tolerance = 1e-12, int max_iterations = 50);

}  // namespace wlx::baseline
