// An independent forward-kinematics chain for the tests, written directly from docs/excavator.md
// sections 3 and 6 with elementary rotation matrices, generic in the scalar (double or Jet).
// It shares nothing with the generator but the coordinate order and parameter values.
#pragma once

#include "chain_algebra.hpp"

#include <wlx/gen/params.hpp>
#include <wlx/gen/types.hpp>

#include <array>

namespace wlx::test {

// Every frame of interest (same order as wlx::gen::frame) and every body CoM frame (wlx::gen::body).
template <class T> struct ReferenceKinematics {
  std::array<Pose<T>, gen::kFrameCount> frames;
  std::array<Pose<T>, gen::kBodyCount> bodies;
};

template <class T> ReferenceKinematics<T> reference_kinematics(const std::array<T, gen::kCoordinateCount>& s,
                                                               const gen::Params& p) {
  namespace c = gen::coord;
  namespace f = gen::frame;
  namespace b = gen::body;
  ReferenceKinematics<T> out;
  const M3<T> R_C = mul(mul(Rz(s[c::yaw]), Ry(s[c::pitch])), Rx(s[c::roll]));
  const V3<T> r_C = {s[c::x_C], s[c::y_C], s[c::z_C]};
  out.frames[f::C] = {R_C, r_C};
  out.bodies[b::M1] = {R_C, r_C};
  const auto world = [&](const V3<T>& local) { return add(r_C, mul(R_C, local)); };

  struct Leg { int psi1, psi2, psi3, psi4, hip, knee, foot, thigh, shank; double side; };
  for (const Leg& L : {Leg{c::psi_l1, c::psi_l2, c::psi_l3, c::psi_l4, f::hip_l, f::knee_l, f::F_l, b::M3, b::M5, 1.0},
                       Leg{c::psi_r1, c::psi_r2, c::psi_r3, c::psi_r4, f::hip_r, f::knee_r, f::F_r, b::M2, b::M4, -1.0}}) {
    const V3<T> h = {T(p.cxd / 2), T(L.side * p.cyd / 2), T(0)};
    const M3<T> R_hip = mul(mul(Rx(s[L.psi1]), Ry(s[L.psi2])), Rz(s[L.psi3]));
    const M3<T> R_knee = mul(R_hip, Ry(s[L.psi4]));
    const V3<T> knee = add(h, mul(R_hip, V3<T>{T(p.thighD), T(0), T(0)}));
    const V3<T> foot = add(knee, mul(R_knee, V3<T>{T(p.legD), T(0), T(0)}));
    out.frames[L.hip] = {mul(R_C, R_hip), world(h)};
    out.frames[L.knee] = {mul(R_C, R_knee), world(knee)};
    out.frames[L.foot] = {mul(R_C, R_knee), world(foot)};
    out.bodies[L.thigh] = {mul(R_C, R_hip), world(add(h, mul(R_hip, V3<T>{T(p.thighD / 2), T(0), T(0)})))};
    out.bodies[L.shank] = {mul(R_C, R_knee), world(add(knee, mul(R_knee, V3<T>{T(p.legD / 2), T(0), T(0)})))};
  }
  struct Wheel { int th2, th3, th4, th5, th6, hip, end, W, lever; double side; };
  for (const Wheel& W : {Wheel{c::theta_l2, c::theta_l3, c::theta_l4, c::theta_l5, c::theta_l6, f::lever_hip_l,
                               f::lever_end_l, f::W_l, b::M6, 1.0},
                         Wheel{c::theta_r2, c::theta_r3, c::theta_r4, c::theta_r5, c::theta_r6, f::lever_hip_r,
                               f::lever_end_r, f::W_r, b::M7, -1.0}}) {
    const V3<T> h = {T(-p.cxd / 2), T(W.side * p.cyd / 2), T(0)};
    const M3<T> R_lev = mul(Ry(s[W.th6]), Rz(s[W.th5]));
    const M3<T> R_10 = mul(mul(R_lev, Rz(s[W.th4])), Ry(s[W.th3]));
    const M3<T> R_W = mul(R_10, Rx(s[W.th2]));
    const V3<T> end = add(h, mul(R_lev, V3<T>{T(-p.wl), T(0), T(0)}));
    const V3<T> contact = add(end, mul(R_10, V3<T>{T(0), T(0), T(-p.w)}));
    out.frames[W.hip] = {mul(R_C, R_lev), world(h)};
    out.frames[W.end] = {mul(R_C, R_10), world(end)};
    out.frames[W.W] = {mul(R_C, R_W), world(contact)};
    out.bodies[W.lever] = {mul(R_C, R_lev), world(add(h, mul(R_lev, V3<T>{T(-p.wl / 2), T(0), T(0)})))};
  }
  return out;
}

// The 14 closure equations of docs/excavator.md section 4, from the reference chain.
template <class T> std::array<T, gen::kClosureCount> reference_closure(const std::array<T, gen::kCoordinateCount>& s,
                                                                        const gen::Params& p) {
  namespace c = gen::coord;
  namespace f = gen::frame;
  const auto k = reference_kinematics(s, p);
  std::array<T, gen::kClosureCount> phi;
  const int targets[2][3] = {{c::x_Fl, c::y_Fl, c::z_Fl}, {c::x_Fr, c::y_Fr, c::z_Fr}};
  const int feet[2] = {f::F_l, f::F_r};
  for (int leg = 0; leg < 2; ++leg)
    for (int i = 0; i < 3; ++i) phi[3 * leg + i] = k.frames[feet[leg]].r[i] - s[targets[leg][i]];
  const int contacts[2] = {f::W_l, f::W_r};
  const int levels[2] = {c::z_Wl, c::z_Wr};
  const int guidance[2][2] = {{c::theta_l4, c::theta_l5}, {c::theta_r4, c::theta_r5}};
  for (int w = 0; w < 2; ++w) {
    const auto& P = k.frames[contacts[w]];
    phi[6 + 4 * w + 0] = P.r[2] - s[levels[w]];
    phi[6 + 4 * w + 1] = P.R[2][0];  // (R e_x) . e_z
    phi[6 + 4 * w + 2] = P.R[2][1];  // (R e_y) . e_z
    phi[6 + 4 * w + 3] = s[guidance[w][0]] + s[guidance[w][1]];
  }
  return phi;
}

}  // namespace wlx::test
