// Motion-only optimization with IMU factors (inertial_pose_optimization.hpp), with Ceres.
#include "components/core/tracking/inertial_pose_optimization.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Geometry>

#include "components/core/imu/imu_factor.hpp"
#include "components/core/tracking/optimize_frame.hpp"

namespace heslam {
namespace {

// As optimize_pose(): fewer residuals than this and another round cannot classify anything reliably.
constexpr int kMinEdgesToContinue = 10;
constexpr double kMinDepthM = 1e-9;

// One observation's whitened reprojection (2 mono, 3 stereo residuals) at the body pose (q_wb, p_wb).
class BodyReprojection {
 public:
  BodyReprojection(const PinholeStereo& camera, const PoseObservation& obs, const Pose3& T_bc,
                   double disparity_sigma_ratio)
      : camera_(camera), obs_(obs), R_bc_(T_bc.rotation()), p_bc_(T_bc.translation()) {
    sqrt_info_ = std::sqrt(obs.inv_sigma2);
    disparity_sqrt_info_ = sqrt_info_ / (disparity_sigma_ratio * obs.disparity_sigma_scale);
  }

  template <typename T>
  bool operator()(const T* q_wb, const T* p_wb, T* residual) const {
    using Vector3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Quaternion<T> q = Eigen::Map<const Eigen::Quaternion<T>>(q_wb).normalized();
    const Eigen::Matrix<T, 3, 3> R_wc = q.toRotationMatrix() * R_bc_.cast<T>();
    const Vector3 p_wc = q * p_bc_.cast<T>() + Eigen::Map<const Vector3>(p_wb);
    const Vector3 p_c = R_wc.transpose() * (obs_.p_w.cast<T>() - p_wc);
    const int rows = obs_.stereo() ? 3 : 2;
    if (!(p_c.z() > T(kMinDepthM))) {
      for (int k = 0; k < rows; ++k) residual[k] = T(0.0);  // unusable at this pose, as optimize_pose()
      return true;
    }
    const T inv_z = T(1.0) / p_c.z();
    residual[0] = (T(camera_.fx_px) * p_c.x() * inv_z + T(camera_.cx_px) - T(obs_.u_px)) * T(sqrt_info_);
    residual[1] = (T(camera_.fy_px) * p_c.y() * inv_z + T(camera_.cy_px) - T(obs_.v_px)) * T(sqrt_info_);
    if (obs_.stereo()) {
      residual[2] = (T(camera_.bf()) * inv_z - T(obs_.u_px - obs_.u_right_px)) * T(disparity_sqrt_info_);
    }
    return true;
  }

  static ceres::CostFunction* create(const PinholeStereo& camera, const PoseObservation& obs, const Pose3& T_bc,
                                     double disparity_sigma_ratio) {
    auto* functor = new BodyReprojection(camera, obs, T_bc, disparity_sigma_ratio);
    if (obs.stereo()) return new ceres::AutoDiffCostFunction<BodyReprojection, 3, 4, 3>(functor);
    return new ceres::AutoDiffCostFunction<BodyReprojection, 2, 4, 3>(functor);
  }

 private:
  const PinholeStereo& camera_;
  const PoseObservation& obs_;
  Eigen::Matrix3d R_bc_;
  Eigen::Vector3d p_bc_;
  double sqrt_info_ = 1.0;
  double disparity_sqrt_info_ = 1.0;
};

// The previous state's prior carried into the IMU factor: its covariance mapped through the factor's
// Jacobians with respect to that state (rotation, velocity, position order). The rotation's coupling into
// the velocity and position rows (through R_i^T) is left out: below a millimetre at a frame's interval.
Matrix9d previous_state_covariance(const InertialPoseConstraint& c) {
  const double t = c.preintegration.duration_s();
  const double var_R = c.prior_rotation_rad * c.prior_rotation_rad;
  const double var_p = c.prior_position_m * c.prior_position_m;
  const double var_v = c.prior_velocity_m_s * c.prior_velocity_m_s;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  Matrix9d covariance = Matrix9d::Zero();
  covariance.block<3, 3>(0, 0) = var_R * I;
  covariance.block<3, 3>(3, 3) = var_v * I;
  covariance.block<3, 3>(6, 6) = (var_p + var_v * t * t) * I;
  covariance.block<3, 3>(3, 6) = var_v * t * I;
  covariance.block<3, 3>(6, 3) = var_v * t * I;
  return covariance;
}

// The IMU factor from the fixed previous state to the frame's (q, p, v) with the frame's biases.
class ImuFromPrevious {
 public:
  ImuFromPrevious(const InertialPoseConstraint& c)
      : residual_(c.preintegration, previous_state_covariance(c)),
        R_wi_(c.previous.R_wb),
        p_wi_(c.previous.p_wb),
        v_wi_(c.previous.v_wb),
        gravity_w_(c.gravity_w) {}

