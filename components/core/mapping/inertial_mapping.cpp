// The local mapper's inertial side (see inertial_mapping.hpp).
#include "components/core/mapping/inertial_mapping.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

#include "components/core/map/ids.hpp"

namespace heslam {
namespace {

constexpr double kNsPerS = 1e9;

double seconds(std::int64_t ns) { return static_cast<double>(ns) / kNsPerS; }

}  // namespace

InertialMapping::InertialMapping(const InertialMappingOptions& options, const std::string& source)
    : options_(options), buffer_([&] {
        ImuBufferOptions buffer_options = options.buffer;
        buffer_options.source = source;
        return buffer_options;
      }()) {}

void InertialMapping::set_imu_calibration(const ImuCalibration& calibration) {
  calibration_ = calibration;
  if (T_B_rect_) T_cb_ = T_B_rect_->inverse() * calibration_->T_BS;
}

void InertialMapping::set_camera(const Pose3& T_B_rect) {
  T_B_rect_ = T_B_rect;
  if (calibration_) T_cb_ = T_B_rect_->inverse() * calibration_->T_BS;
}

std::int64_t InertialMapping::imu_stamp(std::int64_t camera_stamp_ns) const {
  return camera_stamp_ns + (calibration_ ? calibration_->time_offset_ns : 0);
}

void InertialMapping::turn_off(const std::string& reason) {
  if (off_) return;
  off_ = true;
  warn_once("off", "IMU off: " + reason + "; the local BA goes on visual only");
}

void InertialMapping::warn_once(const std::string& kind, const std::string& message) {
  if (!warned_.insert(kind).second || !warn_) return;
  warn_(message);
}

std::optional<ImuPreintegration> InertialMapping::interval(std::int64_t t0, std::int64_t t1, const ImuBias& bias,
                                                           std::string& why) const {
  const ImuInterval readings = buffer_.interval(t0, t1);
  if (readings.coverage != ImuCoverage::kComplete) {
    why = readings.message;
    return std::nullopt;
  }
  return preintegrate(readings.samples, t0, t1, bias, calibration_->noise);
}

bool InertialMapping::try_initialize(const Map& map, std::int64_t t) {
  const bool refining = initialized_;
  if (refining && (t < next_refine_ns_ || seconds(t - *initialized_ns_) > options_.refine_until_s)) return false;
  // The newest keyframes (IMU stamps, body poses), oldest first.
  std::vector<std::pair<std::int64_t, KeyframeId>> keyframes;
  for (const auto& [id, keyframe] : map.keyframes) {
    if (!keyframe.culled && imu_stamp(keyframe.stamp_ns) <= t) keyframes.emplace_back(imu_stamp(keyframe.stamp_ns), id);
  }
  std::sort(keyframes.begin(), keyframes.end());
  keyframes.erase(
      std::unique(keyframes.begin(), keyframes.end(), [](const auto& a, const auto& b) { return a.first == b.first; }),
      keyframes.end());
  const auto max_keyframes = static_cast<std::size_t>(options_.init_max_keyframes);
  if (keyframes.size() > max_keyframes) keyframes.erase(keyframes.begin(), keyframes.end() - max_keyframes);
  // Only the newest run of keyframes with IMU readings between each pair (a gap cuts it).
  InertialInitInput input;
  std::vector<KeyframeId> ids;
  for (std::size_t k = keyframes.size(); k-- > 0;) {
    if (!ids.empty()) {
      std::string why;
      const std::optional<ImuPreintegration> pre =
          interval(keyframes[k].first, input.stamps_ns.back(), options_.init.prior_bias, why);
      if (!pre) break;
      input.intervals.push_back(*pre);
    }
    ids.push_back(keyframes[k].second);
    input.T_wb.push_back(map.keyframes.at(keyframes[k].second).T_wc * *T_cb_);
    input.stamps_ns.push_back(keyframes[k].first);
  }
  std::reverse(ids.begin(), ids.end());
  std::reverse(input.T_wb.begin(), input.T_wb.end());
  std::reverse(input.stamps_ns.begin(), input.stamps_ns.end());
  std::reverse(input.intervals.begin(), input.intervals.end());
  if (static_cast<int>(ids.size()) < options_.init_min_keyframes ||
      seconds(input.stamps_ns.back() - input.stamps_ns.front()) < options_.init_min_duration_s) {
    return false;  // still waiting for enough keyframes
  }
  ++counts_.init_attempts;
  if (refining) next_refine_ns_ = t + static_cast<std::int64_t>(options_.refine_every_s * kNsPerS);
  InertialInitOptions init_options = options_.init;
  init_options.min_duration_s = options_.init_min_duration_s;
  init_options.min_intervals = options_.init_min_keyframes - 1;
  InertialInitResult result;
  try {
    result = initialize_inertial(input, init_options);
    if (result.ok) {  // preintegrated again around the biases found: no first-order correction left
      for (std::size_t k = 0; k < input.intervals.size(); ++k) {
        std::string why;
        if (auto pre = interval(input.stamps_ns[k], input.stamps_ns[k + 1], result.bias, why))
          input.intervals[k] = *pre;
      }
      init_options.prior_bias = result.bias;
      const InertialInitResult again = initialize_inertial(input, init_options);
      if (again.ok) result = again;
    }
  } catch (const std::exception& error) {
    result.ok = false;
    result.reason = error.what();
  }
  if (!result.ok) {
    if (!refining)
      warn_once("init", "inertial initialization not possible yet: " + result.reason +
                            " (tried again at each keyframe, the visual local BA meanwhile)");
    return false;
  }
  if (refining && result.gravity_stddev_deg >= gravity_stddev_deg_) return false;
  if (refining) ++counts_.refinements;
  initialized_ = true;
  counts_.initialized = 1;
  gravity_w_ = result.gravity_w(init_options.gravity_m_s2);
  gravity_stddev_deg_ = result.gravity_stddev_deg;
  if (!initialized_ns_) {
    initialized_ns_ = t;
    next_refine_ns_ = t + static_cast<std::int64_t>(options_.refine_every_s * kNsPerS);
  }
  for (std::size_t k = 0; k < ids.size(); ++k) {
    states_[ids[k]] = InertialKeyframeState{result.v_wb[k], result.bias};
    seeded_.erase(ids[k]);
  }
  last_bias_ = result.bias;
  if (info_ && !refining) {
    std::ostringstream line;
    line << "inertial initialization over " << ids.size() << " keyframes: gravity (" << gravity_w_.transpose()
         << ") m/s^2 (stddev " << result.gravity_stddev_deg << " deg), gyro bias ("
         << result.bias.gyro_rad_s.transpose() << ") rad/s, accel bias (" << result.bias.accel_m_s2.transpose()
         << ") m/s^2; inertial local BA from now on";
    info_(line.str());
  }
  return true;
}

std::optional<LocalBundleAdjustmentResult> InertialMapping::bundle_adjust(Map& map, KeyframeId kf_id,
                                                                          const PinholeStereo& camera,
                                                                          const LocalBundleAdjustmentOptions& options,
                                                                          MapChanges& changes) {
  if (off_ || !calibration_ || !T_cb_) return std::nullopt;
  const Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || kf->culled) return std::nullopt;
  const std::int64_t t = imu_stamp(kf->stamp_ns);
  try_initialize(map, t);
  if (!initialized_) return std::nullopt;

