// The cameras' photometric relation on stereo matches, and its carrying from pair to pair (stereo_tone.hpp).
#include "components/core/feature/stereo_tone.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace heslam {
namespace {

struct PatchMoments {
  double mean = 0.0;
  double std = 0.0;
};

// Mean and standard deviation of the (2r + 1)^2 patch at (x, y); false when it leaves the image or
// holds a clipped pixel (0 or 255).
bool patch_moments(const cv::Mat& image, int x, int y, int r, PatchMoments& moments) {
  if (x - r < 0 || y - r < 0 || x + r >= image.cols || y + r >= image.rows) return false;
  double sum = 0.0;
  double square_sum = 0.0;
  for (int dy = -r; dy <= r; ++dy) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(y + dy);
    for (int dx = -r; dx <= r; ++dx) {
      const int value = row[x + dx];
      if (value == 0 || value == 255) return false;
      sum += value;
      square_sum += static_cast<double>(value) * value;
    }
  }
  const double n = static_cast<double>((2 * r + 1) * (2 * r + 1));
  moments.mean = sum / n;
  // Less the variance of the image's own rounding to whole grey levels (1/12), which does not scale
  // with the exposure: left at its weight, a darkened camera's patch would look more textured.
  constexpr double rounding = 1.0 / 12.0;
  moments.std = std::sqrt(std::max(square_sum / n - moments.mean * moments.mean - rounding, 0.0));
  return true;
}

double median_of(std::vector<double> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace

StereoToneMeasurement measure_stereo_tone(const cv::Mat& left, const cv::Mat& right, const StereoFeatures& features,
                                          const StereoToneMeasureOptions& options) {
  if (left.type() != CV_8UC1 || right.type() != CV_8UC1 || left.size() != right.size()) {
    throw std::invalid_argument("measure_stereo_tone: expected two 8-bit grey images of one size");
  }
  // A right patch this flat (in grey levels) gives no ratio: it would be a gain of infinity.
  constexpr double kMinRightStd = 0.25;
  std::vector<double> gains;
  std::vector<double> left_means;
  std::vector<double> right_means;
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (!features.has_stereo(i)) continue;
    const Keypoint& keypoint = features.keypoints[i];
    const int v = static_cast<int>(std::lround(keypoint.v_px));
    PatchMoments left_patch;
    PatchMoments right_patch;
    if (!patch_moments(left, static_cast<int>(std::lround(keypoint.u_px)), v, options.half_window, left_patch) ||
        !(left_patch.std >= options.min_texture) ||
        !patch_moments(right, static_cast<int>(std::lround(features.u_right_px[i])), v, options.half_window,
                       right_patch) ||
        !(right_patch.std >= kMinRightStd)) {
      continue;
    }
    gains.push_back(left_patch.std / right_patch.std);
    left_means.push_back(left_patch.mean);
    right_means.push_back(right_patch.mean);
  }
  StereoToneMeasurement measurement;
  measurement.matches = static_cast<int>(gains.size());
  if (measurement.matches < options.min_matches) return measurement;
  measurement.tone.gain = median_of(gains);
  std::vector<double> offsets(gains.size());
  for (std::size_t i = 0; i < offsets.size(); ++i) offsets[i] = left_means[i] - measurement.tone.gain * right_means[i];
  measurement.tone.offset = median_of(offsets);
  measurement.valid = true;
  return measurement;
}

bool StereoToneTracker::is_step(const LinearTone& histogram_tone) const {
  if (!have_last_histogram_ || !(histogram_tone.gain > 0.0) || !(last_histogram_.gain > 0.0)) return false;
  const double change = histogram_tone.gain / last_histogram_.gain;
  return change > options_.step_factor || change < 1.0 / options_.step_factor;
}

LinearTone StereoToneTracker::recent_median() const {
  std::vector<double> gains;
  std::vector<double> offsets;
  for (const LinearTone& tone : recent_) {
    gains.push_back(tone.gain);
    offsets.push_back(tone.offset);
  }
  return LinearTone{median_of(gains), median_of(offsets)};
}

std::optional<LinearTone> StereoToneTracker::predict(const LinearTone& histogram_tone) const {
  if (recent_.empty() || age_pairs_ >= options_.max_age_pairs || is_step(histogram_tone)) return std::nullopt;
  return recent_median();
}

void StereoToneTracker::update(const StereoToneMeasurement& measurement, const LinearTone& histogram_tone) {
  if (is_step(histogram_tone)) recent_.clear();
  if (measurement.valid && !recent_.empty()) {
    const double change = measurement.tone.gain / recent_median().gain;
    if (!(change <= options_.jump_factor && change >= 1.0 / options_.jump_factor)) {
      recent_.clear();  // the next pair takes the quantile curve and measures afresh
      age_pairs_ = 0;
      last_histogram_ = histogram_tone;
      have_last_histogram_ = true;
      return;
    }
  }
  if (measurement.valid) {
    recent_.push_back(measurement.tone);
    if (static_cast<int>(recent_.size()) > options_.window_pairs) recent_.erase(recent_.begin());
    age_pairs_ = 0;
  } else {
    ++age_pairs_;
  }
  last_histogram_ = histogram_tone;
  have_last_histogram_ = true;
}

void StereoToneTracker::reset() {
  recent_.clear();
  age_pairs_ = 0;
  have_last_histogram_ = false;
}

}  // namespace heslam
