// Inverse kinematics at run-time sizes: the model's generated closed forms (its ModelCode) and
// Newton's method on its generated closure, by the same algorithms as the model's own runtime
// (wlx/ik_algorithms.hpp; wlx/ik.hpp says what each function does). A limb without a closed form
// is solved by Newton's method wherever the closed form is asked for.
#pragma once

#include "wlx/generic/model.hpp"
#include "wlx/ik_options.hpp"

#include <string>
#include <vector>

namespace wlx::generic {

// Per limb, the branch its closed form takes; kModelsChoice (or an empty list: every limb) leaves
// it to the model (resolve_branches).
using Branches = std::vector<int>;

struct NewtonReport {
  std::vector<int> iterations;  // per limb
  double residual = 0;          // max |Phi| over the solved limbs' equations at the end
  bool converged = false;
};

bool has_closed_form(const Model& model, int limb);
int branch_count(const Model& model, int limb);

// The model's start: its nominal inputs and the dependent joints at Newton's start values.
Eigen::VectorXd nominal_coordinates(const Model& model);
// s with its dependent joints at the model's start values for Newton's method.
Eigen::VectorXd dependent_start(const Model& model, Eigen::VectorXd s);

Branches resolve_branches(const Model& model, Data& data, const Eigen::VectorXd& s, const Branches& requested = {},
                          std::vector<bool>* outside = nullptr);
void solve_limb_closed_form(const Model& model, Data& data, int limb, int branch, Eigen::VectorXd& s);
void solve_ik_closed_form(const Model& model, Data& data, Eigen::VectorXd& s, const Branches& branches = {},
                          NewtonReport* newton = nullptr, const NewtonOptions* newton_options = nullptr);
int classify_branch(const Model& model, Data& data, int limb, const Eigen::VectorXd& s);

NewtonReport solve_ik_newton(const Model& model, Data& data, Eigen::VectorXd& s, const NewtonOptions& options = {});
NewtonReport solve_newton_limbs(const Model& model, Data& data, const std::vector<bool>& limbs, Eigen::VectorXd& s,
                                const NewtonOptions& options = {});
NewtonReport solve_limb_newton(const Model& model, Data& data, int limb, Eigen::VectorXd& s, const NewtonOptions& options = {});

// The joints' ranges (wlx/ik.hpp). wlx::Error for an s of another size or a k out of range.
bool within_range(const Model& model, const Eigen::VectorXd& s, int k);
int first_outside_limits(const Model& model, const Eigen::VectorXd& s);
std::string describe_outside_limits(const Model& model, const Eigen::VectorXd& s, int k);

}  // namespace wlx::generic
