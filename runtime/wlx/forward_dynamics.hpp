// Forward dynamics: the machine moved by its actuators (the converse of wlx/dynamics.hpp's inverse
// dynamics, on the same commanded speeds u, actuated joints and dependent pair).
#pragma once

#include "wlx/dynamics.hpp"

WLX_MODEL_NAMESPACE_BEGIN

// Forward dynamics: the accelerations u' of the commanded speeds under the actuator torques tau
// (in kActuatedJoints' order), from M u' = J_beta^T tau - b + Q_gravity, the other inputs held
// (as in inverse_dynamics), the closure and the rolling rows kept (s'' = T u' + s''_bias in
// out.sddot). One inverse-dynamics evaluation and a Cholesky factorisation of M; out.Qstar is
// J_beta^T tau. Throws wlx::Error if M is not positive definite (a model whose bodies do not move
// with some commanded speed) or for a model without a dynamics section.
void forward_dynamics(const Model& model, Data& data, const Coordinates& s, const CommandVector& u, const TorqueVector& tau,
                      CommandVector& u_dot, DynamicsTerms& out, const NonholonomicOptions& options = {});

WLX_MODEL_NAMESPACE_END
