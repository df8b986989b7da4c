// Spline trajectories with arc-length parameterization and seeded heading oscillations.
#include "tools/synth/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <random>
#include <stdexcept>

#include <Eigen/Geometry>

namespace heslam::synth {
namespace {

// Arc-length table resolution: samples per spline segment (sub-millimetre error for metre segments).
constexpr int kSamplesPerSegment = 64;
// Heading is taken from the path this far ahead, which smooths yaw rate through tight bends.
constexpr double kHeadingLookaheadM = 0.3;
// Second oscillation harmonic, an irrational ratio so the motion does not look periodic.
constexpr double kSecondHarmonic = 2.37;
// Velocity by central difference over this time step.
constexpr double kVelocityStepS = 1e-3;
constexpr double kPi = 3.14159265358979323846;
// Wavelengths of the path jitter along the path: room-scale and step-scale deviations.
constexpr double kJitterLongWaveM = 7.0;
constexpr double kJitterShortWaveM = 3.1;

double deg(double d) { return d * kPi / 180.0; }

// Platform-independent uniform in [-1, 1] (std distributions differ between standard libraries).
double signed_unit(std::mt19937_64& rng) { return 2.0 * static_cast<double>(rng() >> 11) * 0x1.0p-53 - 1.0; }

}  // namespace

Trajectory::Trajectory(const PathSpec& path, const TrajectorySpec& spec, std::uint64_t seed, bool smooth)
    : closed_(path.closed), spec_(spec), smooth_(smooth) {
  const auto& cps = path.control_points_w;
  const int n = static_cast<int>(cps.size());
  if (n < 4) throw std::runtime_error("trajectory needs at least 4 control points");
  if (smooth && spec.teleport_m > 0) {
    throw std::runtime_error(
        "trajectory.teleport_m: a teleport cannot be rendered with --imu (no IMU measures a jump)");
  }
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 17);
  // Jitter is a smooth function of the distance along the control polygon (two seeded sine waves),
  // so densely placed control points (tight turns) are displaced together instead of zig-zagging.
  std::vector<double> along(cps.size(), 0.0);
  for (int i = 1; i < n; ++i)
    along[static_cast<std::size_t>(i)] =
        along[static_cast<std::size_t>(i) - 1] +
        (cps[static_cast<std::size_t>(i)] - cps[static_cast<std::size_t>(i) - 1]).norm();
  const double polygon_length = along.back() + (closed_ ? (cps.front() - cps.back()).norm() : 0.0);
  auto wavelength = [&](double nominal) {
    // Closed paths need a whole number of waves so the jitter closes on itself too.
    return closed_ ? polygon_length / std::max(1.0, std::round(polygon_length / nominal)) : nominal;
  };
  const double wave_long = wavelength(kJitterLongWaveM), wave_short = wavelength(kJitterShortWaveM);
  double jitter_phase[4];
  for (double& ph : jitter_phase) ph = signed_unit(rng) * kPi;
  auto jitter = [&](double s, int k) {
    return 0.6 * std::sin(2 * kPi * s / wave_long + jitter_phase[2 * k]) +
           0.4 * std::sin(2 * kPi * s / wave_short + jitter_phase[2 * k + 1]);
  };
  std::vector<Eigen::Vector3d> jittered(cps.size());
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& prev = cps[static_cast<std::size_t>(closed_ ? (i + n - 1) % n : std::max(i - 1, 0))];
    const Eigen::Vector3d& next = cps[static_cast<std::size_t>(closed_ ? (i + 1) % n : std::min(i + 1, n - 1))];
    Eigen::Vector3d dir = next - prev;
    dir.z() = 0;
    const Eigen::Vector3d side =
        dir.norm() > 1e-9 ? Eigen::Vector3d(-dir.y(), dir.x(), 0).normalized() : Eigen::Vector3d::Zero();
    const double s_i = along[static_cast<std::size_t>(i)];
    jittered[static_cast<std::size_t>(i)] = cps[static_cast<std::size_t>(i)] +
                                            spec.lateral_jitter_m * jitter(s_i, 0) * side +
                                            spec.height_jitter_m * jitter(s_i, 1) * Eigen::Vector3d::UnitZ();
  }
  for (double& ph : phases_) ph = signed_unit(rng) * kPi;

  if (closed_) {
    points_ = jittered;
    num_segments_ = n;
  } else {
    // Triple end points so the open B-spline starts and ends exactly on them.
    points_.push_back(jittered.front());
    points_.push_back(jittered.front());
    points_.insert(points_.end(), jittered.begin(), jittered.end());
    points_.push_back(jittered.back());
    points_.push_back(jittered.back());
    num_segments_ = static_cast<int>(points_.size()) - 3;
  }
  table_step_u_ = 1.0 / kSamplesPerSegment;
  const int samples = num_segments_ * kSamplesPerSegment;
  arc_length_.resize(static_cast<std::size_t>(samples) + 1);
  arc_length_[0] = 0.0;
  Eigen::Vector3d last = spline_point(0.0);
  for (int i = 1; i <= samples; ++i) {
    const Eigen::Vector3d p = spline_point(std::min(i * table_step_u_, num_segments_ - 1e-9));
    arc_length_[static_cast<std::size_t>(i)] = arc_length_[static_cast<std::size_t>(i) - 1] + (p - last).norm();
    last = p;
  }
  plan_stops();
}

