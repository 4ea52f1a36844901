// An independent forward-kinematics chain of the walker (models/walker.yaml), written by hand from
// its description with elementary rotation matrices, generic in the scalar (double or Jet). It
// shares nothing with the generator but the coordinate order and the parameter values.
#pragma once

#include "chain_algebra.hpp"

namespace wlx::test {

template <class T> struct WalkerKinematics {
  std::array<Pose<T>, gen::kFrameCount> frames;
  std::array<Pose<T>, gen::kBodyCount> bodies;
};

template <class T> WalkerKinematics<T> walker_kinematics(const std::array<T, gen::kCoordinateCount>& s, const gen::Params& p) {
  namespace c = gen::coord;
  namespace f = gen::frame;
  namespace b = gen::body;
  WalkerKinematics<T> out;
  const M3<T> R_C = mul(mul(Rz(s[c::yaw]), Ry(s[c::pitch])), Rx(s[c::roll]));
  const V3<T> r_C = {s[c::x_C], s[c::y_C], s[c::z_C]};
  const auto world = [&](const V3<T>& local) { return add(r_C, mul(R_C, local)); };
  out.frames[f::C] = {R_C, r_C};
  out.bodies[b::cabin] = {R_C, world(V3<T>{T(0.1), T(0), T(0.2)})};

  // Legs: hip below the cabin plane, slewing about z, abduction about x, lift about y; the knee
  // axis sits knee_offset outboard of the thigh; the foot at the end of the shank.
  struct Leg { int slew, abduct, lift, knee, hip_f, knee_f, foot_f, thigh_b, shank_b; double side; };
  for (const Leg& L : {Leg{c::slew_l, c::abduct_l, c::lift_l, c::knee_l, f::hip_l, f::knee_l, f::foot_l, b::thigh_l, b::shank_l, 1.0},
                       Leg{c::slew_r, c::abduct_r, c::lift_r, c::knee_r, f::hip_r, f::knee_r, f::foot_r, b::thigh_r, b::shank_r, -1.0}}) {
    const V3<T> h = {T(p.hip_x), T(L.side * p.hip_y), T(-p.hip_drop)};
    const M3<T> R_hip = mul(mul(Rz(s[L.slew]), Rx(s[L.abduct])), Ry(s[L.lift]));
    const M3<T> R_knee = mul(R_hip, Ry(s[L.knee]));
    const V3<T> knee = add(h, mul(R_hip, V3<T>{T(p.thigh), T(L.side * p.knee_offset), T(0)}));
    const V3<T> foot = add(knee, mul(R_knee, V3<T>{T(p.shank), T(0), T(0)}));
    out.frames[L.hip_f] = {mul(R_C, R_hip), world(h)};
    out.frames[L.knee_f] = {mul(R_C, R_knee), world(knee)};
    out.frames[L.foot_f] = {mul(R_C, R_knee), world(foot)};
    out.bodies[L.thigh_b] = {mul(R_C, R_hip), world(add(h, mul(R_hip, V3<T>{T(p.thigh / 2), T(0), T(0)})))};
    out.bodies[L.shank_b] = {mul(R_C, R_knee), world(add(knee, mul(R_knee, V3<T>{T(p.shank * 2 / 5), T(0), T(0)})))};
  }
  // Levers: swing about y, steering about z; the hub joint lever_offset outboard of the lever
  // axis; guidance about z, hub pitch about y; the wheel plane hub_offset outboard; camber about x.
  struct Lever { int swing, steer, guide, hub, camber, lever_f, hub_f, contact_f, lever_b; double side; };
  for (const Lever& W : {Lever{c::swing_l, c::steer_l, c::guide_l, c::hub_l, c::camber_l, f::lever_l, f::hub_l, f::contact_l, b::lever_l, 1.0},
                         Lever{c::swing_r, c::steer_r, c::guide_r, c::hub_r, c::camber_r, f::lever_r, f::hub_r, f::contact_r, b::lever_r, -1.0}}) {
    const V3<T> h = {T(-p.rear_x), T(W.side * p.rear_y), T(-p.rear_drop)};
    const M3<T> R_lev = mul(Ry(s[W.swing]), Rz(s[W.steer]));
    const M3<T> R_hub = mul(mul(R_lev, Rz(s[W.guide])), Ry(s[W.hub]));
    const M3<T> R_W = mul(R_hub, Rx(s[W.camber]));
    const V3<T> hub = add(h, mul(R_lev, V3<T>{T(-p.lever), T(W.side * p.lever_offset), T(0)}));
    const V3<T> contact = add(hub, mul(R_hub, V3<T>{T(0), T(W.side * p.hub_offset), T(-p.radius)}));
    out.frames[W.lever_f] = {mul(R_C, R_lev), world(h)};
    out.frames[W.hub_f] = {mul(R_C, R_hub), world(hub)};
    out.frames[W.contact_f] = {mul(R_C, R_W), world(contact)};
    out.bodies[W.lever_b] = {mul(R_C, R_lev), world(add(h, mul(R_lev, V3<T>{T(-p.lever * 3 / 5), T(0), T(0)})))};
  }
  return out;
}

// The walker's 14 closure equations, from the chain above.
template <class T> std::array<T, gen::kClosureCount> walker_closure(const std::array<T, gen::kCoordinateCount>& s,
                                                                     const gen::Params& p) {
  namespace c = gen::coord;
  namespace f = gen::frame;
  const auto k = walker_kinematics(s, p);
  std::array<T, gen::kClosureCount> phi;
  const int targets[2][3] = {{c::foot_x_l, c::foot_y_l, c::foot_z_l}, {c::foot_x_r, c::foot_y_r, c::foot_z_r}};
  const int feet[2] = {f::foot_l, f::foot_r};
  for (int leg = 0; leg < 2; ++leg)
    for (int i = 0; i < 3; ++i) phi[3 * leg + i] = k.frames[feet[leg]].r[i] - s[targets[leg][i]];
  const int contacts[2] = {f::contact_l, f::contact_r};
  const int grounds[2] = {c::ground_l, c::ground_r};
  const int guidance[2][2] = {{c::guide_l, c::steer_l}, {c::guide_r, c::steer_r}};
  for (int w = 0; w < 2; ++w) {
    const auto& P = k.frames[contacts[w]];
    phi[6 + 4 * w + 0] = P.r[2] - s[grounds[w]];
    phi[6 + 4 * w + 1] = P.R[2][0];
    phi[6 + 4 * w + 2] = P.R[2][1];
    phi[6 + 4 * w + 3] = s[guidance[w][0]] + s[guidance[w][1]];
  }
  return phi;
}

}  // namespace wlx::test
