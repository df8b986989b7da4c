// Inertial local bundle adjustment: the visual BA's window and solver (local_bundle_adjustment.hpp,
// bundle_adjustment_solver.hpp) with the IMU and bias random walk factors as extra terms.
// GCC 12 with -march=native (AVX-512) reports Eigen's vectorised quaternion reductions as "may be used
// uninitialized": a known false positive (bundle_adjustment_terms.cpp).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "components/core/mapping/inertial_bundle_adjustment.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "components/core/imu/so3.hpp"
#include "components/core/map/ids.hpp"

namespace heslam {
namespace {

// d(Plus(x, (w, 0)))/dw at w = 0 for PoseManifold's quaternion (x y z w): Exp(w) q = q + 0.5 (w, 0) * q.
Eigen::Matrix<double, 4, 3> quaternion_plus_jacobian(const double* q) {
  const Eigen::Vector3d v(q[0], q[1], q[2]);
  const double w = q[3];
  Eigen::Matrix3d skew_v;
  skew_v << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  Eigen::Matrix<double, 4, 3> J;
  J.topRows<3>() = 0.5 * (w * Eigen::Matrix3d::Identity() - skew_v);
  J.row(3) = -0.5 * v.transpose();
  return J;
}

// The IMU terms of the window as the solver's extra terms. Own parameters, in this order: per chain
// keyframe whose state is free, (v_wb, bg, ba) (9), then, when estimated, gravity's direction (2: a
// rotation of g about two axes orthogonal to it, so its magnitude stays). Residuals: per interval the IMU
// factor (ImuCameraCost, on the solver's camera poses) and the bias random walk; gravity's prior.
class InertialTerms : public BundleAdjustmentExtraTerms {
 public:
  InertialTerms(const InertialWindow& window, std::vector<std::size_t> chain_poses)
      : poses_(std::move(chain_poses)), gravity_(window.gravity_w), gravity_prior_(window.gravity_w) {
    const std::size_t n = window.chain.size();
    states_.resize(n);
    offsets_.assign(n, -1);
    int next = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const InertialKeyframeState& state = window.states.at(window.chain[k]);
      states_[k] << state.v_wb, state.bias.gyro_rad_s, state.bias.accel_m_s2;
      if (k > 0 || !window.hold_anchor) {
        offsets_[k] = next;
        next += 9;
      }
    }
    for (std::size_t k = 0; k + 1 < n; ++k) {
      imu_.push_back(std::make_unique<ImuCameraCost>(window.intervals[k], window.T_cb));
      const Eigen::Matrix<double, 6, 6> walk = window.intervals[k].bias_random_walk_covariance();
      if (!(walk(0, 0) > 0.0) || !(walk(3, 3) > 0.0)) {
        throw std::invalid_argument(
            "inertial_local_bundle_adjustment: interval " + std::to_string(k) +
            ": expected positive bias random walks and duration (gyro_random_walk, accel_random_walk)");
      }
      walk_inv_sigma_.emplace_back(1.0 / std::sqrt(walk(0, 0)), 1.0 / std::sqrt(walk(3, 3)));
    }
    if (window.gravity_stddev_rad > 0.0) {
      gravity_offset_ = next;
      next += 2;
      gravity_inv_sigma_ = 1.0 / (window.gravity_w.norm() * window.gravity_stddev_rad);
      update_gravity_basis();
    }
    dimension_ = next;
  }

  int dimension() const override { return dimension_; }

