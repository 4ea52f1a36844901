// The runtime compiled once for every model (wlx/generic/) against the model's own runtime
// (compiled for it at its fixed sizes), for the model this file is compiled with (tests/CMakeLists.txt
// compiles it once per model, with WLX_TEST_MODEL_JSON naming its model.json).
//
// The two run the same generated code on the same numbers, through algorithms written once
// (wlx/ik_algorithms.hpp): their results must agree to the last bit, and their errors word for
// word. Bitwise equality is the claim, so it is what is asserted: any difference means one of
// them computes something else.
#include <doctest/doctest.h>
#include <wlx/error.hpp>
#include <wlx/generic/ik.hpp>
#include <wlx/generic/kinematics.hpp>
#include <wlx/generic/nonholonomic.hpp>
#include <wlx/ik.hpp>
#include <wlx/kinematics.hpp>
#include <wlx/nonholonomic.hpp>
#include <wlx/model_code.hpp>
#include <wlx/settings.hpp>

#include <cstring>
#include <algorithm>
#include <deque>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string>

#ifndef WLX_TEST_MODEL_JSON
#error "compile with WLX_TEST_MODEL_JSON, the model's model.json (tests/CMakeLists.txt)"
#endif

using namespace wlx;

namespace {

const std::string kName(gen::kModelName);

const char* titled(const char* what) {
  static std::deque<std::string> titles;
  return titles.emplace_back(kName + ": generic runtime: " + what).c_str();
}

std::string description_text() {
  std::ifstream in(WLX_TEST_MODEL_JSON);
  REQUIRE_MESSAGE(in.good(), "cannot read " WLX_TEST_MODEL_JSON);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::shared_ptr<const generic::Description> description() {
  static const auto d = std::make_shared<const generic::Description>(generic::read_description(description_text()));
  return d;
}

Eigen::VectorXd dynamic(const Coordinates& s) { return Eigen::VectorXd(s); }

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

bool same_bits(const Eigen::Ref<const Eigen::MatrixXd>& a, const Eigen::Ref<const Eigen::MatrixXd>& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return false;
  for (Eigen::Index j = 0; j < a.cols(); ++j)
    for (Eigen::Index i = 0; i < a.rows(); ++i)
      if (!same_bits(a(i, j), b(i, j))) return false;
  return true;
}

// The outcome of a call: its error's text, or empty.
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return std::string("wlx::Error(") + error_kind_name(e.kind()) + "): " + e.what();
  }
  return {};
}

// Inputs near the model's nominal ones (every input moved by up to `reach`, m or rad), the
// dependent joints at Newton's start values: some out of a limb's reach, which both must refuse alike.
Coordinates near_nominal(std::mt19937_64& rng, double reach) {
  std::uniform_real_distribution<double> u(-1, 1);
  Coordinates s = nominal_inputs();
  for (int k = 0; k < kInputCount; ++k) s(k) += reach * u(rng);
  return s;
}

}  // namespace

