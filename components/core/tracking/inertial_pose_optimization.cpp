// Motion-only optimization with IMU factors (inertial_pose_optimization.hpp): a Levenberg-Marquardt of its own
// on the frame's 15 parameters, and the Ceres version of the same cost it is tested against.
//
// With Ceres, a Problem built per round, its preprocessing and the autodiff of every reprojection cost about
// 30 times the visual optimization; here the 15x15 normal equations are accumulated directly: analytic
// reprojection Jacobians (6 pose columns), the IMU factor's 9x15 from its autodiff cost function's Evaluate().
#include "components/core/tracking/inertial_pose_optimization.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "components/core/imu/imu_factor.hpp"
#include "components/core/solve/dense_levenberg_marquardt.hpp"
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

// --- The hand-written solver (optimize_pose_inertial) --------------------------------------------------

using Matrix15d = Eigen::Matrix<double, 15, 15>;
using Vector15d = Eigen::Matrix<double, 15, 1>;

// The frame's 15 parameters. A step is (rotation, position, velocity, gyro bias, accel bias); the rotation's
// is on the left, in the world frame (q' = Exp(step) q), as Ceres' EigenQuaternionManifold.
struct BodyState {
  Eigen::Quaterniond q_wb = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_wb = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_wb = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();

  // The norm of the parameter vector as Ceres sees it (the quaternion's 4 coefficients and the rest).
  double norm() const {
    return std::sqrt(q_wb.coeffs().squaredNorm() + p_wb.squaredNorm() + v_wb.squaredNorm() + bg.squaredNorm() +
                     ba.squaredNorm());
  }
  bool finite() const {
    return q_wb.coeffs().allFinite() && p_wb.allFinite() && v_wb.allFinite() && bg.allFinite() && ba.allFinite();
  }
};

BodyState plus(const BodyState& x, const Vector15d& step) {
  BodyState y = x;
  const Eigen::Vector3d w = step.segment<3>(0);
  const double angle = w.norm();
  const Eigen::Quaterniond dq =
      angle > 0.0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle)) : Eigen::Quaterniond::Identity();
  y.q_wb = dq * x.q_wb;
  y.p_wb += step.segment<3>(3);
  y.v_wb += step.segment<3>(6);
  y.bg += step.segment<3>(9);
  y.ba += step.segment<3>(12);
  return y;
}

// An observation in a round, its square-root informations computed once per round.
struct VisualTerm {
  const PoseObservation* obs;
  double delta2;               // Huber threshold on the squared whitened error
  double sqrt_info;            // sqrt(obs->inv_sigma2)
  double disparity_sqrt_info;  // sqrt_info / (disparity_sigma_ratio * obs->disparity_sigma_scale)
};

// The cost of the Ceres version at a state, with its Gauss-Newton normal equations (IRLS weights for the
// Huber rounds, as motion_only_ba.cpp): the reprojections with analytic Jacobians, the IMU factor's through
// the same autodiff cost function the Ceres version adds (Evaluate() without a Problem), the bias random walk.
class InertialLinearization {
 public:
  InertialLinearization(const PinholeStereo& camera, const InertialPoseConstraint& constraint)
      : camera_(camera),
        R_bc_(constraint.T_cb.inverse().rotation()),
        p_bc_(constraint.T_cb.inverse().translation()),
        imu_(new ImuFromPrevious(constraint)),
        bias_(constraint.previous_bias) {
    const Eigen::Matrix<double, 6, 6> covariance = constraint.preintegration.bias_random_walk_covariance();
    inv_sigma_gyro_ = 1.0 / std::sqrt(covariance(0, 0));
    inv_sigma_accel_ = 1.0 / std::sqrt(covariance(3, 3));
  }

