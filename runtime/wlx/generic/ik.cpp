#include "wlx/generic/ik.hpp"

#include "wlx/error.hpp"
#include "wlx/ik_algorithms.hpp"

#include <fmt/format.h>

#include <type_traits>
#include <utility>

namespace wlx::generic {

namespace {

// The joints' ranges alone, as the algorithms' range checks see them.
struct Ranges {
  using Vector = Eigen::VectorXd;
  const Description& d;
  int coordinate_count() const { return d.coordinate_count(); }
  std::string_view coordinate_name(int k) const { return d.coordinates[static_cast<std::size_t>(k)].name; }
  double lower(int k) const { return d.settings.lower[static_cast<std::size_t>(k)]; }
  double upper(int k) const { return d.settings.upper[static_cast<std::size_t>(k)]; }
};

// The model as the IK's algorithms see it (wlx/ik_algorithms.hpp), N its largest limb's size: its
// description, and its code on data's workspace.
template <int N>
class GenericIk : public Ranges {
 public:
  static constexpr int kLimbSize = N;
  static constexpr int kLimbCapacity = kMaxLimbs;

  GenericIk(const Model& model, Data& data)
      : Ranges{model.description()}, d_(model.description()), code_(model.code()), data_(data), workspace_(data.workspace(model)) {}

  int limb_count() const { return static_cast<int>(d_.limbs.size()); }
  int input_count() const { return d_.input_count; }
  IkLimb limb(int l) const {
    const Limb& b = d_.limbs[static_cast<std::size_t>(l)];
    return {static_cast<int>(b.joints.size()), b.rows.data(), b.joints.data(), static_cast<int>(b.inputs.size()), b.inputs.data()};
  }
  std::string_view limb_title(int l) const { return d_.limbs[static_cast<std::size_t>(l)].title; }
  std::string_view coordinate_unit(int k) const { return d_.coordinates[static_cast<std::size_t>(k)].unit; }
  double dependent_start(int k) const { return d_.settings.dependent_start[static_cast<std::size_t>(k)]; }
  int default_branch(int l) const { return d_.settings.default_branch[static_cast<std::size_t>(l)]; }
  bool has_closed_form(int l) const { return code_.closed_forms[l].exists; }
  int closed_form_branches(int l) const { return code_.closed_forms[l].branches; }
  std::string_view closed_form_failure(int l, int stage) const { return code_.closed_forms[l].failures[stage - 1]; }
  bool has_fused_ik() const {
    for (int l = 0; l < limb_count(); ++l)
      if (!has_closed_form(l)) return false;
    return true;
  }
  ClosedFormStatus solve_limb(int l, int branch, Vector& s, ClosedFormFailure& failure) {
    data_.set_coordinates(s);
    const ClosedFormStatus status = code_.ik_limb(workspace_, l, branch, &failure);
    data_.get_coordinates(s);
    return status;
  }
  ClosedFormStatus solve_all(const int* branches, Vector& s, ClosedFormFailure& failure) {
    std::copy(branches, branches + limb_count(), data_.arrays().branches);
    data_.set_coordinates(s);
    const ClosedFormStatus status = code_.ik_all(workspace_, &failure);
    data_.get_coordinates(s);
    return status;
  }
  void evaluate_closure(const Vector& s, bool with_jacobian) {
    data_.set_coordinates(s);
    code_.closure(workspace_, with_jacobian);
  }
  double Phi(int row) const { return data_.arrays().Phi[row]; }
  double dPhi_ds(int row, int k) const { return data_.arrays().dPhi_ds[row + static_cast<std::ptrdiff_t>(k) * code_.closure_rows]; }
  bool Phi_finite() const { return data_.Phi.allFinite(); }