  double cost(const std::vector<PoseBlock>& poses, const Eigen::VectorXd* step) const override {
    std::vector<Vector9> states = states_;
    Eigen::Vector3d gravity = gravity_;
    if (step != nullptr) moved(*step, states, gravity);
    double sum = 0.0;
    for (std::size_t k = 0; k < imu_.size(); ++k) {
      Eigen::Matrix<double, 9, 1> r;
      const double* parameters[7] = {
          poses[poses_[k]].data(),     states[k].data(),     states[k].data() + 3, states[k].data() + 6,
          poses[poses_[k + 1]].data(), states[k + 1].data(), gravity.data()};
      if (!imu_[k]->Evaluate(parameters, r.data(), nullptr)) return std::numeric_limits<double>::infinity();
      sum += r.squaredNorm();
      sum += walk_residual(k, states).squaredNorm();
    }
    if (gravity_offset_ >= 0) sum += ((gravity - gravity_prior_) * gravity_inv_sigma_).squaredNorm();
    return 0.5 * sum;
  }

  void linearise(const std::vector<PoseBlock>& poses, const std::vector<int>& free_index, Eigen::MatrixXd& H,
                 Eigen::VectorXd& b) const override {
    const int base = static_cast<int>(H.rows()) - dimension_;
    // Columns of one term: (offset in the reduced system, Jacobian block).
    std::vector<std::pair<int, Eigen::MatrixXd>> blocks;
    const auto add = [&](const Eigen::VectorXd& r) {
      for (const auto& [oa, Ja] : blocks) {
        b.segment(oa, Ja.cols()).noalias() -= Ja.transpose() * r;
        for (const auto& [ob, Jb] : blocks) H.block(oa, ob, Ja.cols(), Jb.cols()).noalias() += Ja.transpose() * Jb;
      }
    };
    const Eigen::Matrix<double, 3, 2> dg = -so3::hat(gravity_) * gravity_basis_;  // d(Exp(B d) g)/dd at 0
    for (std::size_t k = 0; k < imu_.size(); ++k) {
      Eigen::Matrix<double, 9, 1> r;
      Eigen::Matrix<double, 9, 7, Eigen::RowMajor> J_pose_i, J_pose_j;
      Eigen::Matrix<double, 9, 3, Eigen::RowMajor> J_v_i, J_bg_i, J_ba_i, J_v_j, J_g;
      const double* parameters[7] = {poses[poses_[k]].data(), states_[k].data(),           states_[k].data() + 3,
                                     states_[k].data() + 6,   poses[poses_[k + 1]].data(), states_[k + 1].data(),
                                     gravity_.data()};
      double* jacobians[7] = {J_pose_i.data(), J_v_i.data(), J_bg_i.data(), J_ba_i.data(),
                              J_pose_j.data(), J_v_j.data(), J_g.data()};
      imu_[k]->Evaluate(parameters, r.data(), jacobians);
      blocks.clear();
      const int fi = free_index[poses_[k]];
      const int fj = free_index[poses_[k + 1]];
      if (fi >= 0) blocks.emplace_back(6 * fi, J_pose_i.leftCols<6>());
      if (fj >= 0) blocks.emplace_back(6 * fj, J_pose_j.leftCols<6>());
      if (offsets_[k] >= 0) {
        Eigen::Matrix<double, 9, 9> J_state;
        J_state << J_v_i, J_bg_i, J_ba_i;
        blocks.emplace_back(base + offsets_[k], J_state);
      }
      if (offsets_[k + 1] >= 0) blocks.emplace_back(base + offsets_[k + 1], J_v_j);
      if (gravity_offset_ >= 0) blocks.emplace_back(base + gravity_offset_, J_g * dg);
      add(r);
      // The bias random walk: (bg_j - bg_i, ba_j - ba_i), whitened.
      blocks.clear();
      Eigen::Matrix<double, 6, 6> J_walk = Eigen::Matrix<double, 6, 6>::Zero();
      J_walk.diagonal() << Eigen::Vector3d::Constant(walk_inv_sigma_[k].first),
          Eigen::Vector3d::Constant(walk_inv_sigma_[k].second);
      if (offsets_[k] >= 0) {
        Eigen::Matrix<double, 6, 9> J_i = Eigen::Matrix<double, 6, 9>::Zero();
        J_i.rightCols<6>() = -J_walk;
        blocks.emplace_back(base + offsets_[k], J_i);
      }
      if (offsets_[k + 1] >= 0) {
        Eigen::Matrix<double, 6, 9> J_j = Eigen::Matrix<double, 6, 9>::Zero();
        J_j.rightCols<6>() = J_walk;
        blocks.emplace_back(base + offsets_[k + 1], J_j);
      }
      add(walk_residual(k, states_));
    }
    if (gravity_offset_ >= 0) {
      blocks.clear();
      blocks.emplace_back(base + gravity_offset_, gravity_inv_sigma_ * dg);
      add((gravity_ - gravity_prior_) * gravity_inv_sigma_);
    }
  }