  template <typename T>
  bool operator()(const T* q_wj, const T* p_wj, const T* v_wj, const T* bg, const T* ba, T* residual) const {
    using Vector3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Quaternion<T> qj = Eigen::Map<const Eigen::Quaternion<T>>(q_wj).normalized();
    residual_.evaluate<T>(R_wi_.cast<T>(), p_wi_.cast<T>(), v_wi_.cast<T>(), Eigen::Map<const Vector3>(bg),
                          Eigen::Map<const Vector3>(ba), qj.toRotationMatrix(), Eigen::Map<const Vector3>(p_wj),
                          Eigen::Map<const Vector3>(v_wj), gravity_w_.cast<T>(), residual);
    return true;
  }

 private:
  ImuIntervalResidual residual_;
  Eigen::Matrix3d R_wi_;
  Eigen::Vector3d p_wi_, v_wi_, gravity_w_;
};

// The bias random walk from the previous frame's (fixed) biases to the frame's.
class BiasFromPrevious {
 public:
  explicit BiasFromPrevious(const InertialPoseConstraint& c) : bias_(c.previous_bias) {
    const Eigen::Matrix<double, 6, 6> covariance = c.preintegration.bias_random_walk_covariance();
    if (!(covariance(0, 0) > 0.0) || !(covariance(3, 3) > 0.0)) {
      throw std::invalid_argument("inertial pose optimization: expected positive bias random walks and duration");
    }
    inv_sigma_gyro_ = 1.0 / std::sqrt(covariance(0, 0));
    inv_sigma_accel_ = 1.0 / std::sqrt(covariance(3, 3));
  }

  template <typename T>
  bool operator()(const T* bg, const T* ba, T* residual) const {
    for (int k = 0; k < 3; ++k) {
      residual[k] = (bg[k] - T(bias_.gyro_rad_s[k])) * T(inv_sigma_gyro_);
      residual[3 + k] = (ba[k] - T(bias_.accel_m_s2[k])) * T(inv_sigma_accel_);
    }
    return true;
  }