TEST_CASE(titled("model.json describes the code: names, limbs, parameters and settings as the model's tables have them")) {
  const generic::Description& d = *description();
  CHECK(d.model == kName);
  REQUIRE(d.coordinate_count() == kCoordinateCount);
  CHECK(d.input_count == kInputCount);
  for (int k = 0; k < kCoordinateCount; ++k) {
    CHECK(d.coordinates[static_cast<std::size_t>(k)].name == gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    CHECK(d.coordinates[static_cast<std::size_t>(k)].unit == gen::kCoordinateUnits[static_cast<std::size_t>(k)]);
  }
  REQUIRE(d.frames.size() == static_cast<std::size_t>(gen::kFrameCount));
  for (int f = 0; f < gen::kFrameCount; ++f) {
    CHECK(d.frames[static_cast<std::size_t>(f)].name == gen::kFrameNames[static_cast<std::size_t>(f)]);
    CHECK(d.frames[static_cast<std::size_t>(f)].parent == gen::kFrameParent[static_cast<std::size_t>(f)]);
  }
  REQUIRE(d.parameters.size() == gen::kParamInfo.size());
  for (std::size_t k = 0; k < d.parameters.size(); ++k) CHECK(d.parameters[k].name == gen::kParamInfo[k].name);
  REQUIRE(d.limbs.size() == static_cast<std::size_t>(kLimbCount));
  for (int l = 0; l < kLimbCount; ++l) {
    const gen::LimbInfo& fixed = gen::kLimbs[static_cast<std::size_t>(l)];
    const generic::Limb& read = d.limbs[static_cast<std::size_t>(l)];
    CHECK(read.name == fixed.name);
    CHECK(read.title == fixed.title);
    REQUIRE(read.joints.size() == static_cast<std::size_t>(fixed.size));
    for (int j = 0; j < fixed.size; ++j) {
      CHECK(read.joints[static_cast<std::size_t>(j)] == fixed.joints[static_cast<std::size_t>(j)]);
      CHECK(read.rows[static_cast<std::size_t>(j)] == fixed.rows[static_cast<std::size_t>(j)]);
    }
    REQUIRE(read.inputs.size() == static_cast<std::size_t>(fixed.input_count));
    for (int i = 0; i < fixed.input_count; ++i) CHECK(read.inputs[static_cast<std::size_t>(i)] == fixed.inputs[static_cast<std::size_t>(i)]);
    CHECK(read.joints.size() <= static_cast<std::size_t>(d.max_limb_size()));
    CHECK(d.settings.default_branch[static_cast<std::size_t>(l)] == settings().default_branch[static_cast<std::size_t>(l)]);
  }
  CHECK(d.max_limb_size() == gen::kMaxLimbSize);
  for (int k = 0; k < kCoordinateCount; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (k < kInputCount) CHECK(d.settings.nominal_inputs[kk] == settings().nominal_inputs[kk]);
    else CHECK(d.settings.dependent_start[kk] == settings().dependent_start[kk - static_cast<std::size_t>(kInputCount)]);
    CHECK(d.settings.lower[kk] == settings().lower[kk]);
    CHECK(d.settings.upper[kk] == settings().upper[kk]);
    CHECK(d.settings.velocity_limit[kk] == settings().velocity_limit[kk]);
  }
  const generic::Model model(description(), model_code());
  CHECK(model.total_mass() == Model().total_mass());
  CHECK(same_bits(generic::nominal_coordinates(model), dynamic(nominal_inputs())));
}

TEST_CASE(titled("forward kinematics and the closure with its Jacobian, bit for bit")) {
  const Model fixed_model;
  Data fixed;
  const generic::Model model(description(), model_code());
  generic::Data data(model);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int trial = 0; trial < 50; ++trial) {
    Coordinates s;
    for (int k = 0; k < kCoordinateCount; ++k) s(k) = u(rng);  // anywhere: these evaluate, they solve nothing
    forward_kinematics(fixed_model, fixed, s);
    generic::forward_kinematics(model, data, dynamic(s));
    REQUIRE(same_bits(data.frame_positions, fixed.frame_positions));
    for (int f = 0; f < gen::kFrameCount; ++f) REQUIRE(same_bits(data.frame_rotation(f), frame_rotation(fixed, f)));
    closure(fixed_model, fixed, s, true);
    generic::closure(model, data, dynamic(s), true);
    REQUIRE(same_bits(data.Phi, fixed.Phi));
    REQUIRE(same_bits(data.dPhi_ds, fixed.dPhi_ds));
  }
}

