#include "wlx/forward_dynamics.hpp"

#include "wlx/error.hpp"

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include <cmath>

WLX_MODEL_NAMESPACE_BEGIN

void forward_dynamics(const Model& model, Data& d, const Coordinates& s, const CommandVector& u, const TorqueVector& tau,
                      CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options) {
#if !__has_include(<wlx/gen/reduced_dynamics.hpp>)
  static_cast<void>(model), static_cast<void>(d), static_cast<void>(s), static_cast<void>(u), static_cast<void>(tau);
  static_cast<void>(u_dot), static_cast<void>(out), static_cast<void>(options);
  throw_no_dynamics_section();
#else
  for (int r = 0; r < kActuatedCount; ++r)
    if (!std::isfinite(tau(r)))
      throw Error(fmt::format("tau.{}", gen::kCoordinateNames[static_cast<std::size_t>(kActuatedJoints[static_cast<std::size_t>(r)])]),
                  fmt::format("must be a finite number, got {}", tau(r)));
  inverse_dynamics(model, d, s, u, CommandVector::Zero(), out, options);  // M, b, Q_gravity, J_beta; s'' at u' = 0
  out.Qstar.noalias() = out.J_beta.transpose() * tau;
  const Eigen::LLT<CommandMatrix> llt(out.M);
  if (llt.info() != Eigen::Success)
    throw Error("M", "the mass matrix on the commanded speeds is not positive definite: some commanded speed moves no body");
  u_dot = llt.solve(out.Qstar - out.b + out.Q_gravity);
  out.sddot.noalias() += out.T * u_dot;
#endif
}

WLX_MODEL_NAMESPACE_END
