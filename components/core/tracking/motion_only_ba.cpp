// Motion-only bundle adjustment: a 6-dof Levenberg-Marquardt on the pose alone with analytic Jacobians.
//
// The problem is one 6-parameter block against a few hundred fixed points, solved 8 times a frame
// (2 optimizations x 4 rounds). With Ceres, building a Problem per round, its preprocessing and the
// autodiff Jacobians through angle-axis rotations cost more than the arithmetic itself; here one pass
// over the observations accumulates the 6x6 normal equations directly (g2o's way, as in ORB-SLAM2).
#include "components/core/tracking/motion_only_ba.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

namespace heslam {
namespace {

// Fewer residuals than this and another round cannot classify anything reliably (ORB-SLAM2 stops too).
constexpr int kMinEdgesToContinue = 10;
// A point this close to (or behind) the camera plane gives no usable projection in an iteration.
constexpr double kMinDepthM = 1e-9;
// Ceres' defaults, kept from the Ceres version of this solver: initial damping 1 / trust radius 1e4,
// stop when an accepted step lowers the cost by less than this fraction.
constexpr double kInitialLambda = 1e-4;
constexpr double kFunctionTolerance = 1e-6;
// ... and, as Ceres, at a gradient below this (max norm) or a step below this relative size.
constexpr double kGradientTolerance = 1e-10;
constexpr double kParameterTolerance = 1e-8;
// Rejected steps raise the damping; beyond this the step would be negligible, so the round ends.
constexpr double kMaxLambda = 1e16;
// LM scales its damping by the diagonal of J^T J clamped to this range (Ceres' min / max_lm_diagonal).
constexpr double kMinDiagonal = 1e-6;
constexpr double kMaxDiagonal = 1e32;

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// Robust (Huber) cost of one squared whitened error and the IRLS weight of its residual.
struct Robust {
  double cost;
  double weight;
};

Robust huber(double squared_error, double delta2, bool robust) {
  if (!robust || squared_error <= delta2) return {squared_error, 1.0};
  const double error = std::sqrt(squared_error);
  const double delta = std::sqrt(delta2);
  return {2.0 * delta * error - delta2, delta / error};
}

// Whitened residual (2 or 3 components) and, when asked, its Jacobian with respect to the pose
// perturbation [w, r]: R' = Exp(w) R, t' = t + r (dp_c/dw = -[R p_w]x, dp_c/dr = I).
// The Jacobian is left unset where it is not asked for: zeroing it on every call (a memset, also in
// each cost evaluation) was 3 % of the tracking's instructions.
struct Linearization {
  Eigen::Vector3d residual = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, 6> jacobian;  // all 18 entries written when with_jacobian
  int size = 0;  // 0: not usable at this pose (point at or behind the camera)
};

// An observation in a round, with its square-root informations computed once per round instead of at
// every linearization (a square root and a division each time; the same values).
struct Active {
  const PoseObservation* obs;
  double delta2;               // Huber threshold on the squared whitened error
  double sqrt_info;            // sqrt(obs->inv_sigma2)
  double disparity_sqrt_info;  // sqrt_info / (disparity_sigma_ratio * obs->disparity_sigma_scale)
};

Active make_active(const PoseObservation& obs, double delta2, double disparity_sigma_ratio) {
  const double sqrt_info = std::sqrt(obs.inv_sigma2);
  return {&obs, delta2, sqrt_info, sqrt_info / (disparity_sigma_ratio * obs.disparity_sigma_scale)};
}

Linearization linearize(const PinholeStereo& camera, const Active& a, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                        bool with_jacobian) {
  Linearization out;
  const PoseObservation& obs = *a.obs;
  const Eigen::Vector3d p_r = R * obs.p_w;
  const Eigen::Vector3d p_c = p_r + t;
  if (!(p_c.z() > kMinDepthM)) return out;
  const double sqrt_info = a.sqrt_info;
  const double inv_z = 1.0 / p_c.z();
  const double x = p_c.x() * inv_z;
  const double y = p_c.y() * inv_z;
  out.size = obs.stereo() ? 3 : 2;
  out.residual(0) = (camera.fx_px * x + camera.cx_px - obs.u_px) * sqrt_info;
  out.residual(1) = (camera.fy_px * y + camera.cy_px - obs.v_px) * sqrt_info;
  const double disparity_sqrt_info = a.disparity_sqrt_info;
  if (obs.stereo()) out.residual(2) = (camera.bf() * inv_z - (obs.u_px - obs.u_right_px)) * disparity_sqrt_info;
  if (!with_jacobian) return out;
  // d(residual)/d(p_c), whitened.
  Eigen::Matrix3d d_p = Eigen::Matrix3d::Zero();
  d_p(0, 0) = camera.fx_px * inv_z * sqrt_info;
  d_p(0, 2) = -camera.fx_px * x * inv_z * sqrt_info;
  d_p(1, 1) = camera.fy_px * inv_z * sqrt_info;
  d_p(1, 2) = -camera.fy_px * y * inv_z * sqrt_info;
  d_p(2, 2) = -camera.bf() * inv_z * inv_z * disparity_sqrt_info;
  Eigen::Matrix3d skew;
  skew << 0.0, -p_r.z(), p_r.y(), p_r.z(), 0.0, -p_r.x(), -p_r.y(), p_r.x(), 0.0;
  out.jacobian.leftCols<3>() = -d_p * skew;
  out.jacobian.rightCols<3>() = d_p;
  if (!obs.stereo()) out.jacobian.row(2).setZero();
  return out;
}

// Total robust cost at a pose (half the sum, as Ceres reports it).
double total_cost(const PinholeStereo& camera, const std::vector<Active>& active, const Eigen::Matrix3d& R,
                  const Eigen::Vector3d& t, bool robust) {
  double cost = 0.0;
  for (const Active& a : active) {
    const Linearization l = linearize(camera, a, R, t, false);
    if (l.size == 0) continue;
    cost += huber(l.residual.squaredNorm(), a.delta2, robust).cost;
  }
  return 0.5 * cost;
}

// One round: at most `iterations` LM steps on the active observations; updates R and t.
void solve_round(const PinholeStereo& camera, const std::vector<Active>& active, Eigen::Matrix3d& R,
                 Eigen::Vector3d& t, bool robust, int iterations) {
  double lambda = kInitialLambda;
  double lambda_factor = 2.0;  // grows while steps are rejected in a row (Ceres' decrease factor)
  double cost = total_cost(camera, active, R, t, robust);
  for (int iteration = 0; iteration < iterations; ++iteration) {
    Matrix6 H = Matrix6::Zero();
    Vector6 g = Vector6::Zero();
    for (const Active& a : active) {
      const Linearization l = linearize(camera, a, R, t, true);
      if (l.size == 0) continue;
      const double w = huber(l.residual.squaredNorm(), a.delta2, robust).weight;
      H.noalias() += w * l.jacobian.transpose() * l.jacobian;
      g.noalias() += w * l.jacobian.transpose() * l.residual;
    }
    if (g.lpNorm<Eigen::Infinity>() <= kGradientTolerance) return;
    // Rejected steps raise the damping and retry from the same linearization, as Ceres' LM does.
    bool accepted = false;
    while (!accepted && lambda < kMaxLambda) {
      Matrix6 damped = H;
      for (int i = 0; i < 6; ++i) damped(i, i) += lambda * std::clamp(H(i, i), kMinDiagonal, kMaxDiagonal);
      const Vector6 step = damped.ldlt().solve(-g);
      if (!step.allFinite()) {
        lambda *= 10.0;
        continue;
      }
      if (step.norm() <= kParameterTolerance * (t.norm() + kParameterTolerance)) return;
      const double angle = step.head<3>().norm();
      const Eigen::Vector3d axis = angle > 0.0 ? Eigen::Vector3d(step.head<3>() / angle) : Eigen::Vector3d::UnitX();
      const Eigen::Matrix3d R_new = Eigen::AngleAxisd(angle, axis).toRotationMatrix() * R;
      const Eigen::Vector3d t_new = t + step.tail<3>();
      const double new_cost = total_cost(camera, active, R_new, t_new, robust);
      // Gain ratio: actual over predicted decrease of the (Gauss-Newton model of the) cost.
      const double predicted = -(step.dot(g) + 0.5 * step.dot(H * step));
      const double ratio = predicted > 0.0 ? (cost - new_cost) / predicted : -1.0;
      if (ratio > 0.0) {
        accepted = true;
        R = R_new;
        t = t_new;
        const double decrease = cost - new_cost;
        cost = new_cost;
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3));
        lambda_factor = 2.0;
        if (decrease <= kFunctionTolerance * (cost + decrease)) return;
      } else {
        lambda *= lambda_factor;
        lambda_factor *= 2.0;
      }
    }
    if (!accepted) return;
  }
}

}  // namespace

