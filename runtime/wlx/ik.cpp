#include "wlx/ik.hpp"

#include "wlx/error.hpp"
#include "wlx/ik_algorithms.hpp"
#include "wlx/kinematics.hpp"

#include <optional>

WLX_MODEL_NAMESPACE_BEGIN

namespace {

const gen::LimbInfo& info(Limb limb) { return gen::kLimbs[static_cast<std::size_t>(limb)]; }
const gen::ClosedFormInfo& closed_form(Limb limb) { return gen::kClosedForm[static_cast<std::size_t>(limb)]; }

// The joints' ranges and Newton's start values alone, as the algorithms' range checks see them.
struct FixedRanges {
  using Vector = Coordinates;
  int coordinate_count() const { return kCoordinateCount; }
  int input_count() const { return kInputCount; }
  std::string_view coordinate_name(int k) const { return gen::kCoordinateNames[static_cast<std::size_t>(k)]; }
  double lower(int k) const { return settings().lower[static_cast<std::size_t>(k)]; }
  double upper(int k) const { return settings().upper[static_cast<std::size_t>(k)]; }
  double dependent_start(int k) const { return settings().dependent_start[static_cast<std::size_t>(k - kInputCount)]; }
};

// The model as the IK's algorithms see it (wlx/ik_algorithms.hpp): its tables, its settings, the
// generated closed forms and closure, on a Data given or made when Newton's method first needs one.
class FixedIk : public FixedRanges {
 public:
  static constexpr int kLimbSize = gen::kMaxLimbSize;
  static constexpr int kLimbCapacity = kLimbCount;

  explicit FixedIk(const Model& model, Data* data = nullptr) : model_(&model), data_(data) {}

  int limb_count() const { return kLimbCount; }
  IkLimb limb(int l) const {
    const gen::LimbInfo& b = info(l);
    return {b.size, b.rows.data(), b.joints.data(), b.input_count, b.inputs.data()};
  }
  std::string_view limb_title(int l) const { return info(l).title; }
  std::string_view coordinate_unit(int k) const { return gen::kCoordinateUnits[static_cast<std::size_t>(k)]; }
  int default_branch(int l) const { return settings().default_branch[static_cast<std::size_t>(l)]; }
  bool has_closed_form(int l) const { return closed_form(l).solve != nullptr; }
  int closed_form_branches(int l) const { return closed_form(l).branches; }
  std::string_view closed_form_failure(int l, int stage) const { return closed_form(l).failures[static_cast<std::size_t>(stage - 1)]; }
  bool has_fused_ik() const { return gen::kHasFusedIk; }
  ClosedFormStatus solve_limb(int l, int branch, Coordinates& s, ClosedFormFailure& failure) const {
    gen::IkDiagnostics why;
    const gen::IkStatus status = closed_form(l).solve(s, model_->params(), branch, s, why);
    failure = {l, why.stage, why.value, why.low, why.high, why.aux};
    return closed_form_status(status);
  }
  ClosedFormStatus solve_all(const int* branches, Coordinates& s, ClosedFormFailure& failure) const {
    std::array<int, kLimbCount> chosen{};
    std::copy(branches, branches + kLimbCount, chosen.begin());
    int failed = 0;
    gen::IkDiagnostics why;
    const gen::IkStatus status = gen::ik_all(s, model_->params(), chosen, s, failed, why);
    failure = {failed, why.stage, why.value, why.low, why.high, why.aux};
    return closed_form_status(status);
  }
  void evaluate_closure(const Coordinates& s, bool with_jacobian) { closure(*model_, data(), s, with_jacobian); }
  double Phi(int row) const { return data_->Phi(row); }
  double dPhi_ds(int row, int k) const { return data_->dPhi_ds(row, k); }
  bool Phi_finite() const { return data_->Phi.allFinite(); }

 private:
  Data& data() {
    if (data_ == nullptr) data_ = &own_.emplace();  // only Newton's method needs one
    return *data_;
  }
  const Model* model_ = nullptr;
  Data* data_ = nullptr;
  std::optional<Data> own_;
};


}  // namespace