  // The newest window_keyframes + 1 keyframes in time order; the readings before the oldest of twice as
  // many are not needed any more (a culled keyframe joins its neighbours' intervals).
  std::vector<std::pair<std::int64_t, KeyframeId>> keyframes;
  for (const auto& [id, keyframe] : map.keyframes) {
    if (!keyframe.culled && imu_stamp(keyframe.stamp_ns) <= t) keyframes.emplace_back(imu_stamp(keyframe.stamp_ns), id);
  }
  std::sort(keyframes.begin(), keyframes.end());
  const auto window = static_cast<std::size_t>(options_.window_keyframes) + 1;
  if (keyframes.size() > 2 * window) buffer_.discard_before(keyframes[keyframes.size() - 2 * window].first);
  if (keyframes.size() > window) keyframes.erase(keyframes.begin(), keyframes.end() - static_cast<long>(window));

  // The chain starts at the oldest keyframe with a state; after a keyframe the IMU cannot reach from
  // its predecessor (a gap), it starts again there. A keyframe without a state gets its predecessor's
  // biases and the velocity the IMU predicts.
  InertialWindow inertial;
  inertial.T_cb = *T_cb_;
  inertial.gravity_w = gravity_w_;
  if (options_.estimate_gravity) inertial.gravity_stddev_rad = std::max(gravity_stddev_deg_, 0.01) * M_PI / 180.0;
  std::string why;
  // A keyframe after a gap has no state: it starts a new chain with the velocity of the body between the
  // keyframe before it and itself and the newest biases, and that state is estimated, not held.
  const auto start_chain = [&](std::size_t k) {
    const KeyframeId id = keyframes[k].second;
    if (states_.count(id) == 0) {
      if (k == 0 || !last_bias_) return;
      const Keyframe& before = map.keyframes.at(keyframes[k - 1].second);
      const Pose3 T_wb0 = before.T_wc * *T_cb_;
      const Pose3 T_wb1 = map.keyframes.at(id).T_wc * *T_cb_;
      const double dt = seconds(keyframes[k].first - keyframes[k - 1].first);
      states_[id] = InertialKeyframeState{(T_wb1.translation() - T_wb0.translation()) / dt, *last_bias_};
      seeded_.insert(id);
    }
    inertial.chain.push_back(id);
    inertial.states[id] = states_.at(id);
    inertial.hold_anchor = seeded_.count(id) == 0;
  };
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    const auto& [stamp, id] = keyframes[k];
    if (inertial.chain.empty()) {
      if (states_.count(id) != 0 || k + 1 == keyframes.size()) start_chain(k);
      continue;
    }
    const KeyframeId previous = inertial.chain.back();
    const InertialKeyframeState& previous_state = inertial.states.at(previous);
    const std::int64_t t0 = imu_stamp(map.keyframes.at(previous).stamp_ns);
    std::optional<ImuPreintegration> pre = interval(t0, stamp, previous_state.bias, why);
    if (!pre) {
      inertial.chain.clear();
      inertial.intervals.clear();
      inertial.states.clear();
      start_chain(k);
      continue;
    }
    if (states_.count(id) != 0 && states_.at(id).v_wb.allFinite()) {
      inertial.states[id] = states_.at(id);
    } else {
      NavState start;
      const Pose3 T_wb = map.keyframes.at(previous).T_wc * *T_cb_;
      start.R_wb = T_wb.linear();
      start.p_wb = T_wb.translation();
      start.v_wb = previous_state.v_wb;
      inertial.states[id] =
          InertialKeyframeState{pre->predict(start, gravity_w_, previous_state.bias).v_wb, previous_state.bias};
    }
    inertial.chain.push_back(id);
    inertial.intervals.push_back(std::move(*pre));
  }
  if (inertial.chain.size() < 2 || inertial.chain.back() != kf_id) {
    ++counts_.visual_fallbacks;
    warn_once("fallback", "keyframe " + format_id(kf_id) + ": no IMU interval reaches it from the previous keyframe (" +
                              (why.empty() ? std::string("no inertial state") : why) +
                              "); visual local BA (counted as imu_ba_visual_fallbacks)");
    return std::nullopt;
  }
  InertialBundleAdjustmentResult result =
      inertial_local_bundle_adjustment(map, kf_id, camera, options, inertial, changes);
  if (!result.solved) {
    ++counts_.failed_solves;
    warn_once("failed", "keyframe " + format_id(kf_id) +
                            ": the inertial local BA gave no usable solution; visual local BA (counted as "
                            "imu_ba_failed_solves)");
    return std::nullopt;
  }
  for (const auto& [id, state] : inertial.states) states_[id] = state;
  gravity_w_ = inertial.gravity_w;
  if (!inertial.hold_anchor) seeded_.erase(inertial.chain.front());
  last_bias_ = inertial.states.at(kf_id).bias;
  ++counts_.inertial_bas;
  counts_.imu_factors += static_cast<std::uint64_t>(result.imu_factors);
  return result.visual;
}

