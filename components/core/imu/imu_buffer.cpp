// The checked IMU reading buffer (imu_buffer.hpp).
#include "components/core/imu/imu_buffer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace heslam {
namespace {

constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();

std::string ms(std::int64_t ns) { return std::to_string(static_cast<double>(ns) * 1e-6) + " ms"; }

}  // namespace

const char* to_string(ImuRejection rejection) {
  switch (rejection) {
    case ImuRejection::kNone: return "accepted";
    case ImuRejection::kNonFinite: return "non-finite";
    case ImuRejection::kSaturated: return "saturated";
    case ImuRejection::kDuplicate: return "duplicate stamp";
    case ImuRejection::kOutOfOrder: return "out of order";
  }
  return "unknown";
}

const char* to_string(ImuCoverage coverage) {
  switch (coverage) {
    case ImuCoverage::kComplete: return "complete";
    case ImuCoverage::kPending: return "pending";
    case ImuCoverage::kBeforeFirst: return "before the first reading";
    case ImuCoverage::kGap: return "gap";
    case ImuCoverage::kDead: return "IMU dead";
  }
  return "unknown";
}

ImuBuffer::ImuBuffer(ImuBufferOptions options)
    : options_(std::move(options)), watermark_ns_(kNever), last_stamp_ns_(kNever) {
  if (options_.max_gap_ns <= 0 || options_.dead_after_ns <= 0 || !(options_.gyro_saturation_rad_s > 0.0) ||
      !(options_.accel_saturation_m_s2 > 0.0)) {
    throw std::invalid_argument("ImuBuffer '" + options_.source +
                                "': expected positive gap, dead and saturation limits");
  }
}

ImuAddResult ImuBuffer::reject(ImuRejection rejection, const ImuSample& sample, const std::string& what) {
  switch (rejection) {
    case ImuRejection::kNonFinite: ++counts_.non_finite; break;
    case ImuRejection::kSaturated: ++counts_.saturated; break;
    case ImuRejection::kDuplicate: ++counts_.duplicates; break;
    case ImuRejection::kOutOfOrder: ++counts_.out_of_order; break;
    case ImuRejection::kNone: break;
  }
  return {rejection, options_.source + ": reading at " + std::to_string(sample.stamp_ns) + " ns: " + what +
                         " (skipped, " + std::to_string(counts_.skipped()) + " so far)"};
}

ImuAddResult ImuBuffer::add(const ImuSample& sample) {
  static constexpr const char* kAxes[3] = {"[0]", "[1]", "[2]"};
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(sample.gyro_rad_s[i])) {
      return reject(ImuRejection::kNonFinite, sample,
                    std::string("gyro_rad_s") + kAxes[i] + " is " + std::to_string(sample.gyro_rad_s[i]));
    }
    if (!std::isfinite(sample.accel_m_s2[i])) {
      return reject(ImuRejection::kNonFinite, sample,
                    std::string("accel_m_s2") + kAxes[i] + " is " + std::to_string(sample.accel_m_s2[i]));
    }
  }
  for (int i = 0; i < 3; ++i) {
    if (std::abs(sample.gyro_rad_s[i]) >= options_.gyro_saturation_rad_s) {
      return reject(ImuRejection::kSaturated, sample,
                    std::string("gyro_rad_s") + kAxes[i] + " = " + std::to_string(sample.gyro_rad_s[i]) +
                        " is at the sensor's limit " + std::to_string(options_.gyro_saturation_rad_s));
    }
    if (std::abs(sample.accel_m_s2[i]) >= options_.accel_saturation_m_s2) {
      return reject(ImuRejection::kSaturated, sample,
                    std::string("accel_m_s2") + kAxes[i] + " = " + std::to_string(sample.accel_m_s2[i]) +
                        " is at the sensor's limit " + std::to_string(options_.accel_saturation_m_s2));
    }
  }
  if (sample.stamp_ns == last_stamp_ns_) {
    return reject(ImuRejection::kDuplicate, sample, "stamp_ns repeats the previous reading's");
  }
  if (sample.stamp_ns < last_stamp_ns_) {
    return reject(ImuRejection::kOutOfOrder, sample,
                  "stamp_ns is before the previous reading's (" + std::to_string(last_stamp_ns_) + " ns)");
  }
  samples_.push_back(sample);
  last_stamp_ns_ = sample.stamp_ns;
  ++counts_.accepted;
  return {};
}

