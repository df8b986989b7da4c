// Visual-inertial initialization from metric (stereo) body poses: the direction of gravity in the visual
// world, the body's velocity at each pose and the IMU biases. ORB-SLAM3's inertial-only MAP estimate
// (Campos et al., "Inertial-only optimization for visual-inertial initialization", ICRA 2020) with the
// scale fixed to 1: the gyroscope bias from the vision rotations first (gyro_bias.hpp), then a linear
// least-squares guess of gravity, velocities and accelerometer bias, then a Ceres refinement of gravity
// (2-DoF), velocities and both biases with Gaussian bias priors, each interval weighted by its
// preintegration covariance plus the vision poses' own uncertainty. It refuses (ok = false, with a
// reason) rather than return a poorly observed answer: the posterior standard deviations of the gravity
// direction and of the accelerometer bias must be small (a sequence without rotation cannot separate a
// tilt of gravity from an accelerometer bias).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "components/core/geometry/pose.hpp"
#include "components/core/imu/preintegration.hpp"

namespace heslam {

struct InertialInitOptions {
  // Refuse windows shorter than this or with fewer intervals (ORB-SLAM3 waits for 10 keyframes / 2 s).
  double min_duration_s = 1.0;
  int min_intervals = 5;
  // Magnitude of gravity, m/s^2 (the direction is estimated).
  double gravity_m_s2 = 9.81;
  // Gaussian priors on the biases, around prior_bias: loose enough to let any consumer-grade IMU's bias
  // through, tight enough to keep the problem well posed when an axis is weakly excited.
  ImuBias prior_bias;
  double gyro_bias_prior_stddev_rad_s = 0.1;
  double accel_bias_prior_stddev_m_s2 = 0.2;
  // Uncertainty of the vision poses (each pose, isotropic), added to the preintegration covariance of
  // the residuals: stereo keyframe poses are good to a millimetre, worse than the IMU over a fraction of a
  // second, so without it the weights would trust them blindly and the posterior would be overconfident.
  double pose_rotation_stddev_rad = 1e-3;
  double pose_position_stddev_m = 1e-3;
  // Ceres iterations of the inertial-only refinement.
  int max_iterations = 50;
  // Refusal thresholds: the posterior (1-sigma) of the gravity direction, also as a share of what the
  // accelerometer bias prior alone leaves (accel_bias_prior_stddev / g: without rotation the data cannot
  // tell a tilt from a bias, and the answer would be the prior's, not the data's), and of the
  // accelerometer bias (worst direction); the whitened residual RMS per degree of freedom (about 1 when
  // the noise model holds); and how many prior sigmas a bias may sit from prior_bias (a bias the data
  // push far beyond its prior means poses and IMU disagree: scale, calibration, time offset).
  double max_gravity_stddev_deg = 1.0;
  double max_gravity_stddev_of_prior = 0.75;
  double max_accel_bias_stddev_m_s2 = 0.2;
  double max_whitened_rms = 3.0;
  double max_bias_prior_sigmas = 5.0;
};

struct InertialInitInput {
  // Body (IMU) poses from vision, metric, one per keyframe or frame, with strictly increasing stamps.
  std::vector<Pose3> T_wb;
  std::vector<std::int64_t> stamps_ns;
  // intervals[k] preintegrates [stamps_ns[k], stamps_ns[k + 1]] (size T_wb.size() - 1). Its
  // linearization bias is where the bias correction starts; for large biases, preintegrate again around
  // the result and call again (the first-order correction of a 0.1 rad/s gyro bias leaves ~1e-4 rad/s).
  std::vector<ImuPreintegration> intervals;
};

enum class InertialInitStatus {
  kOk,
  kTooShort,             // fewer intervals or less time than the options ask
  kTooLittleExcitation,  // gravity direction or accelerometer bias not observable enough
  kNotConverged,         // the refinement did not converge (or failed numerically)
  kResidualTooHigh,      // the IMU disagrees with the vision poses (wrong calibration, time offset, noise model)
};

// When a refusal comes after the refinement (too little excitation, residual too high, not converged), the
// estimate fields hold the withheld answer, for diagnostics only.
struct InertialInitResult {
  bool ok = false;
  InertialInitStatus status = InertialInitStatus::kTooShort;
  // Why not (yet): a one-liner a status topic can show, e.g. "too little excitation: gravity direction
  // stddev 3.2 deg > 0.5 deg (rotate the sensor)". "initialized" when ok.
  std::string reason;
  // Rotation from the gravity-aligned frame g (z up, gravity (0, 0, -g)) to the visual world w: gravity in w
  // is R_wg * (0, 0, -gravity_m_s2). Its yaw about g's z is arbitrary (chosen as the smallest rotation).
  Eigen::Matrix3d R_wg = Eigen::Matrix3d::Identity();
  // Velocity of the body at each input pose, in w.
  std::vector<Eigen::Vector3d> v_wb;
  ImuBias bias;
  // RMS of the whitened inertial residuals at the estimate, per degree of freedom (9 residuals per
  // interval less the unknowns): about 1 when the noise model and pose uncertainties are right.
  double rms = 0.0;
  // Posterior 1-sigma of the gravity direction (degrees) and largest of the accelerometer bias (m/s^2).
  double gravity_stddev_deg = 0.0;
  double accel_bias_stddev_m_s2 = 0.0;
  int iterations = 0;

  Eigen::Vector3d gravity_w(double gravity_m_s2 = 9.81) const {
    return R_wg * Eigen::Vector3d(0.0, 0.0, -gravity_m_s2);
  }
};

// Throws std::invalid_argument naming the field for inconsistent sizes, non-increasing stamps, intervals
// whose duration differs from their stamps', or non-finite poses; all else (including too little data) is
// a result with ok = false and a reason.
InertialInitResult initialize_inertial(const InertialInitInput& input, const InertialInitOptions& options = {});

// The status as a short name ("ok", "too_short", "too_little_excitation", "not_converged", "residual_too_high").
const char* to_string(InertialInitStatus status);

}  // namespace heslam
