// The wheels' dependent rates at run-time sizes: the same algorithms as the model's own runtime
// (wlx/rate_algorithms.hpp; wlx/nonholonomic.hpp says what each function computes), on the
// model's generated rolling rows and convective terms.
#pragma once

#include "wlx/generic/model.hpp"
#include "wlx/ik_options.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace wlx::generic {

// The input rates, one per wheel, that the wheels' rolling determines (their coordinates).
struct DependentPair {
  std::vector<int> index;
};
// "(y_C', yaw')".
std::string pair_label(const Model& model, const DependentPair& pair);
// From the rates' names (one per wheel, each a candidate, all different); wlx::Error naming `field`.
DependentPair dependent_pair(const Model& model, const std::vector<std::string>& names, const std::string& field = "dependent");
// A pair the model names ("A"); wlx::Error naming `field` when there is none.
DependentPair named_pair(const Model& model, std::string_view name, const std::string& field = "dependent");
DependentPair default_pair(const Model& model);

// sigma_max / sigma_min of J_beta (infinity for a singular one; 1 without wheels).
double condition_number(const Eigen::MatrixXd& J);

// Velocity level: the pair's and the dependent joints' rates in sdot from the commanded input rates
// in it; data's J_beta, its factorization and condition. wlx::Error for a singular J_beta.
void solve_dependent_rates(const Model& model, Data& data, const Eigen::VectorXd& s, Eigen::VectorXd& sdot,
                           const DependentPair& pair, const NonholonomicOptions& options = {});
// Acceleration level, after solve_dependent_rates at the same (s, sdot): the pair's and the
// dependent joints' accelerations in sddot from the commanded input accelerations in it.
void solve_dependent_accelerations(const Model& model, Data& data, const Eigen::VectorXd& s, const Eigen::VectorXd& sdot,
                                   Eigen::VectorXd& sddot, const DependentPair& pair);
// The same with every input acceleration zero (the inverse dynamics' s''_bias): overwrites sddot.
void solve_bias_accelerations(const Model& model, Data& data, const Eigen::VectorXd& s, const Eigen::VectorXd& sdot,
                              Eigen::VectorXd& sddot, const DependentPair& pair);
// After solve_dependent_rates (same pair): s' = T u for unit rates of the `commanded` inputs.
Eigen::MatrixXd rate_basis(const Model& model, Data& data, const std::vector<int>& commanded, const DependentPair& pair);

}  // namespace wlx::generic
