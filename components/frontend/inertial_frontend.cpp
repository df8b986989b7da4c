// The frontend's inertial side: prediction from preintegrated IMU readings, velocity, initialization.
#include "components/frontend/inertial_frontend.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "components/core/imu/inertial_initialization.hpp"
#include "components/core/imu/so3.hpp"

namespace heslam::frontend {
namespace {

constexpr double kNsPerS = 1e9;
// Readings kept behind the newest frame: the initialization preintegrates between keyframes of the
// last init_max_keyframes, which a moving camera makes within a few seconds.
constexpr std::int64_t kKeepReadingsNs = 20'000'000'000;
// Frames kept for the velocity (and the constant-velocity translation before the initialization).
constexpr std::size_t kMaxFrames = 64;

double seconds(std::int64_t ns) { return static_cast<double>(ns) / kNsPerS; }

}  // namespace

const char* to_string(InertialInitState state) {
  switch (state) {
    case InertialInitState::kWaiting: return "waiting";
    case InertialInitState::kInitialized: return "initialized";
    case InertialInitState::kFailed: return "failed";
    case InertialInitState::kOff: return "off";
  }
  return "unknown";
}

InertialFrontend::InertialFrontend(const InertialOptions& options, const std::string& source)
    : options_(options), buffer_(ImuBufferOptions{.source = source}) {}

void InertialFrontend::set_imu_calibration(const ImuCalibration& calibration) {
  calibration_ = calibration;
  update_extrinsic();
}

void InertialFrontend::set_camera(const Pose3& T_B_rect) {
  T_B_rect_ = T_B_rect;
  update_extrinsic();
}

void InertialFrontend::update_extrinsic() {
  // The IMU in the rectified left camera: T_c_imu = T_B_rect^-1 T_BS(imu) (both into the body frame).
  if (calibration_ && T_B_rect_) T_cb_ = T_B_rect_->inverse() * calibration_->T_BS;
}

std::int64_t InertialFrontend::imu_stamp(std::int64_t camera_stamp_ns) const {
  return camera_stamp_ns + (calibration_ ? calibration_->time_offset_ns : 0);
}

void InertialFrontend::turn_off(const std::string& reason) {
  state_ = InertialInitState::kOff;
  reason_ = reason;
  estimate_.reset();
  frames_.clear();
}

void InertialFrontend::moved(const Pose3& T_corr) {
  const Eigen::Matrix3d R = T_corr.linear();
  for (FrameState& frame : frames_) {
    frame.T_wb = T_corr * frame.T_wb;
    frame.T_wb.linear() = so3::normalized(frame.T_wb.linear());
    if (frame.v_wb) frame.v_wb = R * *frame.v_wb;
  }
  if (predicted_v_) predicted_v_ = R * *predicted_v_;
}

std::optional<ImuPreintegration> InertialFrontend::preintegrate_between(std::int64_t t0_ns, std::int64_t t1_ns) {
  if (t1_ns <= t0_ns) return std::nullopt;
  const ImuInterval interval = buffer_.interval(t0_ns, t1_ns);
  if (interval.coverage != ImuCoverage::kComplete) return std::nullopt;
  const ImuBias bias = estimate_ ? estimate_->bias : ImuBias{};
  return preintegrate(interval.samples, t0_ns, t1_ns, bias, calibration_->noise);
}

InertialFrontend::Prediction InertialFrontend::predict(std::int64_t stamp_ns) {
  Prediction prediction;
  predicted_v_.reset();
  if (off() || !calibration_ || !T_cb_ || frames_.empty()) return prediction;
  const FrameState& last = frames_.back();
  const std::int64_t t1 = imu_stamp(stamp_ns);
  if (t1 <= last.stamp_ns) return prediction;
  const ImuInterval interval = buffer_.interval(last.stamp_ns, t1);
  prediction.coverage = interval.coverage;
  if (interval.coverage != ImuCoverage::kComplete) {
    if (interval.coverage == ImuCoverage::kGap) ++gaps_;
    prediction.message = interval.message;
    return prediction;
  }
  const ImuBias bias = estimate_ ? bias_at(last) : ImuBias{};
  const ImuPreintegration pre = preintegrate(interval.samples, last.stamp_ns, t1, bias, calibration_->noise);
  ++predictions_;
  if (state_ == InertialInitState::kInitialized && last.v_wb) {
    NavState start;
    start.R_wb = last.T_wb.linear();
    start.p_wb = last.T_wb.translation();
    start.v_wb = *last.v_wb;
    const NavState end = pre.predict(start, estimate_->gravity_w, bias);
    Pose3 T_wb = Pose3::Identity();
    T_wb.linear() = so3::normalized(end.R_wb);
    T_wb.translation() = end.p_wb;
    prediction.T_wc = camera_pose(T_wb);
    // The IMU carries the pose through a blackout only from a state vision confirmed lately.
    if (last_visual_ns_ && seconds(t1 - *last_visual_ns_) <= options_.blackout_max_s) {
      prediction.fallback = prediction.T_wc;
      prediction.v = end.v_wb;
    }
    predicted_v_ = end.v_wb;
    if (options_.pose_optimization && last.visual && pre.duration_s() > 0.0 &&
        gravity_stddev_deg_ <= options_.pose_optimization_max_gravity_stddev_deg) {
      InertialPoseConstraint constraint;
      constraint.preintegration = pre;
      constraint.previous = start;
      constraint.previous_bias = bias;
      constraint.gravity_w = estimate_->gravity_w;
      constraint.T_cb = *T_cb_;
      constraint.prior_rotation_rad = options_.pose_prior_rotation_rad;
      constraint.prior_position_m = options_.pose_prior_position_m;
      constraint.prior_velocity_m_s = options_.pose_prior_velocity_m_s;
      prediction.constraint = std::move(constraint);
    }
    return prediction;
  }
  // Before the initialization: the gyroscope's rotation, the constant-velocity model's translation.
  Pose3 T_wb = last.T_wb;
  T_wb.linear() = so3::normalized(last.T_wb.linear() * pre.delta_R());
  Pose3 T_wc = camera_pose(T_wb);
  const Pose3 last_T_wc = camera_pose(last.T_wb);
  if (frames_.size() >= 2 && last.visual && frames_[frames_.size() - 2].visual) {
    const Pose3 before_T_wc = camera_pose(frames_[frames_.size() - 2].T_wb);
    T_wc.translation() = (last_T_wc * (before_T_wc.inverse() * last_T_wc)).translation();
  } else {
    T_wc.translation() = last_T_wc.translation();
  }
  prediction.T_wc = T_wc;
  return prediction;
}

void InertialFrontend::estimate_velocity(FrameState& current) {
  // The tracked frame about velocity_window_s before: v_j from the two positions and the
  // preintegration between them, carried to this frame (Forster eq. 38 solved for v_j).
  const FrameState* from = nullptr;
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
    if (!it->visual) continue;
    if (seconds(current.stamp_ns - it->stamp_ns) >= options_.velocity_window_s) {
      from = &*it;
      break;
    }
  }
  if (from == nullptr) {
    // Not that long yet: the oldest visual frame, if a quarter of the window back.
    const auto oldest = std::find_if(frames_.begin(), frames_.end(), [](const FrameState& f) { return f.visual; });
    if (oldest != frames_.end() && seconds(current.stamp_ns - oldest->stamp_ns) >= 0.25 * options_.velocity_window_s) {
      from = &*oldest;
    }
  }
  if (from == nullptr) return;
  const std::optional<ImuPreintegration> pre = preintegrate_between(from->stamp_ns, current.stamp_ns);
  if (!pre) return;
  const double dt = pre->duration_s();
  const Eigen::Vector3d& g = estimate_->gravity_w;
  const Eigen::Matrix3d R_j = from->T_wb.linear();
  const Eigen::Vector3d v_j = (current.T_wb.translation() - from->T_wb.translation() - 0.5 * g * dt * dt -
                               R_j * pre->delta_p(estimate_->bias)) /
                              dt;
  current.v_wb = v_j + g * dt + R_j * pre->delta_v(estimate_->bias);
}