double observation_chi2(const PinholeStereo& camera, const PoseObservation& obs, const Pose3& T_cw,
                        double disparity_sigma_ratio) {
  const Eigen::Vector3d p_c = T_cw * obs.p_w;
  if (p_c.z() <= 0.0) return std::numeric_limits<double>::infinity();
  const Eigen::Vector2d uv = camera.project(p_c);
  double e2 = (uv.x() - obs.u_px) * (uv.x() - obs.u_px) + (uv.y() - obs.v_px) * (uv.y() - obs.v_px);
  if (obs.stereo()) {
    const double disparity_error = (camera.bf() / p_c.z() - (obs.u_px - obs.u_right_px)) /
                                   (disparity_sigma_ratio * obs.disparity_sigma_scale);
    e2 += disparity_error * disparity_error;
  }
  return e2 * obs.inv_sigma2;
}

MotionOnlyBaResult optimize_pose(const PinholeStereo& camera, const std::vector<PoseObservation>& observations,
                                 const Pose3& T_cw_guess, const MotionOnlyBaOptions& options) {
  MotionOnlyBaResult result;
  result.T_cw = T_cw_guess;
  if (!(options.disparity_sigma_ratio > 0.0)) {
    throw std::invalid_argument("MotionOnlyBaOptions.disparity_sigma_ratio: expected > 0");
  }
  result.outlier.assign(observations.size(), false);
  if (observations.empty()) return result;

  Eigen::Matrix3d R = T_cw_guess.rotation();
  Eigen::Vector3d t = T_cw_guess.translation();
  std::vector<Active> active;
  active.reserve(observations.size());
  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robust_rounds;
    active.clear();
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (result.outlier[i]) continue;
      active.push_back(make_active(observations[i], observations[i].stereo() ? options.chi2_stereo : options.chi2_mono,
                                   options.disparity_sigma_ratio));
    }
    const int edges = static_cast<int>(active.size());
    if (edges < kMinEdgesToContinue && round > 0) break;
    if (edges == 0) break;
    solve_round(camera, active, R, t, robust, options.iterations_per_round);

    // Reclassify every observation (outliers may come back), as ORB-SLAM2 does.
    Pose3 T_cw = Pose3::Identity();
    T_cw.linear() = R;
    T_cw.translation() = t;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const double threshold = observations[i].stereo() ? options.chi2_stereo : options.chi2_mono;
      result.outlier[i] = !(observation_chi2(camera, observations[i], T_cw, options.disparity_sigma_ratio) <= threshold);
    }
  }
  result.T_cw = Pose3::Identity();
  result.T_cw.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();  // steps leave rounding in R
  result.T_cw.translation() = t;
  result.inliers = 0;
  for (bool o : result.outlier) result.inliers += o ? 0 : 1;
  return result;
}

}  // namespace heslam
