// SE(3) pose-graph optimization: keyframe poses T_wc as vertices, measured relative poses as edges,
// some vertices held fixed; Gauss-Newton with Levenberg-Marquardt damping on the block-sparse normal
// equations (Eigen's simplicial Cholesky), the convergence tests Ceres uses (relative cost change
// 1e-6). The loop closer's essential-graph optimization (ORB-SLAM2's OptimizeEssentialGraph, here
// SE(3) because stereo fixes the scale).
//
// Edge residual (6-vector, in the `from` keyframe's frame): translation of T_from_to estimated minus
// measured, and 2 vec(q_measured^-1 q_estimated) for the rotation; scaled by sqrt(weight). With
// weight 1 this matches ORB-SLAM2's identity information (rotation in radians, translation in m).
// Single-threaded and deterministic: the same input gives the same poses bit for bit.
//
// Inertial mode (options.four_dof, VINS-Mono's and ORB-SLAM3's 4-DoF pose graph): the IMU observes
// gravity, so roll and pitch are not drift directions; each free vertex then moves only by a yaw about
// the world's gravity axis (options.gravity_w, any world convention) and a translation. The residual is
// the same 6-vector; the direction of gravity in every camera stays exactly as it was.
#pragma once

#include <map>
#include <set>
#include <vector>

#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"

namespace heslam {

struct PoseGraphEdge {
  KeyframeId from = kNoId;
  KeyframeId to = kNoId;
  Pose3 T_from_to = Pose3::Identity();  // measured: T_wc(from)^-1 * T_wc(to)
  double weight = 1.0;                  // information = weight x identity
};

struct PoseGraphOptions {
  int max_iterations = 20;   // ORB-SLAM2: 20 Levenberg-Marquardt iterations
  bool robust = false;       // ORB-SLAM2 uses no robust kernel on the essential graph
  double huber_delta = 0.1;  // with `robust`: residual norm (rad / m) beyond which an edge counts linearly
  // Inertial runs: optimize yaw about gravity and translation only (4 DoF per vertex); roll and pitch
  // with respect to gravity_w (gravity's direction in the world frame, any length) are kept.
  bool four_dof = false;
  Eigen::Vector3d gravity_w = Eigen::Vector3d(0.0, 0.0, -1.0);
};

struct PoseGraphStats {
  int vertices = 0;  // vertices touched by an edge
  int fixed_vertices = 0;
  int edges = 0;
  int skipped_edges = 0;      // edges naming an unknown vertex (or a self loop)
  double initial_cost = 0.0;  // Ceres cost, 1/2 sum of squared residuals
  double final_cost = 0.0;
  int iterations = 0;
  double time_ms = 0.0;
};

struct PoseGraphResult {
  std::map<KeyframeId, Pose3> T_wc;  // every input vertex; fixed and edge-less ones unchanged
  PoseGraphStats stats;
};

// The part of rotation R that turns about the direction of gravity_w (swing-twist decomposition: R =
// twist * swing, swing turning about an axis orthogonal to gravity): what a 4-DoF graph may change of
// a rotation. gravity_w: any length; not zero.
Eigen::Matrix3d yaw_about_gravity(const Eigen::Matrix3d& R, const Eigen::Vector3d& gravity_w);

class PoseGraph {
 public:
  explicit PoseGraph(const PoseGraphOptions& options = {}) : options_(options) {}

  PoseGraphResult compute(const std::map<KeyframeId, Pose3>& initial_T_wc, const std::vector<PoseGraphEdge>& edges,
                          const std::set<KeyframeId>& fixed) const;

 private:
  PoseGraphOptions options_;
};

}  // namespace heslam
