// Motion-only bundle adjustment: a 6-dof Levenberg-Marquardt on the pose alone with analytic Jacobians.
//
// The problem is one 6-parameter block against a few hundred fixed points, solved 8 times a frame
// (2 optimizations x 4 rounds). With Ceres, building a Problem per round, its preprocessing and the
// autodiff Jacobians through angle-axis rotations cost more than the arithmetic itself; here the
// 6x6 normal equations are accumulated directly (g2o's way, as in ORB-SLAM2).
//
// One pass over the observations per trial pose: it projects every point, sums the robust cost the
// step is judged by, and writes each residual row's Jacobian into columns (NormalEquations); an
// accepted step's normal equations then come from those columns as 27 dot products (the 21 entries
// of the symmetric H's upper triangle and the 6 of g), no second projection at the same pose.
#include "components/core/tracking/motion_only_ba.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "components/core/solve/dense_levenberg_marquardt.hpp"

namespace heslam {
namespace {

// Fewer residuals than this and another round cannot classify anything reliably (ORB-SLAM2 stops too).
constexpr int kMinEdgesToContinue = 10;
// A point this close to (or behind) the camera plane gives no usable projection in an iteration.
constexpr double kMinDepthM = 1e-9;

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

// An observation in a round, with its square-root informations computed once per round instead of at
// every projection, and the first of its residual rows (2 mono, 3 stereo) in the columns.
struct Active {
  const PoseObservation* obs;
  double delta2;               // Huber threshold on the squared whitened error
  double sqrt_info;            // sqrt(obs->inv_sigma2)
  double disparity_sqrt_info;  // sqrt_info / (disparity_sigma_ratio * obs->disparity_sigma_scale)
  std::size_t row;
};

// The stacked whitened residual rows of the active observations at one pose, by column: the six
// Jacobian entries d(row)/d[w, r] (R' = Exp(w) R, t' = t + r), the same times the row's IRLS weight,
// and the residual. A row of an observation unusable at the pose (behind the camera) is all zero.
struct NormalEquations {
  std::array<double*, 6> jacobian{};
  std::array<double*, 6> weighted{};
  double* residual = nullptr;
  double* cost = nullptr;        // per observation: robust cost (0 when unusable)
  std::size_t rows = 0;          // rows in use this round
  std::size_t observations = 0;  // observations in use this round

  // Room for up to max_rows rows of max_observations observations, once per optimization and not
  // zero-filled (zeroing the columns was 7 % of the tracking's instructions; every slot in use is
  // written by each pass before it is read).
  void reserve(std::size_t max_rows, std::size_t max_observations) {
    storage_ = std::make_unique_for_overwrite<double[]>(13 * max_rows + max_observations);
    double* next = storage_.get();
    for (double*& column : jacobian) column = std::exchange(next, next + max_rows);
    for (double*& column : weighted) column = std::exchange(next, next + max_rows);
    residual = std::exchange(next, next + max_rows);
    cost = next;
  }

