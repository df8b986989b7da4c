// Exposure events and the sensor model.
#include "tools/synth/photometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace heslam::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kFullScaleDn = 255.0;
// Gaussian samples come from a fixed table indexed by 16 random bits: fast and platform-independent.
constexpr int kGaussBits = 16;
constexpr std::size_t kGaussTableSize = std::size_t{1} << kGaussBits;

std::uint64_t splitmix(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Standard normal quantiles at the centres of kGaussTableSize equal-probability bins
// (Acklam's rational approximation of the inverse normal CDF, ~1e-9 relative error).
const std::array<float, kGaussTableSize>& gauss_table() {
  static const std::array<float, kGaussTableSize> table = [] {
    std::array<float, kGaussTableSize> t{};
    const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                        1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
    const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02, 6.680131188771972e+01,
                        -1.328068155288572e+01};
    const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                        -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
    const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00};
    for (std::size_t i = 0; i < kGaussTableSize; ++i) {
      const double p = (static_cast<double>(i) + 0.5) / static_cast<double>(kGaussTableSize);
      double x;
      if (p < 0.02425) {
        const double q = std::sqrt(-2 * std::log(p));
        x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
      } else if (p > 1 - 0.02425) {
        const double q = std::sqrt(-2 * std::log(1 - p));
        x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
      } else {
        const double q = p - 0.5, r = q * q;
        x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
            (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
      }
      t[i] = static_cast<float>(x);
    }
    return t;
  }();
  return table;
}

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

}  // namespace

std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b) {
  std::uint64_t state = a * 0xD1B54A32D192ED03ull ^ b;
  splitmix(state);
  return splitmix(state);
}

double event_envelope(const ExposureEvent& e, double t_s) {
  if (t_s < e.start_s || t_s > e.end_s) return 0.0;
  if (e.kind == EventKind::kDrift) return std::sin(kPi * (t_s - e.start_s) / (e.end_s - e.start_s));
  if (e.ramp_s <= 0.0) return 1.0;
  return smoothstep((t_s - e.start_s) / e.ramp_s) * smoothstep((e.end_s - t_s) / e.ramp_s);
}

PhotometricState photometric_state(const std::vector<ExposureEvent>& events, double t_s) {
  PhotometricState s;
  for (const ExposureEvent& e : events) {
    const double w = event_envelope(e, t_s);
    if (w <= 0.0) continue;
    switch (e.kind) {
      case EventKind::kOverexposure:
      case EventKind::kDarkness:
      case EventKind::kDrift:
        // Geometric interpolation: the log-exposure ramps linearly, as an auto-exposure step would.
        s.gain *= std::pow(e.strength, w);
        break;
      case EventKind::kHaze: s.haze = std::max(s.haze, e.strength * w); break;
      case EventKind::kStereoGain:
        s.left_gain *= std::pow(e.left, w);
        s.right_gain *= std::pow(e.right, w);
        break;
    }
  }
  return s;
}

PhotometricState PhotometricState::for_camera(int camera) const {
  PhotometricState s = *this;
  s.gain *= camera == 0 ? left_gain : right_gain;
  s.left_gain = 1.0;
  s.right_gain = 1.0;
  return s;
}

void Sensor::expose(const cv::Mat& radiance, const CameraRays& rays, const PhotometricState& state,
                    std::uint64_t noise_seed, cv::Mat& image_u8) const {
  const int w = radiance.cols, h = radiance.rows;
  image_u8.create(h, w, CV_8U);
  const auto& gauss = gauss_table();
  const float scale = static_cast<float>(spec_.exposure * state.gain * kFullScaleDn);
  const float haze = static_cast<float>(state.haze);
  const float airlight = static_cast<float>(spec_.haze_airlight);
  const float electrons_per_dn = static_cast<float>(spec_.full_well_e / kFullScaleDn);
  const float read_noise = static_cast<float>(spec_.read_noise_dn);
  const bool noise = spec_.noise;
  std::uint64_t rng = noise_seed;
  std::uint64_t bits = 0;
  int bits_left = 0;
  auto next_gauss = [&]() {
    if (bits_left == 0) {
      bits = splitmix(rng);
      bits_left = 64 / kGaussBits;
    }
    const float g = gauss[bits & (kGaussTableSize - 1)];
    bits >>= kGaussBits;
    --bits_left;
    return g;
  };
  for (int r = 0; r < h; ++r) {
    const float* in = radiance.ptr<float>(r);
    std::uint8_t* out = image_u8.ptr<std::uint8_t>(r);
    for (int c = 0; c < w; ++c) {
      const float L = in[c] * (1.0f - haze) + haze * airlight;
      float dn = L * scale * rays.vignetting_gain(r * w + c);
      if (noise) {
        // Shot noise: Poisson in electrons, Gaussian approximation; read noise on top.
        const float shot_sigma = std::sqrt(std::max(dn, 0.0f) / electrons_per_dn);
        dn += shot_sigma * next_gauss() + read_noise * next_gauss();
      }
      out[c] = static_cast<std::uint8_t>(std::clamp(std::lround(dn), 0l, 255l));
    }
  }
}

}  // namespace heslam::synth