void Trajectory::plan_stops() {
  std::vector<StopSpec> stops = spec_.stops;
  if (spec_.stop_at_end && !closed_) stops.push_back({length_m(), 0.0});
  if (stops.empty()) return;
  const double v = spec_.speed_mps;
  const double ta = std::max(spec_.accel_time_s, 1e-6);
  const double a = v / ta;
  const double ramp_m = v * ta / 2;  // distance to reach cruising speed from rest (and to brake)
  double t = 0.0;
  double s = 0.0;
  for (const StopSpec& stop : stops) {
    const double gap = std::min(stop.at_m, length_m()) - s;
    if (gap <= 0.0) continue;
    if (gap >= 2 * ramp_m) {
      speed_phases_.push_back({t, s, 0.0, a});
      speed_phases_.push_back({t + ta, s + ramp_m, v, 0.0});
      t += ta + (gap - 2 * ramp_m) / v;
      speed_phases_.push_back({t, s + gap - ramp_m, v, -a});
      t += ta;
    } else {  // too close to reach cruising speed: accelerate half way, brake the other half
      const double peak = std::sqrt(a * gap);
      speed_phases_.push_back({t, s, 0.0, a});
      t += peak / a;
      speed_phases_.push_back({t, s + gap / 2, peak, -a});
      t += peak / a;
    }
    s += gap;
    speed_phases_.push_back({t, s, 0.0, 0.0});
    t += stop.wait_s;
  }
  if (s < length_m() || closed_) {
    speed_phases_.push_back({t, s, 0.0, a});
    speed_phases_.push_back({t + ta, s + ramp_m, v, 0.0});
  }
  for (std::size_t i = 0; i + 1 < speed_phases_.size(); ++i) {
    speed_phases_[i].duration_s = speed_phases_[i + 1].t0_s - speed_phases_[i].t0_s;
  }
}

Eigen::Vector3d Trajectory::spline_point(double u) const {
  const int n = static_cast<int>(points_.size());
  int seg = static_cast<int>(std::floor(u));
  seg = std::clamp(seg, 0, num_segments_ - 1);
  const double t = u - seg;
  auto cp = [&](int k) -> const Eigen::Vector3d& {
    return points_[static_cast<std::size_t>(closed_ ? ((k % n) + n) % n : std::clamp(k, 0, n - 1))];
  };
  // Closed: segment i spans control points i-1..i+2; open (padded): i..i+3.
  const int base = closed_ ? seg - 1 : seg;
  const double t2 = t * t, t3 = t2 * t;
  const double b0 = (1 - 3 * t + 3 * t2 - t3) / 6.0;
  const double b1 = (4 - 6 * t2 + 3 * t3) / 6.0;
  const double b2 = (1 + 3 * t + 3 * t2 - 3 * t3) / 6.0;
  const double b3 = t3 / 6.0;
  return b0 * cp(base) + b1 * cp(base + 1) + b2 * cp(base + 2) + b3 * cp(base + 3);
}