std::optional<std::string> InertialFrontend::update(std::int64_t stamp_ns, const TrackResult& result, const Map& map) {
  if (off() || !calibration_ || !T_cb_) return std::nullopt;
  const std::int64_t t = imu_stamp(stamp_ns);
  buffer_.discard_before(t - kKeepReadingsNs);
  if (result.state == TrackingState::kOk) {
    FrameState frame;
    frame.stamp_ns = t;
    frame.T_wb = body_pose(result.T_wc);
    frame.visual = true;
    if (state_ == InertialInitState::kInitialized) {
      if (result.inertial_state) {
        frame.v_wb = result.inertial_state->v_wb;
        frame.bias = result.inertial_state->bias;
        ++pose_optimizations_;
      } else {
        estimate_velocity(frame);
      }
    }
    frames_.push_back(frame);
    last_visual_ns_ = t;
    if (result.new_keyframe && !first_keyframe_ns_) first_keyframe_ns_ = t;
  } else if (result.state == TrackingState::kInertialOnly) {
    FrameState frame;
    frame.stamp_ns = t;
    frame.T_wb = body_pose(result.T_wc);
    frame.v_wb = predicted_v_;
    if (!frames_.empty()) frame.bias = frames_.back().bias;  // the biases the prediction used
    frames_.push_back(frame);
  } else {
    frames_.clear();  // lost: no pose to predict from until vision tracks again
  }
  while (frames_.size() > kMaxFrames) frames_.pop_front();
  if (state_ == InertialInitState::kInitialized &&
      (!initialized_ns_ || seconds(t - *initialized_ns_) > options_.refine_until_s)) {
    return std::nullopt;
  }
  return try_initialize(t, map);
}