void InertialMapping::moved(const std::map<KeyframeId, Pose3>& old_T_wc, const Map& map) {
  // Gravity turns with the newest keyframes (the local BA's window): the mapper estimated it together
  // with their roll and pitch, and a correction that turns them (the global BA with IMU factors levels
  // them on the odometry's gravity) would otherwise leave the next local BAs pulling the new keyframes
  // back towards the old tilt. A 4-DoF correction turns about gravity: nothing changes then.
  std::vector<std::pair<std::int64_t, Eigen::Matrix3d>> turns;
  for (auto& [id, state] : states_) {
    const auto old = old_T_wc.find(id);
    const Keyframe* kf = map.keyframe(id);
    if (old == old_T_wc.end() || kf == nullptr) continue;
    const Eigen::Matrix3d R = kf->T_wc.linear() * old->second.linear().transpose();
    state.v_wb = R * state.v_wb;
    if (!kf->culled) turns.emplace_back(kf->stamp_ns, R);
  }
  if (!initialized_ || turns.empty()) return;
  std::sort(turns.begin(), turns.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  const auto window = std::min(turns.size(), static_cast<std::size_t>(options_.window_keyframes) + 1);
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (std::size_t k = turns.size() - window; k < turns.size(); ++k) g += turns[k].second * gravity_w_;
  if (g.norm() > 0.5 * gravity_w_.norm()) gravity_w_ = g.normalized() * gravity_w_.norm();
}

}  // namespace heslam
