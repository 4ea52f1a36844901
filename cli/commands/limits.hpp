// Upper bounds on what a wheeled-legged machine can be or do. Values beyond them are accepted by the
// arithmetic but make no machine (a 1e308 kg body, gravity 1e304 m/s^2, a rate of 1e200 rad/s) and
// overflow to inf/NaN inside a step; they are rejected up front with the field named. The numbers
// are documented in README.md ("Hardening") and scenarios/README.md.
#pragma once

#include "per_model.hpp"
#include <wlx/model.hpp>

#include <cstddef>
#include <string>
#include <vector>

WLX_COMMANDS_BEGIN

inline constexpr double kMaxLength = 100;         // m: any length parameter
inline constexpr double kMaxMass = 1e6;           // kg: any body (the default machine is 6.2 t in all)
inline constexpr double kMaxInertia = 1e8;        // kg*m^2: kMaxMass at 10 m
inline constexpr double kMaxGravity = 100;        // m/s^2: about 10 g
inline constexpr double kMaxPosition = 1e4;       // m: |x_C|, |x_Fl|, ... (beyond, doubles lose the millimetre)
inline constexpr double kMaxAngle = 100;          // rad: |yaw|, |theta_l5|, ... (about 16 turns)
inline constexpr double kMaxLinearRate = 100;     // m/s
inline constexpr double kMaxAngularRate = 100;    // rad/s (about 16 turns per second)
inline constexpr double kMaxWeightRatio = 1e12;   // largest / smallest diagonal torque weight
inline constexpr double kMaxTorque = 1e9;         // N m (or N): any actuator, in a torque table
inline constexpr std::size_t kMaxTorqueRows = 1'000'000;  // rows of a torque table: 1000 s at 1 ms, ~0.1 GB
inline constexpr double kMinTorqueRowGap = 1e-9;  // s (relative beyond 1 s): consecutive rows of a torque table

// Whether a coordinate is an angle (unit rad): only angles may be given as {"deg": x}.
bool is_angle(int coordinate);
// The model's input coordinates' names, in order.
std::vector<std::string> input_names();

// Throws wlx::Error "params.<name>: ..." for a parameter beyond its bound (`prefix` + name).
void check_param_bounds(const Params& params, const std::string& prefix);
// An input coordinate's value (k < kInputCount) or its commanded rate, by the unit of the coordinate.
void check_input_bound(int coordinate, double value, const std::string& field);
void check_rate_bound(int coordinate, double rate, const std::string& field);

WLX_COMMANDS_END