std::optional<Eigen::Vector3d> InertialFrontend::velocity() const {
  if (frames_.empty()) return std::nullopt;
  return frames_.back().v_wb;
}

std::optional<ImuBias> InertialFrontend::bias() const {
  if (frames_.empty() || !estimate_) return std::nullopt;
  return bias_at(frames_.back());
}

}  // namespace heslam::frontend

namespace heslam::frontend {

std::optional<std::string> InertialFrontend::try_initialize(std::int64_t stamp_ns, const Map& map) {
  if (next_init_ns_ && stamp_ns < *next_init_ns_) return std::nullopt;
  if (frames_.empty() || !frames_.back().visual) return std::nullopt;
  // The keyframes of the map (refined by the mapper, when one runs), oldest first, the newest
  // init_max_keyframes of them, as IMU body poses.
  std::vector<std::pair<std::int64_t, Pose3>> keyframes;
  for (const auto& [id, keyframe] : map.keyframes) {
    if (keyframe.culled) continue;
    const std::int64_t t = imu_stamp(keyframe.stamp_ns);
    if (t <= stamp_ns) keyframes.emplace_back(t, body_pose(keyframe.T_wc));
  }
  std::sort(keyframes.begin(), keyframes.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  keyframes.erase(
      std::unique(keyframes.begin(), keyframes.end(), [](const auto& a, const auto& b) { return a.first == b.first; }),
      keyframes.end());
  const auto max_keyframes = static_cast<std::size_t>(options_.init_max_keyframes);
  if (keyframes.size() > max_keyframes) keyframes.erase(keyframes.begin(), keyframes.end() - max_keyframes);
  // Only the newest run of keyframes with IMU readings between each pair (a gap cuts it).
  InertialInitInput input;
  for (std::size_t k = keyframes.size(); k-- > 0;) {
    if (input.T_wb.empty()) {
      input.T_wb.push_back(keyframes[k].second);
      input.stamps_ns.push_back(keyframes[k].first);
      continue;
    }
    const std::optional<ImuPreintegration> pre = preintegrate_between(keyframes[k].first, input.stamps_ns.back());
    if (!pre) break;
    input.T_wb.push_back(keyframes[k].second);
    input.stamps_ns.push_back(keyframes[k].first);
    input.intervals.push_back(*pre);
  }
  std::reverse(input.T_wb.begin(), input.T_wb.end());
  std::reverse(input.stamps_ns.begin(), input.stamps_ns.end());
  std::reverse(input.intervals.begin(), input.intervals.end());
  if (static_cast<int>(input.T_wb.size()) < options_.init_min_keyframes ||
      seconds(input.stamps_ns.back() - input.stamps_ns.front()) < options_.init_min_duration_s) {
    return std::nullopt;  // still waiting for enough keyframes
  }
  ++init_attempts_;
  InertialInitOptions init_options;
  init_options.min_duration_s = options_.init_min_duration_s;
  init_options.min_intervals = options_.init_min_keyframes - 1;
  init_options.max_gravity_stddev_deg = options_.init_max_gravity_stddev_deg;
  init_options.max_accel_bias_stddev_m_s2 = options_.init_max_accel_bias_stddev_m_s2;
  init_options.max_gravity_stddev_of_prior = options_.init_max_gravity_stddev_of_prior;
  InertialInitResult result;
  try {
    result = initialize_inertial(input, init_options);
    if (result.ok) {
      // Preintegrated again around the biases found, so that no first-order correction is left.
      for (std::size_t k = 0; k < input.intervals.size(); ++k) {
        const ImuInterval interval = buffer_.interval(input.stamps_ns[k], input.stamps_ns[k + 1]);
        if (interval.coverage != ImuCoverage::kComplete) continue;
        input.intervals[k] = preintegrate(interval.samples, input.stamps_ns[k], input.stamps_ns[k + 1], result.bias,
                                          calibration_->noise);
      }
      init_options.prior_bias = result.bias;
      const InertialInitResult again = initialize_inertial(input, init_options);
      if (again.ok) result = again;
    }
  } catch (const std::exception& error) {
    result.ok = false;
    result.reason = error.what();
  }
  const std::string over = std::to_string(input.T_wb.size()) + " keyframes over " +
                           std::to_string(seconds(input.stamps_ns.back() - input.stamps_ns.front())) + " s";
  const bool refining = state_ == InertialInitState::kInitialized;
  if (refining) {
    next_init_ns_ = stamp_ns + static_cast<std::int64_t>(options_.refine_every_s * kNsPerS);
    if (!result.ok || result.gravity_stddev_deg >= gravity_stddev_deg_) return std::nullopt;  // keeps the estimate
    ++refinements_;
  }
  if (!result.ok) {
    state_ = InertialInitState::kFailed;
    reason_ = result.reason;
    next_init_ns_ = stamp_ns + static_cast<std::int64_t>(options_.init_retry_s * kNsPerS);
    return "inertial initialization not possible yet (" + over + "): " + result.reason +
           "; tracking stereo-only, tried again in " + std::to_string(options_.init_retry_s) + " s";
  }
  estimate_ = InertialEstimate{result.gravity_w(init_options.gravity_m_s2), result.bias};
  state_ = InertialInitState::kInitialized;
  gravity_stddev_deg_ = result.gravity_stddev_deg;
  reason_.clear();
  if (!initialized_ns_) initialized_ns_ = stamp_ns;
  for (FrameState& frame : frames_) frame.bias.reset();  // the new estimate's biases from now on
  if (!refining) next_init_ns_ = stamp_ns + static_cast<std::int64_t>(options_.refine_every_s * kNsPerS);
  estimate_velocity(frames_.back());
  std::ostringstream line;
  line << (refining ? "inertial estimate refined over " : "inertial initialization over ") << over << ": gravity ("
       << estimate_->gravity_w.transpose() << ") m/s^2 in the tracker's world (stddev " << result.gravity_stddev_deg
       << " deg), gyro bias (" << result.bias.gyro_rad_s.transpose() << ") rad/s, accel bias ("
       << result.bias.accel_m_s2.transpose() << ") m/s^2, whitened rms " << result.rms;
  return line.str();
}

}  // namespace heslam::frontend
