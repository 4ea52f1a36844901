#include "wlx/ik.hpp"

#include "wlx/error.hpp"

#include "wlx/kinematics.hpp"

#include <wlx/gen/trig.hpp>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace wlx {

namespace c = gen::coord;

namespace {

constexpr double kPi = std::numbers::pi;
// Targets this close outside the reach (relative to the reach) are rounding, not user error:
// they are clamped onto the boundary (straight leg, lever at +-90 deg).
constexpr double kReachSlack = 1e-12;

double wrap(double a) {
  if (a > -kPi && a <= kPi) return a;  // the usual case, without the slow remainder
  a = std::remainder(a, 2 * kPi);
  return a == -kPi ? kPi : a;
}

Eigen::Matrix3d cabin_rotation(double sy, double cy, double sp, double cp, double sr, double cr) {
  Eigen::Matrix3d R;
  R << cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,  //
      sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,   //
      -sp, cp * sr, cp * cr;
  return R;
}

Eigen::Matrix3d cabin_rotation(const Coordinates& s) {
  return cabin_rotation(std::sin(s(c::yaw)), std::cos(s(c::yaw)), std::sin(s(c::pitch)), std::cos(s(c::pitch)),
                        std::sin(s(c::roll)), std::cos(s(c::roll)));
}

// What the limbs' closed forms need from the cabin pose and the angle inputs, computed once per
// solve: sin and cos of all seven input angles in one pass of the generated batched sincos, and
// the lever quantities that depend on the cabin only (both wheels share them).
struct CabinPose {
  Eigen::Matrix3d R;  // R_C
  Eigen::Vector3d r;  // r_C
  Eigen::Vector3d g;  // world up seen from the cabin, R_C^T e_z
  double rho = 0;     // |g| in the levers' pitch plane (x-z)
  double phi = 0;     // direction of g in that plane
  double theta2 = 0;  // the camber levelling the lever's y axis, hub above the contact (no branch bits)
  std::array<double, 2> sin_psi1{}, cos_psi1{}, sin_theta5{}, cos_theta5{};  // [left, right]
};

CabinPose cabin_pose(const Coordinates& s) {
  const std::array<double, 7> angle{s(c::yaw), s(c::pitch), s(c::roll), s(c::psi_l1), s(c::psi_r1), s(c::theta_l5),
                                    s(c::theta_r5)};
  std::array<double, 7> sin_a, cos_a;
  gen::sincos(angle, sin_a, cos_a);
  CabinPose pose;
  pose.R = cabin_rotation(sin_a[0], cos_a[0], sin_a[1], cos_a[1], sin_a[2], cos_a[2]);
  pose.r = Eigen::Vector3d(s(c::x_C), s(c::y_C), s(c::z_C));
  pose.g = pose.R.row(2).transpose();
  pose.rho = std::sqrt(pose.g.x() * pose.g.x() + pose.g.z() * pose.g.z());  // g is a unit vector: no overflow
  pose.phi = std::atan2(pose.g.x(), pose.g.z());
  pose.theta2 = std::atan2(-pose.g.y(), pose.rho);
  pose.sin_psi1 = {sin_a[3], sin_a[4]};
  pose.cos_psi1 = {cos_a[3], cos_a[4]};
  pose.sin_theta5 = {sin_a[5], sin_a[6]};
  pose.cos_theta5 = {cos_a[5], cos_a[6]};
  return pose;
}

// Short names for the limb blocks inside this file.
struct LimbIndices {
  std::array<int, 4> dep;
  int rows;
  int count;
};

LimbIndices indices(Limb limb) {
  const LimbBlock b = limb_block(limb);
  return {b.joints, b.first_row, b.size};
}

void require_finite(const Coordinates& s, std::initializer_list<int> coords) {
  for (int k : coords)
    if (!std::isfinite(s(k)))
      throw Error(std::string(gen::kCoordinateNames[static_cast<std::size_t>(k)]),
                  fmt::format("must be a finite number, got {}", s(k)));
}

void require_cabin_finite(const Coordinates& s) { require_finite(s, {c::x_C, c::y_C, c::z_C, c::yaw, c::pitch, c::roll}); }

// Clamps x into [-1, 1] when it is outside by rounding only.
bool clamp_unit(double& x) {
  if (std::abs(x) <= 1) return true;
  if (std::abs(x) <= 1 + kReachSlack) {
    x = std::copysign(1.0, x);
    return true;
  }
  return false;
}

void solve_leg(const Model& model, const CabinPose& cabin, Limb limb, int branch, Coordinates& s) {
  const Params& p = model.params();
  const bool left = limb == Limb::leg_l;
  const int x_F = left ? c::x_Fl : c::x_Fr, y_F = left ? c::y_Fl : c::y_Fr, z_F = left ? c::z_Fl : c::z_Fr;
  const int psi1 = left ? c::psi_l1 : c::psi_r1;
  require_finite(s, {x_F, y_F, z_F, psi1});
  const double side = left ? 1.0 : -1.0;
  const Eigen::Vector3d hip(p.cxd / 2, side * p.cyd / 2, 0);
  // Foot relative to the hip, in the frame after the hip roll joint Rx(psi_1).
  const Eigen::Vector3d in_cabin = cabin.R.transpose() * (Eigen::Vector3d(s(x_F), s(y_F), s(z_F)) - cabin.r) - hip;
  const double c1 = cabin.cos_psi1[left ? 0 : 1], s1 = cabin.sin_psi1[left ? 0 : 1];
  const Eigen::Vector3d d(in_cabin.x(), c1 * in_cabin.y() + s1 * in_cabin.z(), -s1 * in_cabin.y() + c1 * in_cabin.z());
  const double T = p.thighD, L = p.legD, dist = d.norm();
  const double near = std::abs(T - L), far = T + L;
  double c4 = (dist * dist - T * T - L * L) / (2 * T * L);
  if (!clamp_unit(c4))
    throw Error(std::string(limb_name(limb)),
                fmt::format("foot is {:.4f} m from the hip, reach is [{:.4f}, {:.4f}] m (|thighD - legD| to thighD + legD)",
                            dist, near, far));
  const double sign4 = branch & 1 ? -1.0 : 1.0;
  double psi4 = sign4 * std::acos(c4);
  double a = T + L * c4, b = -L * sign4 * std::sqrt(1 - c4 * c4);
  // d_y = a sin(psi_3); (d_x, d_z) is (k, b) = (a cos(psi_3), b) turned by -psi_2 about y. With
  // psi_1 an input, the distance fixes the knee, and the knee limits how far beside the hip's
  // pitch plane the foot can be: the in-plane distance must be at least |b| (equivalently
  // |d_y| <= |a|). The annulus of distances alone is not the reach.
  const double in_plane2 = d.x() * d.x() + d.z() * d.z();
  if (b * b > in_plane2) {
    if (b * b - in_plane2 > kReachSlack * far * far)
      throw Error(std::string(limb_name(limb)),
                  fmt::format("foot out of reach: at {:.4f} m from the hip the knee must bend to {} = {:.2f} deg, and "
                              "the foot can then be at most {:.4f} m beside the hip's pitch plane (the plane after the "
                              "hip roll {}), but it is {:.4f} m beside it",
                              dist, gen::kCoordinateNames[static_cast<std::size_t>(indices(limb).dep[2])],
                              std::abs(psi4) * 180 / kPi, std::abs(a), gen::kCoordinateNames[static_cast<std::size_t>(psi1)],
                              std::abs(d.y())));
    // On that boundary (e.g. a straight leg pointing sideways) rounding of |d| can break the
    // condition by an ulp: take the knee from both legs of its triangle, L cos(psi_4) from the
    // distance and L |sin(psi_4)| from the in-plane offset (atan2 stays accurate at every angle).
    psi4 = sign4 * std::atan2(std::sqrt(in_plane2), L * c4);
    a = T + L * std::cos(psi4);
    b = -L * std::sin(psi4);
  }
  // psi_3 from atan2 of both legs of its triangle (asin near 1 would lose half the digits).
  const double a_sign = a < 0 ? -1.0 : 1.0;
  double k = a_sign * std::sqrt(std::max(0.0, in_plane2 - b * b));  // a cos(psi_3), branch |psi_3| < 90 deg
  double psi3 = std::atan2(a_sign * d.y(), a_sign * k);
  if (branch & 2) {
    psi3 = wrap(kPi - psi3);
    k = -k;
  }
  // psi_2 = atan2(b, k) - atan2(d_z, d_x), as the angle of (k + i b) conj(d_x + i d_z): one atan2.
  const double psi2 = wrap(std::atan2(b * d.x() - k * d.z(), k * d.x() + b * d.z()));  // -pi -> pi
  const auto idx = indices(limb);
  s(idx.dep[0]) = psi2;
  s(idx.dep[1]) = psi3;
  s(idx.dep[2]) = psi4;
}

void solve_wheel(const Model& model, const CabinPose& cabin, Limb limb, int branch, Coordinates& s) {
  const Params& p = model.params();
  const bool left = limb == Limb::wheel_l;
  const int z_W = left ? c::z_Wl : c::z_Wr, th5 = left ? c::theta_l5 : c::theta_r5;
  require_finite(s, {z_W, th5});
  const double side = left ? 1.0 : -1.0;
  const Eigen::Vector3d& g = cabin.g;
  const double rho = cabin.rho, phi = cabin.phi;
  // Parallel guidance: theta_4 = -theta_5, so R_10 = Ry(theta_3 + theta_6) =: Ry(sigma).
  // Level x axis: g . Ry(sigma) e_x = 0  ->  sigma = phi (hub above the contact) or phi + pi.
  const double sigma = (branch & 4) ? wrap(phi + kPi) : phi;
  const double m = (branch & 4) ? -rho : rho;  // g_x sin(sigma) + g_z cos(sigma)
  // Level y axis: sin(theta_2) m + g_y cos(theta_2) = 0, i.e. atan2(-g_y sign(m), |m|); atan2 is
  // odd in its first argument, so the upside-down branch negates the cabin's value.
  double theta2 = m < 0 ? -cabin.theta2 : cabin.theta2;
  if (branch & 2) theta2 = wrap(theta2 + kPi);
  // Contact height: z_C + g.h - w m + wl (-s5 g_y... ) : rho sin(theta_6 - phi) * wl c5 = z_W - centre.
  const double s5 = cabin.sin_theta5[left ? 0 : 1], c5 = cabin.cos_theta5[left ? 0 : 1];
  const Eigen::Vector3d h(-p.cxd / 2, side * p.cyd / 2, 0);
  const double centre = s(c::z_C) + g.dot(h) - p.w * m - p.wl * s5 * g.y();
  const double half_width = p.wl * std::abs(c5) * rho;
  double sine = half_width > 0 ? (s(z_W) - centre) / (p.wl * c5 * rho) : 0.0;
  if (!(half_width > 0) || !clamp_unit(sine)) {
    const std::string level(gen::kCoordinateNames[static_cast<std::size_t>(z_W)]);
    throw Error(std::string(limb_name(limb)),
                fmt::format("ground level {} = {:.4f} m is out of the lever's reach: for this cabin pose and {} = "
                            "{:.2f} deg the contact point reaches {} in [{:.4f}, {:.4f}] m",
                            level, s(z_W), gen::kCoordinateNames[static_cast<std::size_t>(th5)],
                            s(th5) * 180 / kPi, level, centre - half_width, centre + half_width));
  }
  double theta6 = phi + std::asin(sine);
  if (branch & 1) theta6 = phi + kPi - std::asin(sine);
  theta6 = wrap(theta6);
  const auto idx = indices(limb);
  s(idx.dep[0]) = theta2;
  s(idx.dep[1]) = wrap(sigma - theta6);
  s(idx.dep[2]) = -s(th5);
  s(idx.dep[3]) = theta6;
}

}  // namespace

