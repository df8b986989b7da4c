// The global BA's IMU chain (see global_inertial_chain.hpp).
#include "components/core/loop/global_inertial_chain.hpp"

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "components/core/imu/gyro_bias.hpp"
#include "components/core/map/ids.hpp"

namespace heslam {

GlobalInertialInput build_global_inertial_input(const Map& map, const ImuBuffer& buffer, const Pose3& T_cb,
                                                std::int64_t time_offset_ns, const ImuNoise& noise,
                                                const Eigen::Vector3d& gravity_w,
                                                const GlobalInertialChainOptions& options,
                                                GlobalInertialChainReport* report) {
  GlobalInertialChainReport local_report;
  GlobalInertialChainReport& out = report != nullptr ? *report : local_report;
  out = {};
  GlobalInertialInput input;
  input.T_cb = T_cb;
  input.gravity_w = gravity_w;

  // Live keyframes per map in stamp order (ids break ties: a repeatable order).
  std::map<MapId, std::vector<std::pair<std::int64_t, KeyframeId>>> by_map;
  for (const auto& [id, kf] : map.keyframes) {
    if (!kf.culled) by_map[kf.map_id].emplace_back(kf.stamp_ns, id);
  }
  struct Segment {
    KeyframeId from, to;
    std::int64_t t0, t1;
    std::vector<ImuSample> samples;
  };
  std::vector<Segment> segments;
  const auto max_interval_ns = static_cast<std::int64_t>(options.max_interval_s * 1e9);
  for (auto& [map_id, keyframes] : by_map) {
    std::sort(keyframes.begin(), keyframes.end());
    for (std::size_t k = 0; k + 1 < keyframes.size(); ++k) {
      const auto [stamp_i, id_i] = keyframes[k];
      const auto [stamp_j, id_j] = keyframes[k + 1];
      const std::int64_t t0 = stamp_i + time_offset_ns;
      const std::int64_t t1 = stamp_j + time_offset_ns;
      if (t1 <= t0) continue;  // two keyframes of one stamp: nothing to integrate
      if (t1 - t0 > max_interval_ns) {
        ++out.too_long;
        if (out.first_problem.empty()) {
          out.first_problem = "keyframes " + format_id(id_i) + " -> " + format_id(id_j) + ": " +
                              std::to_string(static_cast<double>(t1 - t0) * 1e-9) + " s apart (max " +
                              std::to_string(options.max_interval_s) + " s)";
        }
        continue;
      }
      ImuInterval interval = buffer.interval(t0, t1);
      if (interval.coverage != ImuCoverage::kComplete) {
        ++out.not_covered;
        if (out.first_problem.empty()) {
          out.first_problem = "keyframes " + format_id(id_i) + " -> " + format_id(id_j) + ": " + interval.message;
        }
        continue;
      }
      segments.push_back({id_i, id_j, t0, t1, std::move(interval.samples)});
    }
  }
  if (segments.empty()) return input;

  const auto body = [&](KeyframeId id) { return Pose3(map.keyframes.at(id).T_wc * T_cb); };
  ImuBias bias;
  if (segments.size() >= 2) {
    std::vector<ImuPreintegration> around_zero;
    std::vector<Eigen::Matrix3d> R_ij;
    for (const Segment& s : segments) {
      around_zero.push_back(preintegrate(s.samples, s.t0, s.t1, bias, noise));
      R_ij.push_back(body(s.from).linear().transpose() * body(s.to).linear());
    }
    const GyroBiasEstimate gyro = estimate_gyro_bias(around_zero, R_ij);
    if (gyro.gyro_rad_s.allFinite()) {
      bias.gyro_rad_s = gyro.gyro_rad_s;
      out.gyro_bias_estimated = true;
      out.gyro_bias_rad_s = gyro.gyro_rad_s;
    }
  }
  for (const Segment& s : segments) {
    GlobalInertialInterval interval{s.from, s.to, preintegrate(s.samples, s.t0, s.t1, bias, noise)};
    const ImuPreintegration& pre = interval.preintegration;
    const Pose3 T_i = body(s.from);
    const Pose3 T_j = body(s.to);
    const double t = pre.duration_s();
    const Eigen::Vector3d v_i =
        (T_j.translation() - T_i.translation() - 0.5 * gravity_w * t * t - T_i.linear() * pre.delta_p(bias)) / t;
    input.states[s.from] = InertialKeyframeState{v_i, bias};
    // The chain's last keyframe (overwritten when an interval starts there).
    if (input.states.count(s.to) == 0) {
      input.states[s.to] = InertialKeyframeState{v_i + gravity_w * t + T_i.linear() * pre.delta_v(bias), bias};
    }
    input.intervals.push_back(std::move(interval));
  }
  // A keyframe that ends one interval and starts the next got its velocity from the next one (above,
  // in order only when segments are in time order, which they are per map); the last of each chain
  // keeps the extrapolated one.
  out.intervals = static_cast<int>(input.intervals.size());
  return input;
}

}  // namespace heslam