ClosedFormStatus closed_form_status(gen::IkStatus status) noexcept {
  switch (status) {
    case gen::IkStatus::ok: return ClosedFormStatus::ok;
    case gen::IkStatus::out_of_reach: return ClosedFormStatus::out_of_reach;
    case gen::IkStatus::bad_branch: return ClosedFormStatus::bad_branch;
    case gen::IkStatus::residual: break;
  }
  return ClosedFormStatus::residual;
}

LimbBlock limb_block(Limb limb) noexcept {
  const gen::LimbInfo& l = info(limb);
  LimbBlock b;
  b.size = l.size;
  b.rows = l.rows;
  b.joints = l.joints;
  return b;
}

std::string_view limb_name(Limb limb) noexcept { return info(limb).title; }

bool has_closed_form(Limb limb) noexcept { return closed_form(limb).solve != nullptr; }

int branch_count(Limb limb) noexcept {
  const gen::ClosedFormInfo& cf = closed_form(limb);
  return cf.solve == nullptr ? 1 : cf.branches;
}

void solve_limb_closed_form(const Model& model, Limb limb, int branch, Coordinates& s) {
  FixedIk p(model);
  ik_algorithms::solve_limb_closed_form(p, limb, branch, s);
}

bool within_range(const Coordinates& s, int k) noexcept { return ik_algorithms::within_range(FixedRanges{}, s, k); }

int first_outside_limits(const Coordinates& s) noexcept { return ik_algorithms::first_outside_limits(FixedRanges{}, s); }

std::string describe_outside_limits(const Coordinates& s, int k) { return ik_algorithms::describe_outside_limits(FixedRanges{}, s, k); }

Branches resolve_branches(const Model& model, const Coordinates& s, const Branches& requested, std::array<bool, kLimbCount>* outside) {
  Branches out = requested;
  FixedIk p(model);
  ik_algorithms::resolve_branches(p, s, out.limb, outside);
  return out;
}

void solve_ik_closed_form(const Model& model, Coordinates& s, const Branches& requested, NewtonReport* newton_report,
                          const NewtonOptions* newton_options) {
  if (newton_report != nullptr) *newton_report = NewtonReport{};  // nothing stale if a limb fails
  FixedIk p(model);
  const auto progress = ik_algorithms::solve_ik_closed_form(p, s, requested.limb, newton_options);
  if (newton_report != nullptr) ik_algorithms::fill_report(p, progress, *newton_report);
}

int classify_branch(const Model& model, Limb limb, const Coordinates& s) {
  FixedIk p(model);
  return ik_algorithms::classify_branch(p, limb, s);
}

Coordinates dependent_start(Coordinates s) { return ik_algorithms::dependent_start(FixedRanges{}, s); }

NewtonReport solve_newton_limbs(const Model& model, Data& data, const std::array<bool, kLimbCount>& limbs, Coordinates& s,
                                const NewtonOptions& options) {
  FixedIk p(model, &data);
  NewtonReport report;
  ik_algorithms::fill_report(p, ik_algorithms::solve_newton_limbs(p, limbs, s, options), report);
  return report;
}

NewtonReport solve_ik_newton(const Model& model, Data& data, Coordinates& s, const NewtonOptions& options) {
  std::array<bool, kLimbCount> all;
  all.fill(true);
  FixedIk p(model, &data);
  NewtonReport report;
  ik_algorithms::fill_report(p, ik_algorithms::newton(p, all, s, options), report);
  return report;
}

NewtonReport solve_limb_newton(const Model& model, Data& data, Limb limb, Coordinates& s, const NewtonOptions& options) {
  std::array<bool, kLimbCount> active{};
  active[static_cast<std::size_t>(limb)] = true;
  FixedIk p(model, &data);
  NewtonReport report;
  ik_algorithms::fill_report(p, ik_algorithms::newton(p, active, s, options), report);
  return report;
}

WLX_MODEL_NAMESPACE_END
