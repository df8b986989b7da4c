// Visual-inertial initialization from metric poses (inertial_initialization.hpp).
#include "components/core/imu/inertial_initialization.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>

#include "components/core/imu/gyro_bias.hpp"
#include "components/core/imu/imu_factor.hpp"
#include "components/core/imu/so3.hpp"

namespace heslam {
namespace {

constexpr double kNsPerS = 1e9;
constexpr double kRadToDeg = 180.0 / M_PI;
// An interval's preintegrated duration may differ from its stamps' by the interpolation's rounding only.
constexpr double kDurationToleranceS = 1e-6;
// Weight of the linear guess's pull of the accelerometer bias to its prior mean (m/s per m/s^2): only there
// to keep the system solvable without rotation (the refusal then comes from the refinement's posterior).
constexpr double kLinearBiasPriorWeight = 1e-3;
// A linear gravity guess this far from the known magnitude means the poses and the IMU disagree.
constexpr double kMaxGravityMagnitudeRatioError = 0.5;

template <typename... Args>
std::string format(const char* pattern, Args... args) {
  char text[320];
  std::snprintf(text, sizeof(text), pattern, args...);
  return text;
}

InertialInitResult refuse(InertialInitResult result, InertialInitStatus status, std::string reason) {
  result.ok = false;
  result.status = status;
  result.reason = std::move(reason);
  return result;
}

// The covariance the vision poses add to an interval's residual (rotation, velocity, position), with each
// pose's rotation (right perturbation) and position errors isotropic and independent: r_R moves with
// -dR^T d_theta_i and d_theta_j, r_v and r_p with [dv]x d_theta_i and [dp]x d_theta_i, r_p with
// R_i^T (d_p_j - d_p_i).
Matrix9d pose_covariance(const ImuPreintegration& interval, double rotation_stddev_rad, double position_stddev_m) {
  Eigen::Matrix<double, 9, 3> J_i = Eigen::Matrix<double, 9, 3>::Zero();
  J_i.block<3, 3>(0, 0) = -interval.delta_R().transpose();
  J_i.block<3, 3>(3, 0) = so3::hat(interval.delta_v());
  J_i.block<3, 3>(6, 0) = so3::hat(interval.delta_p());
  Eigen::Matrix<double, 9, 3> J_j = Eigen::Matrix<double, 9, 3>::Zero();
  J_j.block<3, 3>(0, 0).setIdentity();
  const double rotation_variance = rotation_stddev_rad * rotation_stddev_rad;
  Matrix9d covariance = rotation_variance * (J_i * J_i.transpose() + J_j * J_j.transpose());
  covariance.block<3, 3>(6, 6) += 2.0 * position_stddev_m * position_stddev_m * Eigen::Matrix3d::Identity();
  return covariance;
}

// One interval with the poses fixed: gravity R_wg0 Exp(theta_x, theta_y, 0) (0, 0, -g), velocities, biases.
struct IntervalCost {
  IntervalCost(const ImuPreintegration& interval, const Matrix9d& pose_covariance, const Pose3& T_wi, const Pose3& T_wj,
               const Eigen::Matrix3d& R_wg0, double gravity_m_s2)
      : residual(interval, pose_covariance),
        R_wi(T_wi.linear()),
        R_wj(T_wj.linear()),
        p_wi(T_wi.translation()),
        p_wj(T_wj.translation()),
        R_wg0(R_wg0),
        gravity_m_s2(gravity_m_s2) {}

  template <typename T>
  bool operator()(const T* theta, const T* v_wi, const T* v_wj, const T* bg, const T* ba, T* out) const {
    using Vector3 = Eigen::Matrix<T, 3, 1>;
    const T angle_axis[3] = {theta[0], theta[1], T(0)};
    Eigen::Matrix<T, 3, 3> R_g0g;
    ceres::AngleAxisToRotationMatrix(angle_axis, R_g0g.data());
    const Vector3 gravity_w = R_wg0.cast<T>() * (R_g0g * Vector3(T(0), T(0), T(-gravity_m_s2)));
    residual.evaluate<T>(R_wi.cast<T>(), p_wi.cast<T>(), Eigen::Map<const Vector3>(v_wi), Eigen::Map<const Vector3>(bg),
                         Eigen::Map<const Vector3>(ba), R_wj.cast<T>(), p_wj.cast<T>(), Eigen::Map<const Vector3>(v_wj),
                         gravity_w, out);
    return true;
  }