TEST_CASE(titled("the IK on every branch and by the model's choice, Newton's method, and their refusals, bit for bit and word for word")) {
  const Model fixed_model;
  const generic::Model model(description(), model_code());
  generic::Data data(model);
  std::mt19937_64 rng(12);
  int solved = 0, refused = 0;
  for (int trial = 0; trial < 60; ++trial) {
    // Mostly within reach, every fifth draw far enough to be refused by some limb.
    const Coordinates start = near_nominal(rng, trial % 5 == 4 ? 0.6 : 0.05);
    Coordinates s_fixed = start;
    Eigen::VectorXd s = dynamic(start);
    NewtonReport fixed_report;
    generic::NewtonReport report;
    const std::string fixed_error = error_of([&] { solve_ik_closed_form(fixed_model, s_fixed, {}, &fixed_report); });
    const std::string error = error_of([&] { generic::solve_ik_closed_form(model, data, s, {}, &report); });
    REQUIRE(error == fixed_error);
    if (!error.empty()) {
      ++refused;
      continue;
    }
    ++solved;
    REQUIRE(same_bits(s, dynamic(s_fixed)));
    CHECK(report.converged == fixed_report.converged);
    CHECK(report.residual == fixed_report.residual);
    for (int l = 0; l < kLimbCount; ++l) {
      CHECK(report.iterations[static_cast<std::size_t>(l)] == fixed_report.iterations[static_cast<std::size_t>(l)]);
      CHECK(generic::classify_branch(model, data, l, s) == classify_branch(fixed_model, l, s_fixed));
      CHECK(generic::branch_count(model, l) == branch_count(l));
      CHECK(generic::has_closed_form(model, l) == has_closed_form(l));
      for (int b = -1; b <= branch_count(l); ++b) {  // one below and one past the branches: refused alike
        Coordinates limb_fixed = start;
        Eigen::VectorXd limb = dynamic(start);
        const std::string a = error_of([&] { solve_limb_closed_form(fixed_model, l, b, limb_fixed); });
        const std::string g = error_of([&] { generic::solve_limb_closed_form(model, data, l, b, limb); });
        REQUIRE(g == a);
        if (a.empty()) REQUIRE(same_bits(limb, dynamic(limb_fixed)));
      }
    }
    // Newton's method on every limb from the model's start values, by both algorithms.
    for (const auto method : {NewtonOptions::Method::levenberg_marquardt, NewtonOptions::Method::backtracking}) {
      NewtonOptions options;
      options.method = method;
      Data fixed;
      Coordinates n_fixed = dependent_start(s_fixed);
      Eigen::VectorXd n = generic::dependent_start(model, dynamic(s_fixed));
      NewtonReport a;
      generic::NewtonReport g;
      const std::string ea = error_of([&] { a = solve_ik_newton(fixed_model, fixed, n_fixed, options); });
      const std::string eg = error_of([&] { g = generic::solve_ik_newton(model, data, n, options); });
      REQUIRE(eg == ea);
      if (!ea.empty()) continue;
      REQUIRE(same_bits(n, dynamic(n_fixed)));
      CHECK(g.converged == a.converged);
      CHECK(g.residual == a.residual);
      for (int l = 0; l < kLimbCount; ++l) CHECK(g.iterations[static_cast<std::size_t>(l)] == a.iterations[static_cast<std::size_t>(l)]);
    }
  }
  CHECK(solved > 20);
  if (kLimbCount > 0) CHECK(refused > 0);  // the far draws took the refusals' path
}

TEST_CASE(titled("Newton's continuation and its bound on a jump, as the model's own runtime")) {
  if (kLimbCount == 0) return;
  const Model fixed_model;
  Data fixed;
  const generic::Model model(description(), model_code());
  generic::Data data(model);
  Coordinates s_fixed = nominal_inputs();
  solve_ik_closed_form(fixed_model, s_fixed);
  // From the solution moved by 0.3 rad or m on every dependent joint: continuation back to it, and
  // with a bound of 0.1 the same refusal, naming the same limb and joint.
  Coordinates moved = s_fixed;
  moved.tail(kDependentCount).array() += 0.3;
  std::array<bool, kLimbCount> all;
  all.fill(true);
  for (const double bound : {std::numeric_limits<double>::infinity(), 0.1}) {
    NewtonOptions options;
    options.max_jump = bound;
    Coordinates a = moved;
    Eigen::VectorXd g = dynamic(moved);
    const std::string ea = error_of([&] { solve_newton_limbs(fixed_model, fixed, all, a, options); });
    const std::string eg = error_of([&] { generic::solve_newton_limbs(model, data, std::vector<bool>(kLimbCount, true), g, options); });
    REQUIRE(eg == ea);
    if (bound < 1) CHECK(ea.find("another solution") != std::string::npos);  // back by 0.3 is a jump past 0.1
    else CHECK(ea.empty());
    if (ea.empty()) CHECK(same_bits(g, dynamic(a)));
  }
}