  // Half the total cost (as Ceres reports it); H and g of that cost in the step's coordinates.
  double evaluate(const std::vector<VisualTerm>& active, const BodyState& x, bool robust, Matrix15d& H,
                  Vector15d& g) const {
    H.setZero();
    g.setZero();
    double cost = 0.0;
    // Reprojections: p_c = R_cw (p_w - p_wb) - R_bc^T p_bc with R_cw = R_bc^T R_wb^T; at R' = Exp(w) R_wb,
    // p' = p_wb + r: d(p_c)/dw = R_cw [p_w - p_wb]x, d(p_c)/dr = -R_cw.
    const Eigen::Matrix3d R_cw = R_bc_.transpose() * x.q_wb.toRotationMatrix().transpose();
    const Eigen::Vector3d t_c = -R_bc_.transpose() * p_bc_;
    const double bf = camera_.bf();
    Eigen::Matrix<double, 6, 6> H_pose = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g_pose = Eigen::Matrix<double, 6, 1>::Zero();
    for (const VisualTerm& term : active) {
      const PoseObservation& obs = *term.obs;
      const Eigen::Vector3d d = obs.p_w - x.p_wb;
      const Eigen::Vector3d p_c = R_cw * d + t_c;
      if (!(p_c.z() > kMinDepthM)) continue;  // unusable at this pose: zero residual, as the Ceres version
      const double s = term.sqrt_info;
      const double inv_z = 1.0 / p_c.z();
      const double u = p_c.x() * inv_z;
      const double v = p_c.y() * inv_z;
      const bool stereo = obs.stereo();
      Eigen::Vector3d r;
      r(0) = (camera_.fx_px * u + camera_.cx_px - obs.u_px) * s;
      r(1) = (camera_.fy_px * v + camera_.cy_px - obs.v_px) * s;
      r(2) = stereo ? (bf * inv_z - (obs.u_px - obs.u_right_px)) * term.disparity_sqrt_info : 0.0;
      const Robust rho = huber(r.squaredNorm(), term.delta2, robust);
      cost += rho.cost;
      Eigen::Matrix3d dr_dpc = Eigen::Matrix3d::Zero();
      dr_dpc(0, 0) = camera_.fx_px * inv_z * s;
      dr_dpc(0, 2) = -camera_.fx_px * u * inv_z * s;
      dr_dpc(1, 1) = camera_.fy_px * inv_z * s;
      dr_dpc(1, 2) = -camera_.fy_px * v * inv_z * s;
      if (stereo) dr_dpc(2, 2) = -bf * inv_z * inv_z * term.disparity_sqrt_info;
      const Eigen::Matrix3d A = dr_dpc * R_cw;
      Eigen::Matrix<double, 3, 6> J;
      J.leftCols<3>() = A * skew(d);
      J.rightCols<3>() = -A;
      H_pose.noalias() += rho.weight * J.transpose() * J;  // a mono observation's third row is zero
      g_pose.noalias() += rho.weight * J.transpose() * r;
    }
    H.topLeftCorner<6, 6>() = H_pose;
    g.head<6>() = g_pose;

    // The IMU factor: its 9x4 quaternion Jacobian times the manifold's 4x3 PlusJacobian, halved: Ceres'
    // quaternion Plus(x, delta) turns by 2 |delta| (its Exp is of the half angle), our step by |step|.
    const double* parameters[5] = {x.q_wb.coeffs().data(), x.p_wb.data(), x.v_wb.data(), x.bg.data(), x.ba.data()};
    Eigen::Matrix<double, 9, 1> r_imu;
    Eigen::Matrix<double, 9, 4, Eigen::RowMajor> J_q;
    std::array<Eigen::Matrix<double, 9, 3, Eigen::RowMajor>, 4> J_rest;
    double* jacobians[5] = {J_q.data(), J_rest[0].data(), J_rest[1].data(), J_rest[2].data(), J_rest[3].data()};
    imu_.Evaluate(parameters, r_imu.data(), jacobians);
    Eigen::Matrix<double, 4, 3, Eigen::RowMajor> plus_jacobian;
    manifold_.PlusJacobian(x.q_wb.coeffs().data(), plus_jacobian.data());
    Eigen::Matrix<double, 9, 15> J_imu;
    J_imu.leftCols<3>() = 0.5 * J_q * plus_jacobian;
    for (int b = 0; b < 4; ++b) J_imu.middleCols<3>(3 + 3 * b) = J_rest[static_cast<std::size_t>(b)];
    H.noalias() += J_imu.transpose() * J_imu;
    g.noalias() += J_imu.transpose() * r_imu;
    cost += r_imu.squaredNorm();

    // The bias random walk: diagonal.
    for (int k = 0; k < 3; ++k) {
      const double r_g = (x.bg(k) - bias_.gyro_rad_s(k)) * inv_sigma_gyro_;
      const double r_a = (x.ba(k) - bias_.accel_m_s2(k)) * inv_sigma_accel_;
      H(9 + k, 9 + k) += inv_sigma_gyro_ * inv_sigma_gyro_;
      H(12 + k, 12 + k) += inv_sigma_accel_ * inv_sigma_accel_;
      g(9 + k) += inv_sigma_gyro_ * r_g;
      g(12 + k) += inv_sigma_accel_ * r_a;
      cost += r_g * r_g + r_a * r_a;
    }
    return 0.5 * cost;
  }