// A speed change from v0 by a * T over T seconds as a smoothstep: v = v0 + a T (3 x^2 - 2 x^3), x = dt / T.
// It covers the distance of the constant acceleration a (v0 T + a T^2 / 2) with an acceleration that
// is 0 at both ends (6 a x (1 - x)), so the motion stays C2 across phases.
Trajectory::Travel Trajectory::smooth_travel_at(double t_s) const {
  const double v = spec_.speed_mps;
  const double ta = std::max(spec_.accel_time_s, 1e-6);
  double s0 = 0.0, v0 = 0.0, a = v / ta, T = ta, dt = std::max(0.0, t_s);
  if (!speed_phases_.empty()) {
    const auto after = std::upper_bound(speed_phases_.begin(), speed_phases_.end(), t_s,
                                        [](double t, const SpeedPhase& phase) { return t < phase.t0_s; });
    const SpeedPhase& phase = after == speed_phases_.begin() ? speed_phases_.front() : *std::prev(after);
    s0 = phase.s0_m;
    v0 = phase.v0_mps;
    a = phase.a_mps2;
    T = phase.duration_s;
    dt = std::max(0.0, t_s - phase.t0_s);
  }
  Travel travel;
  if (a == 0.0 || T <= 0.0) {
    travel = {s0 + v0 * dt, v0, 0.0};
  } else if (dt >= T) {  // the constant-speed profile after its ramp
    travel = {s0 + v0 * T + 0.5 * a * T * T + (v0 + a * T) * (dt - T), v0 + a * T, 0.0};
  } else {
    const double x = dt / T;
    travel = {s0 + v0 * dt + a * T * T * (x * x * x - 0.5 * x * x * x * x), v0 + a * T * (3 * x * x - 2 * x * x * x),
              6.0 * a * x * (1.0 - x)};
  }
  const double length = length_m();
  if (closed_) {
    travel.s_m = std::fmod(travel.s_m, length);
    if (travel.s_m < 0) travel.s_m += length;
  } else if (travel.s_m >= length) {
    travel = {length, 0.0, 0.0};
  }
  return travel;
}

double Trajectory::distance_at(double t_s) const {
  if (smooth_) return smooth_travel_at(t_s).s_m;
  const double v = spec_.speed_mps;
  const double teleported_m = spec_.teleport_m > 0 && t_s >= spec_.teleport_at_s ? spec_.teleport_m : 0.0;
  const double ta = std::max(spec_.accel_time_s, 1e-6);
  double s = t_s < ta ? v * t_s * t_s / (2 * ta) : v * (t_s - ta / 2);
  if (!speed_phases_.empty()) {
    const auto after = std::upper_bound(speed_phases_.begin(), speed_phases_.end(), t_s,
                                        [](double t, const SpeedPhase& phase) { return t < phase.t0_s; });
    const SpeedPhase& phase = after == speed_phases_.begin() ? speed_phases_.front() : *std::prev(after);
    const double dt = std::max(0.0, t_s - phase.t0_s);
    s = phase.s0_m + phase.v0_mps * dt + 0.5 * phase.a_mps2 * dt * dt;
  }
  s += teleported_m;
  const double length = length_m();
  if (closed_) {
    s = std::fmod(s, length);
    if (s < 0) s += length;
  } else {
    s = std::clamp(s, 0.0, length);
  }
  return s;
}

double Trajectory::param_at_distance(double s_m) const {
  if (smooth_) return std::clamp(s_m / length_m() * num_segments_, 0.0, num_segments_ - 1e-9);
  const auto it = std::upper_bound(arc_length_.begin(), arc_length_.end(), s_m);
  if (it == arc_length_.begin()) return 0.0;
  if (it == arc_length_.end()) return num_segments_ - 1e-9;
  const std::size_t i = static_cast<std::size_t>(it - arc_length_.begin());
  const double s0 = arc_length_[i - 1], s1 = arc_length_[i];
  const double frac = s1 > s0 ? (s_m - s0) / (s1 - s0) : 0.0;
  return std::min((static_cast<double>(i - 1) + frac) * table_step_u_, num_segments_ - 1e-9);
}