TEST_CASE(titled("parameters and descriptions that do not fit are refused, naming what")) {
  // A parameter refused by its kind: the same words as the model's own Model.
  int refused = 0;
  std::vector<double> params;
  for (const auto& p : description()->parameters) params.push_back(p.value);
  for (std::size_t k = 0; k < params.size(); ++k) {
    std::vector<double> bad = params;
    bad[k] = -1;
    Params fixed_params = settings().params;
    fixed_params.*gen::kParamInfo[k].member = -1;
    const std::string a = error_of([&] { Model m(fixed_params); });
    const std::string g = error_of([&] { generic::Model m(description(), model_code(), bad); });
    CHECK(g == a);
    refused += !a.empty();
  }
  CHECK(refused > 0);  // every model has masses and inertias, which -1 is not
  CHECK(error_of([&] { generic::Model m(description(), model_code(), std::vector<double>(params.size() + 1, 1.0)); }).find("params") !=
        std::string::npos);
  // A description of another model, or of other sizes, is not this code's.
  generic::Description other = *description();
  other.model = "another";
  CHECK(error_of([&] { generic::Model m(std::make_shared<const generic::Description>(other), model_code()); })
            .find("it describes model 'another'") != std::string::npos);
  other = *description();
  other.frames.push_back({"extra", -1});
  CHECK(error_of([&] { generic::Model m(std::make_shared<const generic::Description>(other), model_code()); })
            .find("frames") != std::string::npos);
  // Text that is not a description, or not one of this format.
  CHECK(error_of([] { generic::read_description("[1, 2"); }).find("model.json: not JSON") != std::string::npos);
  CHECK(error_of([] { generic::read_description(R"({"format": "wlx model description 2"})"); }).find("format 1") != std::string::npos);
  std::string deep(40, '[');
  deep += std::string(40, ']');
  CHECK(error_of([&] { generic::read_description(deep); }).find("nested deeper") != std::string::npos);
  // A limb that names a coordinate the description does not have.
  if (kLimbCount > 0) {
    std::string text = description_text();
    const std::string joint = "\"" + std::string(gen::kCoordinateNames[static_cast<std::size_t>(gen::kLimbs[0].joints[0])]) + "\"";
    const std::size_t limbs = text.find("\"limbs\"");
    const std::size_t at = text.find(joint, limbs);
    REQUIRE(at != std::string::npos);
    text.replace(at, joint.size(), "\"no_such_joint\"");
    CHECK(error_of([&] { generic::read_description(text); }).find("no coordinate 'no_such_joint'") != std::string::npos);
  }
}

