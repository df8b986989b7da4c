// Photometry: the exposure / haze state over time from the preset's events, and the sensor model that
// turns scene radiance into an 8-bit image (vignetting, shot + read noise, quantization, clipping).
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "tools/synth/camera_rays.hpp"
#include "tools/synth/preset.hpp"

namespace heslam::synth {

struct PhotometricState {
  double gain = 1.0;  // exposure x gain multiplier relative to the preset's exposure
  double haze = 0.0;  // fraction of radiance replaced by the airlight
  // Per-camera multipliers on top of `gain` (stereo_gain events); camera 0 is the left.
  double left_gain = 1.0;
  double right_gain = 1.0;

  // The state one camera is exposed with: `gain` times that camera's own multiplier.
  PhotometricState for_camera(int camera) const;
};

// 0 outside [start_s, end_s], 1 inside after a smooth ramp of ramp_s at each end (drift: a sine swell).
double event_envelope(const ExposureEvent& event, double t_s);
PhotometricState photometric_state(const std::vector<ExposureEvent>& events, double t_s);

class Sensor {
 public:
  explicit Sensor(const PhotometrySpec& spec) : spec_(spec) {}

  // Exposes `radiance` (CV_32F) into image_u8 (CV_8U). Noise is a pure function of noise_seed, so
  // one seed gives identical bytes.
  void expose(const cv::Mat& radiance, const CameraRays& rays, const PhotometricState& state, std::uint64_t noise_seed,
              cv::Mat& image_u8) const;

 private:
  PhotometrySpec spec_;
};

// Stateless 64-bit mixing, used to derive independent seeds (frame, camera, purpose) from one seed.
std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b);

}  // namespace heslam::synth
