// Pinocchio 3 behind bench/pinocchio_peer.hpp, and its benchmark rows. The only file that includes
// Pinocchio's headers (CMakeLists.txt: WLX_PINOCCHIO_DIR).
#include "pinocchio_peer.hpp"

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/joint/joint-composite.hpp>
#include <pinocchio/parsers/urdf.hpp>

#ifdef WLX_PINOCCHIO_BENCHMARKS
#include <benchmark/benchmark.h>
#endif

#include <random>
#include <stdexcept>

namespace wlx_peer {

namespace {

// The URDF's robot with its root joined as `root` says, and a Data for it.
struct Loaded {
  pinocchio::Model model;
  std::unique_ptr<pinocchio::Data> data;
  Loaded(const std::string& urdf_file, Root root) {
    if (root == Root::free_flyer) {
      pinocchio::urdf::buildModel(urdf_file, pinocchio::JointModelFreeFlyer(), model);
    } else {
      pinocchio::JointModelComposite base;
      base.addJoint(pinocchio::JointModelPX());
      base.addJoint(pinocchio::JointModelPY());
      base.addJoint(pinocchio::JointModelPZ());
      base.addJoint(pinocchio::JointModelRZ());
      base.addJoint(pinocchio::JointModelRY());
      base.addJoint(pinocchio::JointModelRX());
      pinocchio::urdf::buildModel(urdf_file, base, model);
    }
    data = std::make_unique<pinocchio::Data>(model);
  }
};

}  // namespace

struct PinocchioRobot::Impl : Loaded {
  using Loaded::Loaded;
};

PinocchioRobot::PinocchioRobot(const std::string& urdf_file, Root root) : impl_(std::make_unique<Impl>(urdf_file, root)) {}
PinocchioRobot::~PinocchioRobot() = default;

int PinocchioRobot::nv() const { return impl_->model.nv; }
int PinocchioRobot::q_index(const std::string& name) const {
  return impl_->model.existJointName(name) ? impl_->model.idx_qs[impl_->model.getJointId(name)] : -1;
}
int PinocchioRobot::v_index(const std::string& name) const {
  return impl_->model.existJointName(name) ? impl_->model.idx_vs[impl_->model.getJointId(name)] : -1;
}
int PinocchioRobot::q_size(const std::string& name) const {
  return impl_->model.existJointName(name) ? impl_->model.nqs[impl_->model.getJointId(name)] : 0;
}
Eigen::VectorXd PinocchioRobot::neutral() const { return pinocchio::neutral(impl_->model); }

std::vector<Eigen::Matrix<double, 3, 4>> PinocchioRobot::link_placements(const Eigen::VectorXd& q, const std::vector<std::string>& links) {
  pinocchio::framesForwardKinematics(impl_->model, *impl_->data, q);
  std::vector<Eigen::Matrix<double, 3, 4>> out(links.size());
  for (std::size_t k = 0; k < links.size(); ++k) {
    if (!impl_->model.existBodyName(links[k])) throw std::invalid_argument("Pinocchio's model has no link " + links[k]);
    const auto& X = impl_->data->oMf[impl_->model.getBodyId(links[k])];
    out[k].leftCols<3>() = X.rotation();
    out[k].col(3) = X.translation();
  }
  return out;
}

Eigen::VectorXd PinocchioRobot::inverse_dynamics(const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& a) {
  return pinocchio::rnea(impl_->model, *impl_->data, q, v, a);
}

Eigen::MatrixXd PinocchioRobot::joint_jacobians(const Eigen::VectorXd& q) {
  return pinocchio::computeJointJacobians(impl_->model, *impl_->data, q);
}

#ifdef WLX_PINOCCHIO_BENCHMARKS
namespace {

// The robot as Pinocchio users load it (free flyer) at a random state: the neutral configuration
// moved by a random velocity (joint-configuration's integrate keeps the quaternion and the
// continuous joints' (cos, sin) on their manifolds), random rates, accelerations and torques.
struct PeerState : Loaded {
  Eigen::VectorXd q, v, a, tau;
  explicit PeerState(const std::string& urdf) : Loaded(urdf, Root::free_flyer) {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> n(0.0, 0.3);
    const auto random = [&](int size) {
      Eigen::VectorXd x(size);
      for (int i = 0; i < size; ++i) x(i) = n(rng);
      return x;
    };
    q = pinocchio::integrate(model, pinocchio::neutral(model), random(model.nv));
    v = random(model.nv), a = random(model.nv), tau = random(model.nv);
  }
};

}  // namespace

void register_pinocchio_benchmarks(const std::string& model, const std::string& urdf) {
  const auto row = [&](const char* name, void (*body)(PeerState&)) {
    benchmark::RegisterBenchmark((model + "/" + name).c_str(), [urdf, body](benchmark::State& st) {
      PeerState x(urdf);
      for (auto _ : st) body(x);
    });
  };
  row("pinocchio_fk", [](PeerState& x) {
    pinocchio::framesForwardKinematics(x.model, *x.data, x.q);
    benchmark::DoNotOptimize(x.data->oMf.data());
  });
  row("pinocchio_rnea", [](PeerState& x) { benchmark::DoNotOptimize(pinocchio::rnea(x.model, *x.data, x.q, x.v, x.a).data()); });
  row("pinocchio_crba", [](PeerState& x) { benchmark::DoNotOptimize(pinocchio::crba(x.model, *x.data, x.q).data()); });
  row("pinocchio_aba", [](PeerState& x) { benchmark::DoNotOptimize(pinocchio::aba(x.model, *x.data, x.q, x.v, x.tau).data()); });
  row("pinocchio_jacobians",
      [](PeerState& x) { benchmark::DoNotOptimize(pinocchio::computeJointJacobians(x.model, *x.data, x.q).data()); });
}
#endif

}  // namespace wlx_peer