TEST_CASE(titled("other parameters' values, one Data for two Models, the branches' choice and its limits, one limb's Newton")) {
  // Every length, mass and inertia 3% larger (a uniform scale keeps the inertias physical), in both.
  Params scaled = settings().params;
  std::vector<double> values;
  for (std::size_t k = 0; k < gen::kParamInfo.size(); ++k) {
    const auto kind = gen::kParamInfo[k].kind;
    double& v = scaled.*gen::kParamInfo[k].member;
    if (kind == gen::ParamKind::length || kind == gen::ParamKind::mass || kind == gen::ParamKind::inertia) v *= 1.03;
    values.push_back(v);
  }
  const Model fixed_default, fixed_scaled(scaled);
  const generic::Model model_default(description(), model_code()), model_scaled(description(), model_code(), values);
  CHECK(model_scaled.total_mass() == fixed_scaled.total_mass());
  generic::Data data(model_default);  // shared: each call must load its own model's parameters
  Data fixed;
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int trial = 0; trial < 20; ++trial) {
    Coordinates s;
    for (int k = 0; k < kCoordinateCount; ++k) s(k) = u(rng);
    for (const bool use_scaled : {true, false, true}) {
      const Model& fm = use_scaled ? fixed_scaled : fixed_default;
      const generic::Model& gm = use_scaled ? model_scaled : model_default;
      forward_kinematics(fm, fixed, s);
      generic::forward_kinematics(gm, data, dynamic(s));
      REQUIRE(same_bits(data.frame_positions, fixed.frame_positions));
      closure(fm, fixed, s, true);
      generic::closure(gm, data, dynamic(s), true);
      REQUIRE(same_bits(data.dPhi_ds, fixed.dPhi_ds));
    }
  }
  // The model's choice of branch and whether it leaves a joint's range, every branch requested
  // explicitly, and one limb by Newton's method, at states near the nominal one.
  for (int trial = 0; trial < 20; ++trial) {
    const Coordinates start = near_nominal(rng, 0.05);
    std::array<bool, kLimbCount> outside_fixed{};
    std::vector<bool> outside;
    std::string ea, eg;
    Branches chosen_fixed;
    generic::Branches chosen;
    ea = error_of([&] { chosen_fixed = resolve_branches(fixed_scaled, start, {}, &outside_fixed); });
    eg = error_of([&] { chosen = generic::resolve_branches(model_scaled, data, dynamic(start), {}, &outside); });
    REQUIRE(eg == ea);
    if (!ea.empty()) continue;
    for (int l = 0; l < kLimbCount; ++l) {
      CHECK(chosen[static_cast<std::size_t>(l)] == chosen_fixed.limb[static_cast<std::size_t>(l)]);
      CHECK(outside[static_cast<std::size_t>(l)] == outside_fixed[static_cast<std::size_t>(l)]);
    }
    for (int b = 0; kLimbCount > 0 && b < branch_count(0); ++b) {
      Branches requested;
      requested.limb.fill(kModelsChoice);
      requested.limb[0] = b;
      generic::Branches asked(static_cast<std::size_t>(kLimbCount), kModelsChoice);
      asked[0] = b;
      Coordinates a = start;
      Eigen::VectorXd g = dynamic(start);
      ea = error_of([&] { solve_ik_closed_form(fixed_scaled, a, requested); });
      eg = error_of([&] { generic::solve_ik_closed_form(model_scaled, data, g, asked); });
      REQUIRE(eg == ea);
      if (ea.empty()) REQUIRE(same_bits(g, dynamic(a)));
      if (!ea.empty() || kLimbCount == 0) continue;
      // The first limb again by Newton's method from its start values; its report as the model's.
      Coordinates na = dependent_start(a);
      Eigen::VectorXd ng = generic::dependent_start(model_scaled, dynamic(a));
      NewtonReport ra;
      generic::NewtonReport rg;
      ea = error_of([&] { ra = solve_limb_newton(fixed_scaled, fixed, 0, na); });
      eg = error_of([&] { rg = generic::solve_limb_newton(model_scaled, data, 0, ng); });
      REQUIRE(eg == ea);
      if (!ea.empty()) continue;
      REQUIRE(same_bits(ng, dynamic(na)));
      CHECK(rg.iterations == std::vector<int>(ra.iterations.begin(), ra.iterations.end()));
    }
    // The ranges: a joint moved past its upper bound is named alike.
    Coordinates moved = start;
    for (int k = 0; k < kCoordinateCount; ++k)
      if (std::isfinite(settings().upper[static_cast<std::size_t>(k)])) {
        moved(k) = settings().upper[static_cast<std::size_t>(k)] + 0.25;
        break;
      }
    const int k = first_outside_limits(moved);
    CHECK(generic::first_outside_limits(model_scaled, dynamic(moved)) == k);
    if (k >= 0) {
      CHECK(generic::describe_outside_limits(model_scaled, dynamic(moved), k) == describe_outside_limits(moved, k));
      CHECK_FALSE(generic::within_range(model_scaled, dynamic(moved), k));
    }
  }
}