 private:
  ImuBias bias_;
  double inv_sigma_gyro_ = 1.0;
  double inv_sigma_accel_ = 1.0;
};

Pose3 camera_from_world(const Eigen::Quaterniond& q_wb, const Eigen::Vector3d& p_wb, const Pose3& T_cb) {
  Pose3 T_wb = Pose3::Identity();
  T_wb.linear() = q_wb.normalized().toRotationMatrix();
  T_wb.translation() = p_wb;
  return T_cb * T_wb.inverse();  // T_cw = T_cb T_bw
}

}  // namespace

InertialPoseResult optimize_pose_inertial(const PinholeStereo& camera, const std::vector<PoseObservation>& observations,
                                          const Pose3& T_cw_guess, const InertialPoseConstraint& constraint,
                                          const MotionOnlyBaOptions& options) {
  if (!(options.disparity_sigma_ratio > 0.0)) {
    throw std::invalid_argument("MotionOnlyBaOptions.disparity_sigma_ratio: expected > 0");
  }
  InertialPoseResult result;
  result.T_cw = T_cw_guess;
  result.outlier.assign(observations.size(), false);
  if (observations.empty()) return result;

  const Pose3 T_bc = constraint.T_cb.inverse();
  const Pose3 T_wb_guess = T_cw_guess.inverse() * constraint.T_cb;  // T_wc T_cb
  Eigen::Quaterniond q_wb(T_wb_guess.rotation());
  Eigen::Vector3d p_wb = T_wb_guess.translation();
  Eigen::Vector3d v_wb =
      constraint.preintegration.predict(constraint.previous, constraint.gravity_w, constraint.previous_bias).v_wb;
  Eigen::Vector3d bg = constraint.previous_bias.gyro_rad_s;
  Eigen::Vector3d ba = constraint.previous_bias.accel_m_s2;

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.iterations_per_round;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;

  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robust_rounds;
    ceres::Problem problem;
    problem.AddParameterBlock(q_wb.coeffs().data(), 4, new ceres::EigenQuaternionManifold());
    int edges = 0;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (result.outlier[i]) continue;
      const PoseObservation& obs = observations[i];
      ceres::LossFunction* loss =
          robust ? new ceres::HuberLoss(std::sqrt(obs.stereo() ? options.chi2_stereo : options.chi2_mono)) : nullptr;
      problem.AddResidualBlock(BodyReprojection::create(camera, obs, T_bc, options.disparity_sigma_ratio), loss,
                               q_wb.coeffs().data(), p_wb.data());
      ++edges;
    }
    if (edges < kMinEdgesToContinue && round > 0) break;
    if (edges == 0) break;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<ImuFromPrevious, 9, 4, 3, 3, 3, 3>(new ImuFromPrevious(constraint)), nullptr,
        q_wb.coeffs().data(), p_wb.data(), v_wb.data(), bg.data(), ba.data());
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<BiasFromPrevious, 6, 3, 3>(new BiasFromPrevious(constraint)), nullptr,
        bg.data(), ba.data());
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    if (!q_wb.coeffs().allFinite() || !p_wb.allFinite() || !v_wb.allFinite() || !bg.allFinite() || !ba.allFinite()) {
      return result;  // ok == false
    }
    const Pose3 T_cw = camera_from_world(q_wb, p_wb, constraint.T_cb);
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const double threshold = observations[i].stereo() ? options.chi2_stereo : options.chi2_mono;
      result.outlier[i] =
          !(observation_chi2(camera, observations[i], T_cw, options.disparity_sigma_ratio) <= threshold);
    }
  }
  result.ok = true;
  result.T_cw = camera_from_world(q_wb, p_wb, constraint.T_cb);
  result.state.v_wb = v_wb;
  result.state.bias.gyro_rad_s = bg;
  result.state.bias.accel_m_s2 = ba;
  result.inliers = 0;
  for (bool o : result.outlier) result.inliers += o ? 0 : 1;
  return result;
}

int optimize_frame_pose_inertial(Frame& frame, const Map& map, const PinholeStereo& camera,
                                 const TrackerOptions& options, const InertialPoseConstraint& constraint,
                                 std::optional<InertialFrameState>& state) {
  // As optimize_frame_pose(): matches of points the map no longer holds are dropped, the outlier flags
  // cleared, every other match is an observation.
  for (std::size_t i = 0; i < frame.size(); ++i) {
    frame.outlier[i] = false;
    if (frame.point_ids[i] != kNoId && map.point(frame.point_ids[i]) == nullptr) frame.point_ids[i] = kNoId;
  }
  std::vector<std::size_t> keypoint_of;
  const std::vector<PoseObservation> observations = frame_observations(frame, map, &keypoint_of);
  if (observations.empty()) return 0;
  MotionOnlyBaOptions ba;
  ba.rounds = options.pose_optimization_rounds;
  ba.iterations_per_round = options.pose_optimization_iterations;
  ba.disparity_sigma_ratio = options.disparity_sigma_ratio;
  InertialPoseResult result;
  try {
    result = optimize_pose_inertial(camera, observations, frame.T_cw(), constraint, ba);
  } catch (const std::invalid_argument&) {
    result.ok = false;  // a degenerate interval (a single IMU step): the visual optimization instead
  }
  if (!result.ok) return optimize_frame_pose(frame, map, camera, options);
  frame.T_wc = result.T_cw.inverse();
  for (std::size_t k = 0; k < keypoint_of.size(); ++k) frame.outlier[keypoint_of[k]] = result.outlier[k];
  state = result.state;
  return result.inliers;
}

}  // namespace heslam
