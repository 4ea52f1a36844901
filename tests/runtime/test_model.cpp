// The immutable Model: parameter defaults, validation, name look-ups.
#include <doctest/doctest.h>
#include <wlx/error.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/model.hpp>

#include <cmath>
#include <limits>

using namespace wlx;

TEST_CASE("model: total mass of the default parameters is the thesis' 6153.98 kg") {
  // Thesis Table 6-1; the sum of seven decimal numbers, exact to rounding.
  CHECK(Model().total_mass() == doctest::Approx(6153.98).epsilon(1e-14));
}

TEST_CASE("model: bad parameters are rejected by name") {
  const auto message = [](Params p) -> std::string {
    try {
      Model m(p);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  Params p;
  p.legD = -1;
  CHECK(message(p) == "legD: a length must be positive, got -1 m");
  p = Params{};
  p.cxd = std::numeric_limits<double>::quiet_NaN();
  CHECK(message(p) == "cxd: must be a finite number, got nan");
  p = Params{};
  p.m_M4 = 0;
  CHECK(message(p) == "m_M4: a mass must be positive, got 0 kg");
  p = Params{};
  p.Izz_M1 = 9000;  // > 4090.5 + 4090.5
  CHECK(message(p).rfind("Izz_M1: 9000 kg*m^2 exceeds the sum of the other two principal inertias", 0) == 0);
  CHECK(message(Params{}).empty());
}

TEST_CASE("model: names resolve to indices and parameters") {
  CHECK(coordinate_index("theta_r6") == gen::coord::theta_r6);
  CHECK(coordinate_index("theta_r7") == -1);
  CHECK(frame_index("W_l") == gen::frame::W_l);
  Params p;
  REQUIRE(find_param(p, "wl") != nullptr);
  *find_param(p, "wl") = 2.0;
  CHECK(p.wl == 2.0);
  CHECK(find_param(p, "wheel") == nullptr);
}

TEST_CASE("kinematics: the runtime wrapper fills the workspace") {
  const Model model;
  Data data;
  Coordinates s = nominal_inputs();
  forward_kinematics(model, data, s);
  // With all joints at zero the cabin frame sits at r_C and the left hip at r_C + (cxd/2, cyd/2, 0).
  CHECK(frame_position(data, gen::frame::C) == Eigen::Vector3d(0, 0, 2));
  CHECK(frame_position(data, gen::frame::hip_l) == Eigen::Vector3d(1.5, 1.5, 2));
  CHECK(frame_position(data, gen::frame::F_l) == Eigen::Vector3d(1.5 + 2.0 + 1.5, 1.5, 2));
}