LimbBlock limb_block(Limb limb) noexcept {
  const gen::LimbInfo& info = gen::kLimbs[static_cast<std::size_t>(limb)];
  LimbBlock b{info.rows[0], info.size, {-1, -1, -1, -1}};
  for (int j = 0; j < info.size; ++j) b.joints[static_cast<std::size_t>(j)] = info.joints[static_cast<std::size_t>(j)];
  return b;
}

std::string_view limb_name(Limb limb) noexcept { return gen::kLimbs[static_cast<std::size_t>(limb)].title; }

namespace {

void solve_limb(const Model& model, const CabinPose& cabin, Limb limb, int branch, Coordinates& s) {
  if (branch < 0 || branch >= branch_count(limb))
    throw Error("branch", fmt::format("{} has branches 0 to {}, got {}", limb_name(limb), branch_count(limb) - 1, branch));
  if (limb == Limb::leg_l || limb == Limb::leg_r) solve_leg(model, cabin, limb, branch, s);
  else solve_wheel(model, cabin, limb, branch, s);
}

}  // namespace

void solve_limb_closed_form(const Model& model, Limb limb, int branch, Coordinates& s) {
  require_cabin_finite(s);
  solve_limb(model, cabin_pose(s), limb, branch, s);
}

void solve_ik_closed_form(const Model& model, Coordinates& s, const Branches& branches) {
  require_cabin_finite(s);
  const CabinPose cabin = cabin_pose(s);
  for (Limb limb : kLimbs) solve_limb(model, cabin, limb, branches.limb[static_cast<std::size_t>(limb)], s);
}