TEST_CASE(titled("wrong sizes, indices and code are refused, naming what")) {
  const generic::Model model(description(), model_code());
  generic::Data data(model);
  Eigen::VectorXd short_s = Eigen::VectorXd::Zero(kCoordinateCount - 1);
  CHECK(error_of([&] { generic::forward_kinematics(model, data, short_s); }).find("s: ") != std::string::npos);
  CHECK(error_of([&] { generic::solve_ik_closed_form(model, data, short_s); }).find("s: ") != std::string::npos);
  CHECK(error_of([&] { generic::first_outside_limits(model, short_s); }).find("s: ") != std::string::npos);
  Eigen::VectorXd s = generic::nominal_coordinates(model);
  CHECK(error_of([&] { generic::within_range(model, s, kCoordinateCount); }).find("no coordinate") != std::string::npos);
  CHECK(error_of([&] { generic::solve_limb_closed_form(model, data, kLimbCount, 0, s); }).find("no limb") != std::string::npos);
  CHECK(error_of([&] { generic::solve_ik_closed_form(model, data, s, generic::Branches(static_cast<std::size_t>(kLimbCount) + 1, 0)); })
            .find("branches for the model's") != std::string::npos);
  CHECK(error_of([&] { data.frame_rotation(gen::kFrameCount); }).find("no frame") != std::string::npos);
  // Code of another version of the interface.
  ModelCode old = model_code();
  old.version = kModelCodeVersion + 1;
  CHECK(error_of([&] { generic::Model m(description(), old); }).find("compile the model again") != std::string::npos);
  // A description whose names are not the code's: a coordinate renamed.
  generic::Description renamed = *description();
  renamed.coordinates[0].name = "renamed";
  CHECK(error_of([&] { generic::Model m(std::make_shared<const generic::Description>(renamed), model_code()); })
            .find("coordinate 'renamed' where the code has") != std::string::npos);
  // A description made in code whose indices point nowhere: refused before anything reads them.
  generic::Description broken = *description();
  if (!broken.bodies.empty()) {
    broken.bodies[0].mass = 100000;
    CHECK(error_of([&] { generic::Model m(std::make_shared<const generic::Description>(broken), model_code()); })
              .find("mass is no parameter") != std::string::npos);
  }
  if (kLimbCount > 0) {
    broken = *description();
    std::swap(broken.limbs[0].joints, broken.limbs[0].rows);  // rows are no joints (and the other way)
    CHECK_FALSE(error_of([&] { generic::Model m(std::make_shared<const generic::Description>(broken), model_code()); }).empty());
  }
  broken = *description();
  broken.settings.lower.pop_back();
  CHECK(error_of([&] { generic::Model m(std::make_shared<const generic::Description>(broken), model_code()); }).find("settings.limits") !=
        std::string::npos);
  CHECK(error_of([] { generic::read_description(std::string(generic::kMaxDescriptionBytes + 1, ' ')); }).find("more than a description's") !=
        std::string::npos);
}

namespace {

// Relative agreement of two results of the same algorithm whose sums Eigen orders differently at
// fixed and at run-time sizes (a product's inner sum, a norm): rounding, amplified at most by the
// condition of the solves they pass through (J_beta's and the limb blocks', below 1e6 at these
// states): 1e-12 of the larger entry leaves that room at 1e-16 per operation.
bool agree(const Eigen::Ref<const Eigen::MatrixXd>& a, const Eigen::Ref<const Eigen::MatrixXd>& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols() || !a.allFinite() || !b.allFinite()) return false;
  if (a.size() == 0) return true;  // J_beta of a model without wheels
  const double scale = std::max({1.0, a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()});
  return (a - b).cwiseAbs().maxCoeff() <= 1e-12 * scale;
}

}  // namespace