Pose3 Trajectory::T_wb(double t_s) const {
  const double s = distance_at(t_s);
  const Eigen::Vector3d p = position_at_distance(s);
  double ahead = s + kHeadingLookaheadM;
  double behind = s;
  if (!closed_ && ahead > length_m()) {
    ahead = length_m();
    behind = length_m() - kHeadingLookaheadM;
  }
  if (closed_) ahead = std::fmod(ahead, length_m());
  const Eigen::Vector3d dir = position_at_distance(ahead) - position_at_distance(behind);
  const double heading = std::atan2(dir.y(), dir.x());
  // With stops the sway follows the distance (none at rest); else time, as presets always had.
  const double sway_t_s = speed_phases_.empty() ? t_s : s / spec_.speed_mps;
  const double w = 2 * kPi * spec_.wiggle_hz * sway_t_s;
  auto wiggle = [&](int k) {
    return 0.7 * std::sin(w + phases_[2 * k]) + 0.3 * std::sin(kSecondHarmonic * w + phases_[2 * k + 1]);
  };
  const double yaw = heading + deg(spec_.yaw_offset_deg) + deg(spec_.yaw_wiggle_deg) * wiggle(0);
  const double pitch = deg(spec_.pitch_offset_deg) + deg(spec_.pitch_wiggle_deg) * wiggle(1);
  const double roll = deg(spec_.roll_wiggle_deg) * wiggle(2);
  Pose3 T = Pose3::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = p;
  return T;
}

Eigen::Vector3d Trajectory::spline_derivative(double u, int order) const {
  const int n = static_cast<int>(points_.size());
  int seg = static_cast<int>(std::floor(u));
  seg = std::clamp(seg, 0, num_segments_ - 1);
  const double t = u - seg;
  auto cp = [&](int k) -> const Eigen::Vector3d& {
    return points_[static_cast<std::size_t>(closed_ ? ((k % n) + n) % n : std::clamp(k, 0, n - 1))];
  };
  const int base = closed_ ? seg - 1 : seg;
  double b[4];
  if (order == 1) {
    b[0] = (-3 + 6 * t - 3 * t * t) / 6.0;
    b[1] = (-12 * t + 9 * t * t) / 6.0;
    b[2] = (3 + 6 * t - 9 * t * t) / 6.0;
    b[3] = 3 * t * t / 6.0;
  } else {
    b[0] = (6 - 6 * t) / 6.0;
    b[1] = (-12 + 18 * t) / 6.0;
    b[2] = (6 - 18 * t) / 6.0;
    b[3] = 6 * t / 6.0;
  }
  return b[0] * cp(base) + b[1] * cp(base + 1) + b[2] * cp(base + 2) + b[3] * cp(base + 3);
}

Eigen::Vector3d Trajectory::acceleration_w(double t_s) const {
  if (!smooth_) throw std::logic_error("Trajectory::acceleration_w: only defined for a smooth trajectory");
  const Travel travel = smooth_travel_at(t_s);
  const double k = num_segments_ / length_m();  // du/ds
  const double u = param_at_distance(travel.s_m);
  const double du = k * travel.speed_mps;
  return spline_derivative(u, 2) * du * du + spline_derivative(u, 1) * k * travel.accel_mps2;
}

Eigen::Vector3d Trajectory::angular_velocity_b(double t_s) const {
  if (!smooth_) throw std::logic_error("Trajectory::angular_velocity_b: only defined for a smooth trajectory");
  // Log(R(t-h)^T R(t+h)) / 2h = w + O(h^2) with even powers only: Richardson over h and h/2 is O(h^4).
  const auto central = [&](double h) {
    const Eigen::AngleAxisd delta(T_wb(t_s - h).linear().transpose() * T_wb(t_s + h).linear());
    return Eigen::Vector3d(delta.axis() * delta.angle() / (2.0 * h));
  };
  constexpr double kStepS = 2e-3;
  return (4.0 * central(kStepS / 2) - central(kStepS)) / 3.0;
}

Eigen::Vector3d Trajectory::velocity_w(double t_s) const {
  if (smooth_) {
    const Travel travel = smooth_travel_at(t_s);
    return spline_derivative(param_at_distance(travel.s_m), 1) * (num_segments_ / length_m()) * travel.speed_mps;
  }
  double t0 = std::max(0.0, t_s - kVelocityStepS);
  double t1 = t_s + kVelocityStepS;
  // Across a teleport: the difference on the frame's side of the jump.
  if (spec_.teleport_m > 0 && t0 < spec_.teleport_at_s && spec_.teleport_at_s <= t1) {
    (t_s >= spec_.teleport_at_s ? t0 : t1) = t_s;
  }
  return (T_wb(t1).translation() - T_wb(t0).translation()) / (t1 - t0);
}

}  // namespace heslam::synth