 private:
  std::unique_ptr<double[]> storage_;
};

void clear_rows(NormalEquations& ne, std::size_t row, std::size_t count) {
  for (std::size_t k = row; k < row + count; ++k) {
    for (int c = 0; c < 6; ++c) {
      ne.jacobian[static_cast<std::size_t>(c)][k] = 0.0;
      ne.weighted[static_cast<std::size_t>(c)][k] = 0.0;
    }
    ne.residual[k] = 0.0;
  }
}

void set_row(NormalEquations& ne, std::size_t row, const std::array<double, 6>& j, double weight, double residual) {
  for (std::size_t c = 0; c < 6; ++c) {
    ne.jacobian[c][row] = j[c];
    ne.weighted[c][row] = weight * j[c];
  }
  ne.residual[row] = residual;
}

// Projects observations [begin, end) at (R, t): their costs and rows. Touches only their own slots.
void fill(const PinholeStereo& camera, const std::vector<Active>& active, std::size_t begin, std::size_t end,
          const Eigen::Matrix3d& R, const Eigen::Vector3d& t, bool robust, NormalEquations& ne) {
  const double bf = camera.bf();
  for (std::size_t k = begin; k < end; ++k) {
    const Active& a = active[k];
    const PoseObservation& obs = *a.obs;
    const bool stereo = obs.stereo();
    const Eigen::Vector3d p_r = R * obs.p_w;
    const Eigen::Vector3d p_c = p_r + t;
    if (!(p_c.z() > kMinDepthM)) {
      ne.cost[k] = 0.0;
      clear_rows(ne, a.row, stereo ? 3 : 2);
      continue;
    }
    const double s = a.sqrt_info;
    const double inv_z = 1.0 / p_c.z();
    const double x = p_c.x() * inv_z;
    const double y = p_c.y() * inv_z;
    const double r0 = (camera.fx_px * x + camera.cx_px - obs.u_px) * s;
    const double r1 = (camera.fy_px * y + camera.cy_px - obs.v_px) * s;
    const double r2 = stereo ? (bf * inv_z - (obs.u_px - obs.u_right_px)) * a.disparity_sqrt_info : 0.0;
    const Robust rho = huber(r0 * r0 + r1 * r1 + r2 * r2, a.delta2, robust);
    ne.cost[k] = rho.cost;
    // d(residual)/d(p_c), whitened: [a 0 b; 0 c d; 0 0 e], times d(p_c)/d[w, r] = [-[p_r]x I].
    const double da = camera.fx_px * inv_z * s;
    const double db = -camera.fx_px * x * inv_z * s;
    const double dc = camera.fy_px * inv_z * s;
    const double dd = -camera.fy_px * y * inv_z * s;
    const double X = p_r.x();
    const double Y = p_r.y();
    const double Z = p_r.z();
    set_row(ne, a.row, {db * Y, da * Z - db * X, -da * Y, da, 0.0, db}, rho.weight, r0);
    set_row(ne, a.row + 1, {dd * Y - dc * Z, -dd * X, dc * X, 0.0, dc, dd}, rho.weight, r1);
    if (stereo) {
      const double de = -bf * inv_z * inv_z * a.disparity_sqrt_info;
      set_row(ne, a.row + 2, {de * Y, -de * X, 0.0, 0.0, 0.0, de}, rho.weight, r2);
    }
  }
}

// H (symmetric: its upper triangle mirrored) and g from the rows, each entry one dot product of two
// columns in row order.
void normal_equations(const NormalEquations& ne, Matrix6& H, Vector6& g) {
  using Column = Eigen::Map<const Eigen::VectorXd>;
  const Eigen::Index n = static_cast<Eigen::Index>(ne.rows);
  const Column residual(ne.residual, n);
  for (std::size_t i = 0; i < 6; ++i) {
    const Column weighted(ne.weighted[i], n);
    for (std::size_t j = i; j < 6; ++j) {
      const double h = weighted.dot(Column(ne.jacobian[j], n));
      H(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = h;
      H(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(i)) = h;
    }
    g(static_cast<Eigen::Index>(i)) = weighted.dot(residual);
  }
}

// Half the total robust cost (as Ceres reports it), summed in observation order.
double total_cost(const NormalEquations& ne) {
  double cost = 0.0;
  for (std::size_t k = 0; k < ne.observations; ++k) cost += ne.cost[k];
  return 0.5 * cost;
}

// The pass at one pose over all active observations.
void evaluate(const PinholeStereo& camera, const std::vector<Active>& active, const Eigen::Matrix3d& R,
              const Eigen::Vector3d& t, bool robust, NormalEquations& ne) {
  fill(camera, active, 0, active.size(), R, t, robust, ne);
}

// One round's problem for dense_levenberg_marquardt(): the pose, one pass over the active
// observations per trial pose, the normal equations of an accepted pose only (from its columns).
struct PoseProblem {
  struct State {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
  };
  const PinholeStereo& camera;
  const std::vector<Active>& active;
  bool robust;
  NormalEquations& current;  // the pass at the accepted pose
  NormalEquations& trial;    // a step's

  double evaluate_trial(const State& x) {
    evaluate(camera, active, x.R, x.t, robust, trial);
    return total_cost(trial);
  }
  void accept_trial() { std::swap(current, trial); }
  void normal_equations(Matrix6& H, Vector6& g) const { heslam::normal_equations(current, H, g); }
  static State plus(const State& x, const Vector6& step) {
    const double angle = step.head<3>().norm();
    const Eigen::Vector3d axis = angle > 0.0 ? Eigen::Vector3d(step.head<3>() / angle) : Eigen::Vector3d::UnitX();
    return {Eigen::AngleAxisd(angle, axis).toRotationMatrix() * x.R, x.t + step.tail<3>()};
  }
  static double norm(const State& x) { return x.t.norm(); }
};

// One round: at most `iterations` LM steps on the active observations; updates R and t.
void solve_round(const PinholeStereo& camera, const std::vector<Active>& active, Eigen::Matrix3d& R, Eigen::Vector3d& t,
                 bool robust, int iterations, NormalEquations& current, NormalEquations& trial) {
  PoseProblem problem{camera, active, robust, current, trial};
  PoseProblem::State x{R, t};
  const double cost = problem.evaluate_trial(x);
  problem.accept_trial();
  dense_levenberg_marquardt<6>(problem, x, cost, iterations);
  R = x.R;
  t = x.t;
}

}  // namespace

double observation_chi2(const PinholeStereo& camera, const PoseObservation& obs, const Pose3& T_cw,
                        double disparity_sigma_ratio) {
  const Eigen::Vector3d p_c = T_cw * obs.p_w;
  if (p_c.z() <= 0.0) return std::numeric_limits<double>::infinity();
  const Eigen::Vector2d uv = camera.project(p_c);
  double e2 = (uv.x() - obs.u_px) * (uv.x() - obs.u_px) + (uv.y() - obs.v_px) * (uv.y() - obs.v_px);
  if (obs.stereo()) {
    const double disparity_error =
        (camera.bf() / p_c.z() - (obs.u_px - obs.u_right_px)) / (disparity_sigma_ratio * obs.disparity_sigma_scale);
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
  NormalEquations current;
  NormalEquations trial;
  std::size_t max_rows = 0;
  for (const PoseObservation& obs : observations) max_rows += obs.stereo() ? 3 : 2;
  current.reserve(max_rows, observations.size());
  trial.reserve(max_rows, observations.size());
  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robust_rounds;
    active.clear();
    std::size_t rows = 0;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (result.outlier[i]) continue;
      const PoseObservation& obs = observations[i];
      const double sqrt_info = std::sqrt(obs.inv_sigma2);
      active.push_back({&obs, obs.stereo() ? options.chi2_stereo : options.chi2_mono, sqrt_info,
                        sqrt_info / (options.disparity_sigma_ratio * obs.disparity_sigma_scale), rows});
      rows += obs.stereo() ? 3 : 2;
    }
    const int edges = static_cast<int>(active.size());
    if (edges < kMinEdgesToContinue && round > 0) break;
    if (edges == 0) break;
    current.rows = trial.rows = rows;
    current.observations = trial.observations = active.size();
    solve_round(camera, active, R, t, robust, options.iterations_per_round, current, trial);

    // Reclassify every observation (outliers may come back), as ORB-SLAM2 does.
    Pose3 T_cw = Pose3::Identity();
    T_cw.linear() = R;
    T_cw.translation() = t;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const double threshold = observations[i].stereo() ? options.chi2_stereo : options.chi2_mono;
      result.outlier[i] =
          !(observation_chi2(camera, observations[i], T_cw, options.disparity_sigma_ratio) <= threshold);
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
