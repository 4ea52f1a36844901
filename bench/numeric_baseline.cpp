#include "numeric_baseline.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>

namespace wlx::baseline {

namespace c = gen::coord;
namespace f = gen::frame;
namespace b = gen::body;

namespace {

Eigen::Matrix3d Rx(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }
Eigen::Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }
Eigen::Matrix3d Rz(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

constexpr double kStep = 1e-6;  // central differences: error ~h^2 + eps/h, both ~1e-10 here

}  // namespace

void frames(const Params& p, const Coordinates& s, Frames& o) {
  const Eigen::Matrix3d R_C = Rz(s(c::yaw)) * Ry(s(c::pitch)) * Rx(s(c::roll));
  const Eigen::Vector3d r_C(s(c::x_C), s(c::y_C), s(c::z_C));
  o.R[f::C] = R_C;
  o.r[f::C] = r_C;
  o.body_R[b::M1] = R_C;
  o.body_r[b::M1] = r_C;
  for (int side = 0; side < 2; ++side) {
    const double sg = side == 0 ? 1 : -1;
    const int psi1 = side == 0 ? c::psi_l1 : c::psi_r1;
    const Eigen::Matrix3d R_hip = R_C * Rx(s(psi1)) * Ry(s(side == 0 ? c::psi_l2 : c::psi_r2)) *
                                  Rz(s(side == 0 ? c::psi_l3 : c::psi_r3));
    const Eigen::Matrix3d R_knee = R_hip * Ry(s(side == 0 ? c::psi_l4 : c::psi_r4));
    const Eigen::Vector3d hip = r_C + R_C * Eigen::Vector3d(p.cxd / 2, sg * p.cyd / 2, 0);
    const Eigen::Vector3d knee = hip + R_hip * Eigen::Vector3d(p.thighD, 0, 0);
    const Eigen::Vector3d foot = knee + R_knee * Eigen::Vector3d(p.legD, 0, 0);
    const int fh = side == 0 ? f::hip_l : f::hip_r, fk = side == 0 ? f::knee_l : f::knee_r, ff = side == 0 ? f::F_l : f::F_r;
    o.R[fh] = R_hip;
    o.r[fh] = hip;
    o.R[fk] = R_knee;
    o.r[fk] = knee;
    o.R[ff] = R_knee;
    o.r[ff] = foot;
    const int thigh = side == 0 ? b::M3 : b::M2, shank = side == 0 ? b::M5 : b::M4;
    o.body_R[thigh] = R_hip;
    o.body_r[thigh] = hip + R_hip * Eigen::Vector3d(p.thighD / 2, 0, 0);
    o.body_R[shank] = R_knee;
    o.body_r[shank] = knee + R_knee * Eigen::Vector3d(p.legD / 2, 0, 0);

    const int t2 = side == 0 ? c::theta_l2 : c::theta_r2, t3 = side == 0 ? c::theta_l3 : c::theta_r3,
              t4 = side == 0 ? c::theta_l4 : c::theta_r4, t5 = side == 0 ? c::theta_l5 : c::theta_r5,
              t6 = side == 0 ? c::theta_l6 : c::theta_r6;
    const Eigen::Matrix3d R_lev = R_C * Ry(s(t6)) * Rz(s(t5));
    const Eigen::Matrix3d R_10 = R_lev * Rz(s(t4)) * Ry(s(t3));
    const Eigen::Vector3d lever_hip = r_C + R_C * Eigen::Vector3d(-p.cxd / 2, sg * p.cyd / 2, 0);
    const Eigen::Vector3d end = lever_hip + R_lev * Eigen::Vector3d(-p.wl, 0, 0);
    const int fl = side == 0 ? f::lever_hip_l : f::lever_hip_r, fe = side == 0 ? f::lever_end_l : f::lever_end_r,
              fw = side == 0 ? f::W_l : f::W_r;
    o.R[fl] = R_lev;
    o.r[fl] = lever_hip;
    o.R[fe] = R_10;
    o.r[fe] = end;
    o.R[fw] = R_10 * Rx(s(t2));
    o.r[fw] = end + R_10 * Eigen::Vector3d(0, 0, -p.w);
    const int lever = side == 0 ? b::M6 : b::M7;
    o.body_R[lever] = R_lev;
    o.body_r[lever] = lever_hip + R_lev * Eigen::Vector3d(-p.wl / 2, 0, 0);
  }
}

gen::ClosureVector closure(const Params& p, const Coordinates& s, Frames& w) {
  frames(p, s, w);
  gen::ClosureVector phi;
  phi.segment<3>(0) = w.r[f::F_l] - Eigen::Vector3d(s(c::x_Fl), s(c::y_Fl), s(c::z_Fl));
  phi.segment<3>(3) = w.r[f::F_r] - Eigen::Vector3d(s(c::x_Fr), s(c::y_Fr), s(c::z_Fr));
  for (int side = 0; side < 2; ++side) {
    const int fw = side == 0 ? f::W_l : f::W_r;
    phi(6 + 4 * side) = w.r[fw].z() - s(side == 0 ? c::z_Wl : c::z_Wr);
    phi(7 + 4 * side) = w.R[fw](2, 0);
    phi(8 + 4 * side) = w.R[fw](2, 1);
    phi(9 + 4 * side) = side == 0 ? s(c::theta_l4) + s(c::theta_l5) : s(c::theta_r4) + s(c::theta_r5);
  }
  return phi;
}

void closure_jacobian(const Params& p, const Coordinates& s, gen::ClosureJacobian& J, Frames& w) {
  Coordinates x = s;
  for (int j = 0; j < kCoordinateCount; ++j) {
    x(j) = s(j) + kStep;
    const gen::ClosureVector plus = closure(p, x, w);
    x(j) = s(j) - kStep;
    J.col(j) = (plus - closure(p, x, w)) / (2 * kStep);
    x(j) = s(j);
  }
}

void nonholonomic_rows(const Params& p, const Coordinates& s, gen::WheelRows& C, Frames& w) {
  frames(p, s, w);
  const Eigen::Vector3d n_l = w.R[f::W_l].col(1), n_r = w.R[f::W_r].col(1);
  Coordinates x = s;
  for (int j = 0; j < kCoordinateCount; ++j) {
    x(j) = s(j) + kStep;
    frames(p, x, w);
    const Eigen::Vector3d l = w.r[f::W_l], r = w.r[f::W_r];
    x(j) = s(j) - kStep;
    frames(p, x, w);
    C(0, j) = n_l.dot(l - w.r[f::W_l]) / (2 * kStep);
    C(1, j) = n_r.dot(r - w.r[f::W_r]) / (2 * kStep);
    x(j) = s(j);
  }
}

void convective(const Params& p, const Coordinates& s, const Coordinates& sdot, gen::ClosureVector& phi_conv,
                gen::WheelVector& C_conv, Frames& w) {
  const double h = 1e-4;  // second differences: error ~h^2 + eps/h^2, both ~1e-8
  phi_conv = (closure(p, s + h * sdot, w) - 2 * closure(p, s, w) + closure(p, s - h * sdot, w)) / (h * h);
  gen::WheelRows Cp, Cm;
  nonholonomic_rows(p, s + h * sdot, Cp, w);
  nonholonomic_rows(p, s - h * sdot, Cm, w);
  C_conv = (Cp - Cm) * sdot / (2 * h);
}

void body_jacobians(const Params& p, const Coordinates& s, gen::BodyJacobians& Jv, gen::BodyJacobians& Jw, Frames& w) {
  Frames plus;
  Coordinates x = s;
  for (int j = 0; j < kCoordinateCount; ++j) {
    x(j) = s(j) + kStep;
    frames(p, x, plus);
    x(j) = s(j) - kStep;
    frames(p, x, w);
    x(j) = s(j);
    for (int k = 0; k < gen::kBodyCount; ++k) {
      Jv[static_cast<std::size_t>(k)].col(j) = (plus.body_r[static_cast<std::size_t>(k)] - w.body_r[static_cast<std::size_t>(k)]) / (2 * kStep);
      // omega^ = Rdot R^T, with R at s taken as the mean of the two evaluations.
      const Eigen::Matrix3d Rd = (plus.body_R[static_cast<std::size_t>(k)] - w.body_R[static_cast<std::size_t>(k)]) / (2 * kStep);
      const Eigen::Matrix3d W = Rd * (0.5 * (plus.body_R[static_cast<std::size_t>(k)] + w.body_R[static_cast<std::size_t>(k)])).transpose();
      Jw[static_cast<std::size_t>(k)].col(j) = Eigen::Vector3d(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1)) / 2;
    }
  }
}

int newton_ik(const Params& p, Coordinates& s, Frames& w, double tolerance, int max_iterations) {
  gen::ClosureJacobian J;
  for (int it = 0; it < max_iterations; ++it) {
    const gen::ClosureVector phi = closure(p, s, w);
    if (phi.cwiseAbs().maxCoeff() <= tolerance) return it;
    closure_jacobian(p, s, J, w);
    const Eigen::Matrix<double, 14, 14> A = J.rightCols<kDependentCount>();
    s.tail<kDependentCount>() -= A.partialPivLu().solve(phi);
  }
  return max_iterations;
}

}  // namespace wlx::baseline