TEST_CASE(titled("the dependent rates, accelerations and rate basis, and the pairs, as the model's own runtime")) {
  const Model fixed_model;
  Data fixed;
  const generic::Model model(description(), model_code());
  generic::Data data(model);
  // The pairs: by name, by the rates' names, the default, and the refusals, word for word.
  const DependentPair fixed_default = default_pair();
  const generic::DependentPair generic_default = generic::default_pair(model);
  CHECK(generic_default.index == std::vector<int>(fixed_default.index.begin(), fixed_default.index.end()));
  CHECK(generic::pair_label(model, generic_default) == fixed_default.label());
  for (const auto& named : gen::kPairs) {
    CHECK(generic::named_pair(model, named.name).index == std::vector<int>(named.coordinates.begin(), named.coordinates.end()));
    std::vector<std::string> names;
    for (int k : named.coordinates) names.emplace_back(gen::kCoordinateNames[static_cast<std::size_t>(k)]);
    CHECK(generic::dependent_pair(model, names).index == std::vector<int>(named.coordinates.begin(), named.coordinates.end()));
  }
  CHECK(error_of([&] { generic::named_pair(model, "no_such_pair"); }) == error_of([] { named_pair("no_such_pair"); }));
  const std::vector<std::string> wrong{"no_such_rate"};
  CHECK(error_of([&] { generic::dependent_pair(model, wrong); }) == error_of([&] { dependent_pair(wrong); }));
  if (kWheelCount >= 2) {
    const std::string twice(gen::kCoordinateNames[static_cast<std::size_t>(fixed_default.index[0])]);
    std::vector<std::string> repeated(static_cast<std::size_t>(kWheelCount), twice);
    CHECK(error_of([&] { generic::dependent_pair(model, repeated); }) == error_of([&] { dependent_pair(repeated); }));
  }
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> rate(-0.5, 0.5);
  int compared = 0;
  for (int trial = 0; trial < 30; ++trial) {
    Coordinates s = near_nominal(rng, 0.05);
    try {
      solve_ik_closed_form(fixed_model, s);
    } catch (const Error&) {
      continue;
    }
    Coordinates sdot = Coordinates::Zero(), sddot = Coordinates::Zero();
    for (int k = 0; k < kInputCount; ++k) sdot(k) = rate(rng), sddot(k) = rate(rng);
    Eigen::VectorXd g_sdot = dynamic(sdot), g_sddot = dynamic(sddot);
    const std::string ea = error_of([&] { solve_dependent_rates(fixed_model, fixed, s, sdot, fixed_default); });
    const std::string eg = error_of([&] { generic::solve_dependent_rates(model, data, dynamic(s), g_sdot, generic_default); });
    REQUIRE(eg == ea);
    if (!ea.empty()) continue;
    ++compared;
    REQUIRE(agree(g_sdot, dynamic(sdot)));
    CHECK(agree(data.J_beta, fixed.J_beta));
    CHECK(std::abs(data.cond_J_beta - fixed.cond_J_beta) <= 1e-10 * fixed.cond_J_beta);
    solve_dependent_accelerations(fixed_model, fixed, s, sdot, sddot, fixed_default);
    generic::solve_dependent_accelerations(model, data, dynamic(s), g_sdot, g_sddot, generic_default);
    REQUIRE(agree(g_sddot, dynamic(sddot)));
    // The bias accelerations: every input acceleration zero (the fixed runtime reads the convective
    // terms the previous call left in its data, at the same s and sdot).
    Coordinates bias;
    Eigen::VectorXd g_bias;
    solve_bias_accelerations(fixed, bias, fixed_default);
    generic::solve_bias_accelerations(model, data, dynamic(s), g_sdot, g_bias, generic_default);
    REQUIRE(agree(g_bias, dynamic(bias)));
    // The rate basis on the inputs that are not the pair's.
    std::vector<int> commanded;
    for (int k = 0; k < kInputCount; ++k)
      if (std::find(fixed_default.index.begin(), fixed_default.index.end(), k) == fixed_default.index.end()) commanded.push_back(k);
    const Eigen::MatrixXd T = generic::rate_basis(model, data, commanded, generic_default);
    // s' = T u: the basis reproduces the velocity level's rates for those inputs' rates.
    Eigen::VectorXd u(static_cast<Eigen::Index>(commanded.size()));
    for (std::size_t c = 0; c < commanded.size(); ++c) u(static_cast<Eigen::Index>(c)) = g_sdot(commanded[c]);
    CHECK(agree(T * u, g_sdot));
    if constexpr (gen::kHasDynamics) {
      const std::vector<int> dynamics_speeds(gen::kCommanded.begin(), gen::kCommanded.end());
      const DependentPair dynamics_pair{gen::kPairs[static_cast<std::size_t>(gen::kDynamicsPair)].coordinates};
      const generic::DependentPair g_dynamics_pair{std::vector<int>(dynamics_pair.index.begin(), dynamics_pair.index.end())};
      Coordinates rates_fixed = sdot;
      Eigen::VectorXd rates = dynamic(sdot);
      if (error_of([&] { solve_dependent_rates(fixed_model, fixed, s, rates_fixed, dynamics_pair); }).empty()) {
        generic::solve_dependent_rates(model, data, dynamic(s), rates, g_dynamics_pair);
        const auto T_fixed = rate_basis(fixed, gen::kCommanded, dynamics_pair);
        CHECK(agree(generic::rate_basis(model, data, dynamics_speeds, g_dynamics_pair), T_fixed));
      }
    }
  }
  if (kWheelCount > 0 || kLimbCount > 0) CHECK(compared > 10);
  // Refusals of what does not fit the model.
  Eigen::VectorXd s = generic::nominal_coordinates(model), sdot = Eigen::VectorXd::Zero(kCoordinateCount);
  CHECK(error_of([&] { generic::solve_dependent_rates(model, data, s, sdot, generic::DependentPair{{0, 0, 0, 0, 0, 0, 0, 0, 0}}); })
            .find("rates for the model's") != std::string::npos);
  CHECK(error_of([&] { generic::condition_number(Eigen::MatrixXd::Zero(2, 3)); }).find("not square") != std::string::npos);
}