  ImuIntervalResidual residual;
  Eigen::Matrix3d R_wi, R_wj;
  Eigen::Vector3d p_wi, p_wj;
  Eigen::Matrix3d R_wg0;
  double gravity_m_s2;
};

struct PriorCost {
  PriorCost(const Eigen::Vector3d& mean, double stddev) : mean(mean), inv_stddev(1.0 / stddev) {}
  template <typename T>
  bool operator()(const T* x, T* out) const {
    for (int k = 0; k < 3; ++k) out[k] = (x[k] - T(mean[k])) * T(inv_stddev);
    return true;
  }
  Eigen::Vector3d mean;
  double inv_stddev;
};

void validate(const InertialInitInput& input, const InertialInitOptions& options) {
  const std::string where = "initialize_inertial: ";
  if (input.stamps_ns.size() != input.T_wb.size()) {
    throw std::invalid_argument(where + "stamps_ns: expected one stamp per pose (" + std::to_string(input.T_wb.size()) +
                                "), got " + std::to_string(input.stamps_ns.size()));
  }
  if (input.T_wb.size() < 2 || input.intervals.size() != input.T_wb.size() - 1) {
    throw std::invalid_argument(where + "intervals: expected one per pair of consecutive poses (" +
                                std::to_string(input.T_wb.empty() ? 0 : input.T_wb.size() - 1) + ", at least 1), got " +
                                std::to_string(input.intervals.size()));
  }
  for (std::size_t k = 0; k < input.T_wb.size(); ++k) {
    if (!input.T_wb[k].matrix().allFinite()) {
      throw std::invalid_argument(where + "T_wb[" + std::to_string(k) + "]: expected a finite pose");
    }
    if (k > 0 && input.stamps_ns[k] <= input.stamps_ns[k - 1]) {
      throw std::invalid_argument(where + "stamps_ns[" + std::to_string(k) + "]: expected increasing stamps, got " +
                                  std::to_string(input.stamps_ns[k]) + " after " +
                                  std::to_string(input.stamps_ns[k - 1]));
    }
  }
  for (std::size_t k = 0; k < input.intervals.size(); ++k) {
    const double expected_s = static_cast<double>(input.stamps_ns[k + 1] - input.stamps_ns[k]) / kNsPerS;
    if (std::abs(input.intervals[k].duration_s() - expected_s) > kDurationToleranceS) {
      throw std::invalid_argument(where + "intervals[" + std::to_string(k) + "]: duration " +
                                  std::to_string(input.intervals[k].duration_s()) + " s, expected " +
                                  std::to_string(expected_s) + " s between its stamps");
    }
  }
  if (!(options.gravity_m_s2 > 0.0) || !(options.gyro_bias_prior_stddev_rad_s > 0.0) ||
      !(options.accel_bias_prior_stddev_m_s2 > 0.0) || options.pose_rotation_stddev_rad < 0.0 ||
      options.pose_position_stddev_m < 0.0 || options.max_iterations < 1 ||
      !(options.max_gravity_stddev_of_prior > 0.0)) {
    throw std::invalid_argument(where +
                                "options: expected gravity_m_s2, the bias prior stddevs and max_iterations positive, "
                                "the pose stddevs non-negative");
  }
}

}  // namespace

const char* to_string(InertialInitStatus status) {
  switch (status) {
    case InertialInitStatus::kOk: return "ok";
    case InertialInitStatus::kTooShort: return "too_short";
    case InertialInitStatus::kTooLittleExcitation: return "too_little_excitation";
    case InertialInitStatus::kNotConverged: return "not_converged";
    case InertialInitStatus::kResidualTooHigh: return "residual_too_high";
  }
  return "unknown";
}

InertialInitResult initialize_inertial(const InertialInitInput& input, const InertialInitOptions& options) {
  validate(input, options);
  InertialInitResult result;
  const std::size_t n = input.intervals.size();
  const double duration_s = static_cast<double>(input.stamps_ns.back() - input.stamps_ns.front()) / kNsPerS;
  if (static_cast<int>(n) < options.min_intervals || duration_s < options.min_duration_s) {
    return refuse(result, InertialInitStatus::kTooShort,
                  format("too short: %zu intervals over %.2f s (need %d and %.2f s)", n, duration_s,
                         options.min_intervals, options.min_duration_s));
  }

  // 1. The gyroscope bias from the vision rotations alone.
  std::vector<Eigen::Matrix3d> R_ij(n);
  for (std::size_t k = 0; k < n; ++k) R_ij[k] = input.T_wb[k].linear().transpose() * input.T_wb[k + 1].linear();
  ImuBias bias = input.intervals.front().bias();
  try {
    bias.gyro_rad_s = estimate_gyro_bias(input.intervals, R_ij).gyro_rad_s;
  } catch (const std::invalid_argument& e) {
    return refuse(result, InertialInitStatus::kNotConverged, std::string("gyroscope bias: ") + e.what());
  }

  // 2. Linear guess of velocities, gravity (unconstrained, 3 numbers) and accelerometer bias, in m/s units:
  //    v_j - v_i - g t - R_i Jva dba = R_i dv
  //    -v_i - g t / 2 - R_i Jpa dba / t = (R_i dp - (p_j - p_i)) / t
  const int unknowns = 3 * static_cast<int>(n + 1) + 6;
  const int gravity_col = 3 * static_cast<int>(n + 1);
  const int bias_col = gravity_col + 3;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6 * static_cast<int>(n) + 3, unknowns);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(A.rows());
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  for (std::size_t k = 0; k < n; ++k) {
    const ImuPreintegration& interval = input.intervals[k];
    const double t = interval.duration_s();
    const Eigen::Matrix3d R_wi = input.T_wb[k].linear();
    const int row = 6 * static_cast<int>(k);
    const int vi = 3 * static_cast<int>(k);
    A.block<3, 3>(row, vi + 3) = I;
    A.block<3, 3>(row, vi) = -I;
    A.block<3, 3>(row, gravity_col) = -t * I;
    A.block<3, 3>(row, bias_col) = -R_wi * interval.dv_dba();
    b.segment<3>(row) = R_wi * interval.delta_v(bias);
    A.block<3, 3>(row + 3, vi) = -I;
    A.block<3, 3>(row + 3, gravity_col) = -0.5 * t * I;
    A.block<3, 3>(row + 3, bias_col) = -R_wi * interval.dp_dba() / t;
    b.segment<3>(row + 3) =
        (R_wi * interval.delta_p(bias) - (input.T_wb[k + 1].translation() - input.T_wb[k].translation())) / t;
  }
  A.block<3, 3>(6 * static_cast<int>(n), bias_col) = kLinearBiasPriorWeight * I;
  b.segment<3>(6 * static_cast<int>(n)) = kLinearBiasPriorWeight * (options.prior_bias.accel_m_s2 - bias.accel_m_s2);
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  const Eigen::Vector3d gravity_guess = x.segment<3>(gravity_col);
  if (!x.allFinite() ||
      std::abs(gravity_guess.norm() - options.gravity_m_s2) > kMaxGravityMagnitudeRatioError * options.gravity_m_s2) {
    return refuse(result, InertialInitStatus::kResidualTooHigh,
                  format("residual too high: the linear gravity guess has %.2f m/s^2, expected %.2f (poses and IMU "
                         "disagree: calibration, time offset or units?)",
                         gravity_guess.norm(), options.gravity_m_s2));
  }
  const Eigen::Matrix3d R_wg0 =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d(0.0, 0.0, -1.0), gravity_guess.normalized())
          .toRotationMatrix();

  // 3. Inertial-only MAP refinement.
  double theta[2] = {0.0, 0.0};
  std::vector<Eigen::Vector3d> velocities(n + 1);
  for (std::size_t k = 0; k <= n; ++k) velocities[k] = x.segment<3>(3 * static_cast<int>(k));
  Eigen::Vector3d bg = bias.gyro_rad_s;
  Eigen::Vector3d ba = bias.accel_m_s2 + x.segment<3>(bias_col);

  ceres::Problem problem;
  std::vector<ceres::ResidualBlockId> interval_blocks;
  try {
    for (std::size_t k = 0; k < n; ++k) {
      auto* cost = new ceres::AutoDiffCostFunction<IntervalCost, 9, 2, 3, 3, 3, 3>(new IntervalCost(
          input.intervals[k],
          pose_covariance(input.intervals[k], options.pose_rotation_stddev_rad, options.pose_position_stddev_m),
          input.T_wb[k], input.T_wb[k + 1], R_wg0, options.gravity_m_s2));
      interval_blocks.push_back(problem.AddResidualBlock(cost, nullptr, theta, velocities[k].data(),
                                                         velocities[k + 1].data(), bg.data(), ba.data()));
    }
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("initialize_inertial: intervals: ") + e.what());
  }
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 3, 3>(
                               new PriorCost(options.prior_bias.gyro_rad_s, options.gyro_bias_prior_stddev_rad_s)),
                           nullptr, bg.data());
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 3, 3>(
                               new PriorCost(options.prior_bias.accel_m_s2, options.accel_bias_prior_stddev_m_s2)),
                           nullptr, ba.data());

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = 1e-12;
  solver_options.gradient_tolerance = 1e-14;
  solver_options.parameter_tolerance = 1e-12;
  solver_options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  result.iterations = static_cast<int>(summary.iterations.size());

  const Eigen::Vector3d tilt(theta[0], theta[1], 0.0);
  result.R_wg = so3::normalized(R_wg0 * so3::exp(tilt));
  result.v_wb = velocities;
  result.bias.gyro_rad_s = bg;
  result.bias.accel_m_s2 = ba;
  {
    ceres::Problem::EvaluateOptions evaluate;
    evaluate.residual_blocks = interval_blocks;
    double cost = 0.0;
    problem.Evaluate(evaluate, &cost, nullptr, nullptr, nullptr);
    const double dof = 9.0 * static_cast<double>(n) - static_cast<double>(3 * (n + 1) + 8);
    result.rms = std::sqrt(2.0 * cost / std::max(1.0, dof));
  }
  if (summary.termination_type != ceres::CONVERGENCE || !std::isfinite(result.rms)) {
    return refuse(result, InertialInitStatus::kNotConverged,
                  "did not converge: " + std::to_string(result.iterations) + " iterations, " + summary.message);
  }

  // 4. The posterior covariance from the Jacobian at the estimate (all residuals, priors included).
  std::vector<double*> blocks = {theta};
  for (Eigen::Vector3d& v : velocities) blocks.push_back(v.data());
  blocks.push_back(bg.data());
  blocks.push_back(ba.data());
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = blocks;
  ceres::CRSMatrix jacobian;
  problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &jacobian);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(jacobian.num_rows, jacobian.num_cols);
  for (int row = 0; row < jacobian.num_rows; ++row) {
    for (int at = jacobian.rows[row]; at < jacobian.rows[row + 1]; ++at)
      J(row, jacobian.cols[at]) = jacobian.values[at];
  }
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::LDLT<Eigen::MatrixXd> H_ldlt(H);
  const Eigen::MatrixXd covariance = H_ldlt.solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
  const int ba_col = static_cast<int>(H.rows()) - 3;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> tilt_eigen(covariance.block<2, 2>(0, 0));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> ba_eigen(covariance.block<3, 3>(ba_col, ba_col));
  result.gravity_stddev_deg = std::sqrt(std::max(0.0, tilt_eigen.eigenvalues().maxCoeff())) * kRadToDeg;
  result.accel_bias_stddev_m_s2 = std::sqrt(std::max(0.0, ba_eigen.eigenvalues().maxCoeff()));
  if (H_ldlt.info() != Eigen::Success || !covariance.allFinite()) {
    return refuse(result, InertialInitStatus::kTooLittleExcitation,
                  "too little excitation: the inertial problem is singular (rotate and accelerate the sensor)");
  }
  // Without rotation the tilt is only known through the accelerometer bias prior: accel prior / g radians.
  const double prior_tilt_deg = options.accel_bias_prior_stddev_m_s2 / options.gravity_m_s2 * kRadToDeg;
  const double gravity_limit_deg =
      std::min(options.max_gravity_stddev_deg, options.max_gravity_stddev_of_prior * prior_tilt_deg);
  if (result.gravity_stddev_deg > gravity_limit_deg ||
      result.accel_bias_stddev_m_s2 > options.max_accel_bias_stddev_m_s2) {
    return refuse(result, InertialInitStatus::kTooLittleExcitation,
                  format("too little excitation: gravity direction stddev %.2f deg (max %.2f), accelerometer bias "
                         "stddev %.3f m/s^2 (max %.3f): rotate the sensor, or wait",
                         result.gravity_stddev_deg, gravity_limit_deg, result.accel_bias_stddev_m_s2,
                         options.max_accel_bias_stddev_m_s2));
  }
  const double gyro_sigmas =
      (bg - options.prior_bias.gyro_rad_s).lpNorm<Eigen::Infinity>() / options.gyro_bias_prior_stddev_rad_s;
  const double accel_sigmas =
      (ba - options.prior_bias.accel_m_s2).lpNorm<Eigen::Infinity>() / options.accel_bias_prior_stddev_m_s2;
  if (std::max(gyro_sigmas, accel_sigmas) > options.max_bias_prior_sigmas) {
    return refuse(result, InertialInitStatus::kResidualTooHigh,
                  format("residual too high: biases %.1f (gyro) and %.1f (accel) prior sigmas from their prior, max "
                         "%.1f (IMU and poses disagree: scale, calibration or time offset?)",
                         gyro_sigmas, accel_sigmas, options.max_bias_prior_sigmas));
  }
  if (result.rms > options.max_whitened_rms) {
    return refuse(result, InertialInitStatus::kResidualTooHigh,
                  format("residual too high: whitened rms %.2f > %.2f (IMU and poses disagree: noise model, "
                         "calibration or time offset?)",
                         result.rms, options.max_whitened_rms));
  }
  result.ok = true;
  result.status = InertialInitStatus::kOk;
  result.reason =
      format("initialized: gravity stddev %.3f deg, whitened rms %.2f", result.gravity_stddev_deg, result.rms);
  return result;
}

}  // namespace heslam