int classify_branch(const Model& model, Limb limb, const Coordinates& s) {
  static_cast<void>(model);
  const auto idx = indices(limb);
  if (limb == Limb::leg_l || limb == Limb::leg_r)
    return (s(idx.dep[2]) < 0 ? 1 : 0) | (std::cos(s(idx.dep[1])) < 0 ? 2 : 0);
  const Eigen::Vector3d g = cabin_rotation(s).row(2).transpose();
  const double phi = std::atan2(g.x(), g.z());
  const double theta2 = s(idx.dep[0]), theta3 = s(idx.dep[1]), theta6 = s(idx.dep[3]);
  const double sigma = theta3 + theta6;
  const double m = g.x() * std::sin(sigma) + g.z() * std::cos(sigma);
  return (std::cos(theta6 - phi) < 0 ? 1 : 0) | (std::cos(theta2) < 0 ? 2 : 0) | (m < 0 ? 4 : 0);
}

namespace {

NewtonReport newton(const Model& model, std::array<bool, 4> active, Coordinates& s, Data& data,
                    const NewtonOptions& options) {
  for (int k = 0; k < kCoordinateCount; ++k) require_finite(s, {k});
  NewtonReport report;
  std::array<bool, 4> done{!active[0], !active[1], !active[2], !active[3]};
  std::array<bool, 4> stalled{false, false, false, false};  // the last damped step could not descend
  const auto limb_residual = [&](const gen::ClosureVector& Phi, const LimbIndices& idx) {
    return Phi.segment(idx.rows, idx.count).cwiseAbs().maxCoeff();
  };
  for (int iteration = 0;; ++iteration) {
    closure(model, s, data, true);
    if (!data.Phi.allFinite()) throw Error("", "closure residual is not finite: the starting guess is unusable");
    bool all_done = true;
    std::array<Eigen::Vector4d, 4> step;
    std::array<double, 4> before{};
    for (Limb limb : kLimbs) {
      const auto l = static_cast<std::size_t>(limb);
      if (!active[l]) continue;
      const auto idx = indices(limb);
      before[l] = limb_residual(data.Phi, idx);
      done[l] = before[l] <= options.tolerance || (stalled[l] && before[l] <= options.floor_tolerance);
      if (done[l]) continue;
      all_done = false;
      if (report.iterations[l] >= options.max_iterations)
        throw Error(std::string(limb_name(limb)),
                    fmt::format("Newton did not converge in {} iterations (residual {:.3e}, tolerance {:.1e}); the "
                                "target may be unreachable or the start too far: warm-start from a nearby solution or "
                                "use the closed form",
                                options.max_iterations, before[l], options.tolerance));
      // The limb's block of dPhi/ds: its rows against its own dependent joints.
      Eigen::Matrix4d J = Eigen::Matrix4d::Identity();
      Eigen::Vector4d r = Eigen::Vector4d::Zero();
      for (int i = 0; i < idx.count; ++i) {
        r(i) = data.Phi(idx.rows + i);
        for (int j = 0; j < idx.count; ++j) J(i, j) = data.dPhi_ds(idx.rows + i, idx.dep[static_cast<std::size_t>(j)]);
      }
      const Eigen::FullPivLU<Eigen::Matrix4d> lu(J);
      if (lu.rcond() > 1e-12) {
        step[l] = -lu.solve(r);
      } else {  // at a singular pose (straight leg, lever at 90 deg): Levenberg-Marquardt step
        const double mu = 1e-8 * std::max(1.0, J.squaredNorm());
        step[l] = -(J.transpose() * J + mu * Eigen::Matrix4d::Identity()).ldlt().solve(J.transpose() * r);
      }
      ++report.iterations[l];
    }
    if (all_done) break;
    // Damping: halve a limb's step until its residual decreases.
    std::array<double, 4> lambda{1, 1, 1, 1};
    std::array<bool, 4> accepted = done;
    const Coordinates start = s;
    for (int halving = 0; halving < 40; ++halving) {
      for (Limb limb : kLimbs) {
        const auto l = static_cast<std::size_t>(limb);
        if (accepted[l]) continue;
        const auto idx = indices(limb);
        for (int j = 0; j < idx.count; ++j)
          s(idx.dep[static_cast<std::size_t>(j)]) = start(idx.dep[static_cast<std::size_t>(j)]) + lambda[l] * step[l](j);
      }
      if (!options.damped) break;
      closure(model, s, data, false);
      bool all_accepted = true;
      for (Limb limb : kLimbs) {
        const auto l = static_cast<std::size_t>(limb);
        if (accepted[l]) continue;
        const double after = limb_residual(data.Phi, indices(limb));
        if (after < before[l] || !std::isfinite(before[l])) accepted[l] = true;
        else lambda[l] *= 0.5;
        all_accepted = all_accepted && accepted[l];
      }
      if (all_accepted) break;
    }
    for (Limb limb : kLimbs) {
      const auto l = static_cast<std::size_t>(limb);
      stalled[l] = !done[l] && !accepted[l];
    }
  }
  for (Limb limb : kLimbs) {
    if (!active[static_cast<std::size_t>(limb)]) continue;
    const auto idx = indices(limb);
    for (int j = 0; j < idx.count; ++j) s(idx.dep[static_cast<std::size_t>(j)]) = wrap(s(idx.dep[static_cast<std::size_t>(j)]));
  }
  closure(model, s, data, false);
  for (Limb limb : kLimbs)
    if (active[static_cast<std::size_t>(limb)]) report.residual = std::max(report.residual, limb_residual(data.Phi, indices(limb)));
  report.converged = true;
  return report;
}

}  // namespace

NewtonReport solve_ik_newton(const Model& model, Coordinates& s, Data& data, const NewtonOptions& options) {
  return newton(model, {true, true, true, true}, s, data, options);
}

NewtonReport solve_limb_newton(const Model& model, Limb limb, Coordinates& s, Data& data, const NewtonOptions& options) {
  std::array<bool, 4> active{false, false, false, false};
  active[static_cast<std::size_t>(limb)] = true;
  return newton(model, active, s, data, options);
}

}  // namespace wlx