 private:
  const Description& d_;
  const ModelCode& code_;
  Data& data_;
  void* workspace_;
};

// Calls f(GenericIk<N>&) with N the model's largest limb's size: the limb steps are compiled for
// each size a description may have (1 to kMaxLimbSize), as the model's own runtime compiles its one.
template <class F>
decltype(auto) with_problem(const Model& model, Data& data, F&& f) {
  static_assert(kMaxLimbSize == 8, "a case per limb size below");
  const int n = model.description().max_limb_size();
  const auto at = [&]<int N>(std::integral_constant<int, N>) -> decltype(auto) {
    GenericIk<N> p(model, data);
    return f(p);
  };
  switch (n) {
    case 1: return at(std::integral_constant<int, 1>{});
    case 2: return at(std::integral_constant<int, 2>{});
    case 3: return at(std::integral_constant<int, 3>{});
    case 4: return at(std::integral_constant<int, 4>{});
    case 5: return at(std::integral_constant<int, 5>{});
    case 6: return at(std::integral_constant<int, 6>{});
    case 7: return at(std::integral_constant<int, 7>{});
    case 8: return at(std::integral_constant<int, 8>{});
    default: break;
  }
  // The description's reader refuses such limbs; a description made in code may still hold one.
  throw Error("limbs", fmt::format("a limb of {} joints; this runtime solves limbs of 1 to {}", n, kMaxLimbSize));
}

using Flags = std::array<bool, static_cast<std::size_t>(kMaxLimbs)>;
using BranchArray = std::array<int, static_cast<std::size_t>(kMaxLimbs)>;

BranchArray branch_array(const Model& model, const Branches& requested) {
  const std::size_t limbs = model.description().limbs.size();
  if (!requested.empty() && requested.size() != limbs)
    throw Error("branch", fmt::format("{} branches for the model's {} limbs", requested.size(), limbs));
  BranchArray out;
  out.fill(kModelsChoice);
  std::copy(requested.begin(), requested.end(), out.begin());
  return out;
}

Flags flags(const Model& model, const std::vector<bool>& limbs) {
  if (limbs.size() != model.description().limbs.size())
    throw Error("limbs", fmt::format("{} flags for the model's {} limbs", limbs.size(), model.description().limbs.size()));
  Flags out{};
  std::copy(limbs.begin(), limbs.end(), out.begin());
  return out;
}

template <class P>
NewtonReport report_of(const P& p, const ik_algorithms::NewtonProgress<P>& progress) {
  NewtonReport report;
  report.iterations.assign(static_cast<std::size_t>(p.limb_count()), 0);
  ik_algorithms::fill_report(p, progress, report);
  return report;
}


void check_limb(const Model& model, int limb) {
  if (limb < 0 || limb >= static_cast<int>(model.description().limbs.size()))
    throw Error("limb", fmt::format("no limb {} (the model has {})", limb, model.description().limbs.size()));
}


}  // namespace

bool has_closed_form(const Model& model, int limb) {
  check_limb(model, limb);
  return model.code().closed_forms[limb].exists;
}

int branch_count(const Model& model, int limb) {
  check_limb(model, limb);
  const ModelCodeClosedForm& cf = model.code().closed_forms[limb];
  return cf.exists ? cf.branches : 1;
}

Eigen::VectorXd nominal_coordinates(const Model& model) {
  const Settings& s = model.description().settings;
  Eigen::VectorXd out = Eigen::Map<const Eigen::VectorXd>(s.dependent_start.data(), model.description().coordinate_count());
  out.head(model.description().input_count) = Eigen::Map<const Eigen::VectorXd>(s.nominal_inputs.data(), model.description().input_count);
  return out;
}

Eigen::VectorXd dependent_start(const Model& model, Eigen::VectorXd s) {
  check_coordinate_count(model, s);
  const Description& d = model.description();
  for (int k = d.input_count; k < d.coordinate_count(); ++k) s(k) = d.settings.dependent_start[static_cast<std::size_t>(k)];
  return s;
}

Branches resolve_branches(const Model& model, Data& data, const Eigen::VectorXd& s, const Branches& requested, std::vector<bool>* outside) {
  check_coordinate_count(model, s);
  BranchArray chosen = branch_array(model, requested);
  Flags leaves{};
  with_problem(model, data, [&](auto& p) { ik_algorithms::resolve_branches(p, s, chosen, outside != nullptr ? &leaves : nullptr); });
  const std::size_t limbs = model.description().limbs.size();
  if (outside != nullptr) outside->assign(leaves.begin(), leaves.begin() + static_cast<std::ptrdiff_t>(limbs));
  return Branches(chosen.begin(), chosen.begin() + static_cast<std::ptrdiff_t>(limbs));
}

void solve_limb_closed_form(const Model& model, Data& data, int limb, int branch, Eigen::VectorXd& s) {
  check_limb(model, limb);
  check_coordinate_count(model, s);
  with_problem(model, data, [&](auto& p) { ik_algorithms::solve_limb_closed_form(p, limb, branch, s); });
}

void solve_ik_closed_form(const Model& model, Data& data, Eigen::VectorXd& s, const Branches& branches, NewtonReport* newton,
                          const NewtonOptions* newton_options) {
  check_coordinate_count(model, s);
  const BranchArray chosen = branch_array(model, branches);
  with_problem(model, data, [&](auto& p) {
    const auto progress = ik_algorithms::solve_ik_closed_form(p, s, chosen, newton_options);
    if (newton != nullptr) *newton = report_of(p, progress);
  });
}

int classify_branch(const Model& model, Data& data, int limb, const Eigen::VectorXd& s) {
  check_limb(model, limb);
  check_coordinate_count(model, s);
  return with_problem(model, data, [&](auto& p) { return ik_algorithms::classify_branch(p, limb, s); });
}

NewtonReport solve_newton_limbs(const Model& model, Data& data, const std::vector<bool>& limbs, Eigen::VectorXd& s,
                                const NewtonOptions& options) {
  check_coordinate_count(model, s);
  const Flags active = flags(model, limbs);
  return with_problem(model, data, [&](auto& p) { return report_of(p, ik_algorithms::solve_newton_limbs(p, active, s, options)); });
}

NewtonReport solve_ik_newton(const Model& model, Data& data, Eigen::VectorXd& s, const NewtonOptions& options) {
  check_coordinate_count(model, s);
  Flags all{};
  std::fill(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(model.description().limbs.size()), true);
  return with_problem(model, data, [&](auto& p) { return report_of(p, ik_algorithms::newton(p, all, s, options)); });
}

NewtonReport solve_limb_newton(const Model& model, Data& data, int limb, Eigen::VectorXd& s, const NewtonOptions& options) {
  check_limb(model, limb);
  check_coordinate_count(model, s);
  Flags active{};
  active[static_cast<std::size_t>(limb)] = true;
  return with_problem(model, data, [&](auto& p) { return report_of(p, ik_algorithms::newton(p, active, s, options)); });
}

namespace {
void check_coordinate(const Model& model, int k) {
  if (k < 0 || k >= model.description().coordinate_count())
    throw Error("coordinate", fmt::format("no coordinate {} (the model has {})", k, model.description().coordinate_count()));
}
}  // namespace

bool within_range(const Model& model, const Eigen::VectorXd& s, int k) {
  check_coordinate_count(model, s);
  check_coordinate(model, k);
  return ik_algorithms::within_range(Ranges{model.description()}, s, k);
}

int first_outside_limits(const Model& model, const Eigen::VectorXd& s) {
  check_coordinate_count(model, s);
  return ik_algorithms::first_outside_limits(Ranges{model.description()}, s);
}

std::string describe_outside_limits(const Model& model, const Eigen::VectorXd& s, int k) {
  check_coordinate_count(model, s);
  check_coordinate(model, k);
  return ik_algorithms::describe_outside_limits(Ranges{model.description()}, s, k);
}

}  // namespace wlx::generic