void ImuBuffer::set_watermark(std::int64_t stamp_ns) { watermark_ns_ = std::max(watermark_ns_, stamp_ns); }

std::int64_t ImuBuffer::covered_until_ns() const { return std::max(watermark_ns_, last_stamp_ns_); }

bool ImuBuffer::dead_at(std::int64_t stamp_ns) const {
  if (last_stamp_ns_ == kNever || covered_until_ns() < stamp_ns) return false;
  return stamp_ns - last_stamp_ns_ > options_.dead_after_ns;
}

ImuInterval ImuBuffer::interval(std::int64_t t0_ns, std::int64_t t1_ns) const {
  if (t1_ns <= t0_ns) throw std::invalid_argument("ImuBuffer::interval: expected t1 > t0");
  ImuInterval result;
  std::string span = std::to_string(t0_ns);  // built step by step: GCC 12's -Wrestrict misfires on "[" + string
  span.insert(0, 1, '[');
  span += ", " + std::to_string(t1_ns) + "] ns";
  if (covered_until_ns() < t1_ns) {
    result.coverage = ImuCoverage::kPending;
    result.message =
        options_.source + ": interval " + span + ": readings up to " + std::to_string(t1_ns) + " ns not yet received";
    return result;
  }
  if (dead_at(t1_ns)) {
    result.coverage = ImuCoverage::kDead;
    result.message = options_.source + ": interval " + span + ": IMU dead (no reading since " +
                     std::to_string(last_stamp_ns_) + " ns)";
    return result;
  }
  const auto by_stamp = [](const ImuSample& sample, std::int64_t stamp) { return sample.stamp_ns < stamp; };
  auto first = std::lower_bound(samples_.begin(), samples_.end(), t0_ns, by_stamp);
  if (first == samples_.end() || first->stamp_ns > t0_ns) {
    if (first == samples_.begin()) {
      result.coverage = ImuCoverage::kBeforeFirst;
      result.message = options_.source + ": interval " + span + ": no reading at or before its start";
      return result;
    }
    --first;
  }
  // The readings from `first` (at or before t0) to the first at or after t1, or the newest.
  auto last = std::lower_bound(first, samples_.end(), t1_ns, by_stamp);
  const bool held = last == samples_.end();
  if (held) --last;
  std::int64_t largest_gap_ns = held ? t1_ns - last->stamp_ns : 0;
  for (auto it = first; it != last; ++it)
    largest_gap_ns = std::max(largest_gap_ns, std::next(it)->stamp_ns - it->stamp_ns);
  result.largest_gap_ns = largest_gap_ns;
  if (largest_gap_ns > options_.max_gap_ns) {
    result.coverage = ImuCoverage::kGap;
    result.message = options_.source + ": interval " + span + ": readings " + ms(largest_gap_ns) +
                     " apart (more than " + ms(options_.max_gap_ns) + ")";
    return result;
  }
  result.coverage = ImuCoverage::kComplete;
  for (auto it = first; it <= last; ++it) {
    if (it->stamp_ns <= t0_ns) {
      if (std::next(it) <= last && std::next(it)->stamp_ns > t0_ns) {
        result.samples.push_back(interpolate_imu(*it, *std::next(it), t0_ns));
      } else if (it->stamp_ns == t0_ns || std::next(it) > last) {
        ImuSample at_start = *it;
        at_start.stamp_ns = t0_ns;
        result.samples.push_back(at_start);
      }
      continue;
    }
    if (it->stamp_ns >= t1_ns) {
      result.samples.push_back(interpolate_imu(*std::prev(it), *it, t1_ns));
      break;
    }
    result.samples.push_back(*it);
  }
  if (result.samples.back().stamp_ns < t1_ns) {  // the newest reading held to t1
    ImuSample at_end = *last;
    at_end.stamp_ns = t1_ns;
    result.samples.push_back(at_end);
  }
  return result;
}

void ImuBuffer::discard_before(std::int64_t stamp_ns) {
  while (samples_.size() > 1 && samples_[1].stamp_ns <= stamp_ns) samples_.pop_front();
}

}  // namespace heslam