  void update(const Eigen::VectorXd& step) override {
    moved(step, states_, gravity_);
    if (gravity_offset_ >= 0) update_gravity_basis();
  }

  double squared_norm() const override {
    double sum = 0.0;
    for (std::size_t k = 0; k < states_.size(); ++k) {
      if (offsets_[k] >= 0) sum += states_[k].squaredNorm();
    }
    if (gravity_offset_ >= 0) sum += gravity_.squaredNorm();
    return sum;
  }

  // The state of chain keyframe k (v_wb, bg, ba) and gravity, as they are.
  const Eigen::Matrix<double, 9, 1>& state(std::size_t k) const { return states_[k]; }
  const Eigen::Vector3d& gravity() const { return gravity_; }

 private:
  using Vector9 = Eigen::Matrix<double, 9, 1>;

  void moved(const Eigen::VectorXd& step, std::vector<Vector9>& states, Eigen::Vector3d& gravity) const {
    for (std::size_t k = 0; k < states.size(); ++k) {
      if (offsets_[k] >= 0) states[k] += step.segment<9>(offsets_[k]);
    }
    if (gravity_offset_ >= 0) gravity = so3::exp(gravity_basis_ * step.segment<2>(gravity_offset_)) * gravity;
  }

  Eigen::Matrix<double, 6, 1> walk_residual(std::size_t k, const std::vector<Vector9>& states) const {
    Eigen::Matrix<double, 6, 1> r;
    r.head<3>() = (states[k + 1].segment<3>(3) - states[k].segment<3>(3)) * walk_inv_sigma_[k].first;
    r.tail<3>() = (states[k + 1].segment<3>(6) - states[k].segment<3>(6)) * walk_inv_sigma_[k].second;
    return r;
  }

  // Two unit axes orthogonal to gravity: rotations about them tilt it.
  void update_gravity_basis() {
    const Eigen::Vector3d u = gravity_.normalized();
    const Eigen::Vector3d seed = std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d a = u.cross(seed).normalized();
    gravity_basis_.col(0) = a;
    gravity_basis_.col(1) = u.cross(a);
  }

  std::vector<std::size_t> poses_;  // the problem's pose of each chain keyframe
  std::vector<Vector9> states_;
  std::vector<int> offsets_;  // of each chain keyframe's state in the own parameters; -1: held
  std::vector<std::unique_ptr<ImuCameraCost>> imu_;
  std::vector<std::pair<double, double>> walk_inv_sigma_;  // gyro, accel
  Eigen::Vector3d gravity_;
  Eigen::Vector3d gravity_prior_;
  Eigen::Matrix<double, 3, 2> gravity_basis_ = Eigen::Matrix<double, 3, 2>::Zero();
  double gravity_inv_sigma_ = 0.0;
  int gravity_offset_ = -1;
  int dimension_ = 0;
};

}  // namespace

ImuCameraCost::ImuCameraCost(const ImuPreintegration& preintegration, const Pose3& T_cb)
    : autodiff_(new Functor{ImuIntervalResidual(preintegration), T_cb.linear(), T_cb.translation()}) {}