 private:
  struct Robust {
    double cost;
    double weight;
  };
  // Ceres' HuberLoss on a squared whitened error: the cost and its derivative (the IRLS weight).
  static Robust huber(double squared_error, double delta2, bool robust) {
    if (!robust || squared_error <= delta2) return {squared_error, 1.0};
    const double error = std::sqrt(squared_error);
    const double delta = std::sqrt(delta2);
    return {2.0 * delta * error - delta2, delta / error};
  }
  static Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
    Eigen::Matrix3d m;
    m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
    return m;
  }

  const PinholeStereo& camera_;
  Eigen::Matrix3d R_bc_;
  Eigen::Vector3d p_bc_;
  ceres::AutoDiffCostFunction<ImuFromPrevious, 9, 4, 3, 3, 3, 3> imu_;
  ceres::EigenQuaternionManifold manifold_;
  ImuBias bias_;
  double inv_sigma_gyro_ = 1.0;
  double inv_sigma_accel_ = 1.0;
};

// One round's problem for dense_levenberg_marquardt(): the 15 parameters, H and g computed with each
// trial's cost (both come from one pass).
struct InertialProblem {
  const InertialLinearization& linearization;
  const std::vector<VisualTerm>& active;
  bool robust;
  Matrix15d H;
  Vector15d g;
  Matrix15d H_trial;
  Vector15d g_trial;

  double evaluate_trial(const BodyState& x) { return linearization.evaluate(active, x, robust, H_trial, g_trial); }
  void accept_trial() {
    H = H_trial;
    g = g_trial;
  }
  void normal_equations(Matrix15d& H_out, Vector15d& g_out) const {
    H_out = H;
    g_out = g;
  }
  static BodyState plus(const BodyState& x, const Vector15d& step) { return heslam::plus(x, step); }
  static double norm(const BodyState& x) { return x.norm(); }
};

// One round: at most `iterations` Levenberg-Marquardt steps (dense_levenberg_marquardt(), as
// solve_round() in motion_only_ba.cpp).
void solve_round(const InertialLinearization& linearization, const std::vector<VisualTerm>& active, BodyState& x,
                 bool robust, int iterations) {
  InertialProblem problem{linearization, active, robust, {}, {}, {}, {}};
  const double cost = problem.evaluate_trial(x);
  problem.accept_trial();
  dense_levenberg_marquardt<15>(problem, x, cost, iterations);
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

  const InertialLinearization problem(camera, constraint);  // throws for a degenerate interval, as Ceres'
  const Pose3 T_wb_guess = T_cw_guess.inverse() * constraint.T_cb;
  BodyState x;
  x.q_wb = Eigen::Quaterniond(T_wb_guess.rotation());
  x.p_wb = T_wb_guess.translation();
  x.v_wb = constraint.preintegration.predict(constraint.previous, constraint.gravity_w, constraint.previous_bias).v_wb;
  x.bg = constraint.previous_bias.gyro_rad_s;
  x.ba = constraint.previous_bias.accel_m_s2;

  std::vector<VisualTerm> active;
  active.reserve(observations.size());
  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robust_rounds;
    active.clear();
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (result.outlier[i]) continue;
      const PoseObservation& obs = observations[i];
      const double sqrt_info = std::sqrt(obs.inv_sigma2);
      active.push_back({&obs, obs.stereo() ? options.chi2_stereo : options.chi2_mono, sqrt_info,
                        sqrt_info / (options.disparity_sigma_ratio * obs.disparity_sigma_scale)});
    }
    const int edges = static_cast<int>(active.size());
    if (edges < kMinEdgesToContinue && round > 0) break;
    if (edges == 0) break;
    solve_round(problem, active, x, robust, options.iterations_per_round);
    if (!x.finite()) return result;  // ok == false
    const Pose3 T_cw = camera_from_world(x.q_wb, x.p_wb, constraint.T_cb);
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const double threshold = observations[i].stereo() ? options.chi2_stereo : options.chi2_mono;
      result.outlier[i] =
          !(observation_chi2(camera, observations[i], T_cw, options.disparity_sigma_ratio) <= threshold);
    }
  }
  result.ok = true;
  result.T_cw = camera_from_world(x.q_wb, x.p_wb, constraint.T_cb);
  result.state.v_wb = x.v_wb;
  result.state.bias.gyro_rad_s = x.bg;
  result.state.bias.accel_m_s2 = x.ba;
  result.inliers = 0;
  for (bool o : result.outlier) result.inliers += o ? 0 : 1;
  return result;
}

InertialPoseResult optimize_pose_inertial_ceres(const PinholeStereo& camera,
                                                const std::vector<PoseObservation>& observations,
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
