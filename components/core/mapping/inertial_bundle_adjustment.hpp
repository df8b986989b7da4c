// Inertial local bundle adjustment (ORB-SLAM3's Optimizer::LocalInertialBA), solved by the visual BA's own solver.
//
// The visual part is local_bundle_adjustment.hpp's: the new keyframe and its covisible keyframes free,
// the other observers of their points fixed, the map's origin keyframe fixed, stereo / monocular
// reprojection residuals whitened by the keypoint's level under Huber at the chi2 95 % threshold, two
// passes with the outliers of the first left out of the second and unlinked at the end. The inertial
// part: the newest keyframes in time order (`window.chain`, oldest first) each get a velocity and a
// gyroscope and accelerometer bias block, and consecutive ones an IMU factor (imu_factor.hpp, the
// preintegration between their stamps) and a bias random walk factor. The chain's oldest keyframe is
// held fixed (pose, and unless hold_anchor is false velocity and biases: it anchors the chain, as
// ORB-SLAM3's keyframe before its window); the others are free, poses included.
//
// Poses stay camera poses (PoseBlock, PoseManifold, as the visual BA and the loop closer's global BA);
// the IMU factor's body pose is T_wb = T_wc * T_cb with the IMU-camera extrinsic T_cb (IMU -> camera).
// The IMU terms are the solver's extra terms (bundle_adjustment_solver.hpp): velocity and biases per chain
// keyframe and gravity's direction join the free poses in its reduced system; the stop request ends it too.
#pragma once

#include <map>
#include <vector>

#include <ceres/ceres.h>

#include <Eigen/Core>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/imu/imu_factor.hpp"
#include "components/core/imu/preintegration.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/bundle_adjustment_terms.hpp"
#include "components/core/mapping/local_bundle_adjustment.hpp"
#include "components/core/mapping/local_mapper_options.hpp"
#include "components/core/mapping/map_changes.hpp"

namespace heslam {

// A keyframe's inertial state besides its pose: the body's velocity in the world and the IMU biases.
struct InertialKeyframeState {
  Eigen::Vector3d v_wb = Eigen::Vector3d::Zero();
  ImuBias bias;
};

struct InertialWindow {
  Pose3 T_cb = Pose3::Identity();  // IMU body -> rectified left camera
  Eigen::Vector3d gravity_w = Eigen::Vector3d(0.0, 0.0, -9.81);
  // Keyframes in time order, oldest first (at least 2); intervals[k] preintegrates the IMU between
  // chain[k] and chain[k + 1] around states[chain[k]].bias.
  std::vector<KeyframeId> chain;
  std::vector<ImuPreintegration> intervals;
  // In: the state of every chain keyframe; out: the optimized states of the free ones.
  std::map<KeyframeId, InertialKeyframeState> states;
  // The anchor's velocity and biases held (its pose always is); false for a guessed state (after a gap).
  bool hold_anchor = true;
  // > 0: the direction of gravity is estimated too (its magnitude kept), with a prior of this stddev
  // (radians) around gravity_w; out: the estimate. 0: gravity held.
  double gravity_stddev_rad = 0.0;
};

struct InertialBundleAdjustmentResult {
  LocalBundleAdjustmentResult visual;  // the same figures as the visual BA's
  int inertial_keyframes = 0;          // chain keyframes with free velocity and biases
  int imu_factors = 0;
  bool solved = false;  // false: nothing was written back (non-finite or failed solve, bad window)
  double initial_cost = 0.0;
  double final_cost = 0.0;
};

// Runs on `map` in place (moved keyframes / points and removed points recorded in `changes`) and
// updates window.states. Throws std::invalid_argument when the window is inconsistent (sizes, a chain
// keyframe missing from the map or from states).
InertialBundleAdjustmentResult inertial_local_bundle_adjustment(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                                const LocalBundleAdjustmentOptions& options,
                                                                InertialWindow& window, MapChanges& changes);

// The IMU factor on two camera pose blocks (PoseBlock: q_cw x y z w, t_cw) with T_wb = T_wc * T_cb:
// blocks pose_i (7), v_i, bg_i, ba_i, pose_j (7), v_j, gravity_w (3); 9 residuals. Its Jacobians are in PoseManifold's
// tangent space (first 6 columns, the 7th zero), as ReprojectionCost's.
class ImuCameraCost : public ceres::SizedCostFunction<9, 7, 3, 3, 3, 7, 3, 3> {
 public:
  ImuCameraCost(const ImuPreintegration& preintegration, const Pose3& T_cb);
  bool Evaluate(const double* const* parameters, double* residuals, double** jacobians) const override;

  struct Functor {
    ImuIntervalResidual residual;
    Eigen::Matrix3d R_cb;
    Eigen::Vector3d t_cb;

    template <typename T>
    bool operator()(const T* pose_i, const T* v_i, const T* bg_i, const T* ba_i, const T* pose_j, const T* v_j,
                    const T* gravity_w, T* out) const {
      using Vector3 = Eigen::Matrix<T, 3, 1>;
      using Matrix3 = Eigen::Matrix<T, 3, 3>;
      const auto body = [&](const T* pose, Matrix3& R_wb, Vector3& p_wb) {
        const Eigen::Quaternion<T> q_cw = Eigen::Map<const Eigen::Quaternion<T>>(pose).normalized();
        const Matrix3 R_wc = q_cw.toRotationMatrix().transpose();
        const Vector3 p_wc = -(R_wc * Eigen::Map<const Vector3>(pose + 4));
        R_wb = R_wc * R_cb.cast<T>();
        p_wb = R_wc * t_cb.cast<T>() + p_wc;
      };
      Matrix3 R_wi, R_wj;
      Vector3 p_wi, p_wj;
      body(pose_i, R_wi, p_wi);
      body(pose_j, R_wj, p_wj);
      residual.evaluate<T>(R_wi, p_wi, Eigen::Map<const Vector3>(v_i), Eigen::Map<const Vector3>(bg_i),
                           Eigen::Map<const Vector3>(ba_i), R_wj, p_wj, Eigen::Map<const Vector3>(v_j),
                           Eigen::Map<const Vector3>(gravity_w), out);
      return true;
    }
  };

 private:
  ceres::AutoDiffCostFunction<Functor, 9, 7, 3, 3, 3, 7, 3, 3> autodiff_;
};

}  // namespace heslam