bool ImuCameraCost::Evaluate(const double* const* parameters, double* residuals, double** jacobians) const {
  if (jacobians == nullptr) return autodiff_.Evaluate(parameters, residuals, nullptr);
  // Ambient (quaternion) Jacobians from autodiff, then chained with PoseManifold's Plus at zero.
  Eigen::Matrix<double, 9, 7, Eigen::RowMajor> ambient_i, ambient_j;
  double* inner[7] = {jacobians[0] != nullptr ? ambient_i.data() : nullptr, jacobians[1], jacobians[2], jacobians[3],
                      jacobians[4] != nullptr ? ambient_j.data() : nullptr, jacobians[5], jacobians[6]};
  if (!autodiff_.Evaluate(parameters, residuals, inner)) return false;
  for (const int block : {0, 4}) {
    if (jacobians[block] == nullptr) continue;
    const auto& ambient = block == 0 ? ambient_i : ambient_j;
    Eigen::Map<Eigen::Matrix<double, 9, 7, Eigen::RowMajor>> J(jacobians[block]);
    J.leftCols<3>() = ambient.leftCols<4>() * quaternion_plus_jacobian(parameters[block]);
    J.middleCols<3>(3) = ambient.middleCols<3>(4);
    J.col(6).setZero();
  }
  return true;
}

InertialBundleAdjustmentResult inertial_local_bundle_adjustment(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                                const LocalBundleAdjustmentOptions& options,
                                                                InertialWindow& window, MapChanges& changes) {
  InertialBundleAdjustmentResult result;
  if (window.chain.size() < 2 || window.intervals.size() + 1 != window.chain.size()) {
    throw std::invalid_argument("inertial_local_bundle_adjustment: " + std::to_string(window.chain.size()) +
                                " chain keyframes and " + std::to_string(window.intervals.size()) +
                                " intervals (expected at least 2 and one fewer)");
  }
  for (const KeyframeId id : window.chain) {
    const Keyframe* chain_kf = map.keyframe(id);
    if (chain_kf == nullptr || chain_kf->culled || window.states.count(id) == 0) {
      throw std::invalid_argument("inertial_local_bundle_adjustment: chain keyframe " + format_id(id) +
                                  (window.states.count(id) == 0 ? " has no inertial state" : " is not in the map"));
    }
  }
  // The visual window with the chain's keyframes free, its oldest (the anchor) held.
  const std::vector<KeyframeId> chain_free(window.chain.begin() + 1, window.chain.end());
  LocalBundleAdjustmentWindow visual(map, kf_id, camera, options, chain_free, {window.chain.front()});
  result.visual = visual.result();
  if (!visual.solvable()) return result;
  std::vector<std::size_t> chain_poses;
  for (const KeyframeId id : window.chain) chain_poses.push_back(visual.pose_index(id));
  InertialTerms terms(window, chain_poses);
  result.imu_factors = static_cast<int>(window.intervals.size());
  result.inertial_keyframes = static_cast<int>(window.chain.size()) - (window.hold_anchor ? 1 : 0);
  visual.solve(&terms);
  result.initial_cost = visual.initial_cost();
  result.final_cost = visual.final_cost();
  bool usable = visual.finite() && terms.gravity().allFinite();
  for (std::size_t k = 0; k < window.chain.size(); ++k) usable = usable && terms.state(k).allFinite();
  if (!usable) {
    result.visual = visual.result();
    return result;  // nothing written back: the caller falls back to the visual BA
  }
  result.solved = true;
  for (std::size_t k = window.hold_anchor ? 1 : 0; k < window.chain.size(); ++k) {
    InertialKeyframeState& state = window.states.at(window.chain[k]);
    const Eigen::Matrix<double, 9, 1>& x = terms.state(k);
    state.v_wb = x.head<3>();
    state.bias.gyro_rad_s = x.segment<3>(3);
    state.bias.accel_m_s2 = x.tail<3>();
  }
  if (window.gravity_stddev_rad > 0.0) window.gravity_w = terms.gravity();
  visual.write_back(changes);
  result.visual = visual.result();
  return result;
}

}  // namespace heslam
