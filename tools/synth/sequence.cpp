// Frame rendering for a preset: trajectory -> camera poses -> radiance -> sensor -> 8-bit images.
#include "tools/synth/sequence.hpp"

#include <cmath>
#include <stdexcept>
#include <thread>

#include <opencv2/imgproc.hpp>

namespace heslam::synth {
namespace {

// Seed streams, so noise of (frame, camera) never coincides with another purpose's stream.
constexpr std::uint64_t kNoiseStream = 0x6E6F697365;  // "noise"

Pose3 camera_in_body(double offset_y_m) {
  // Camera axes (x right, y down, z forward) in the body frame (x forward, y left, z up).
  Pose3 T = Pose3::Identity();
  T.linear().col(0) = -Eigen::Vector3d::UnitY();
  T.linear().col(1) = -Eigen::Vector3d::UnitZ();
  T.linear().col(2) = Eigen::Vector3d::UnitX();
  T.translation() = Eigen::Vector3d(0.0, offset_y_m, 0.0);
  return T;
}

}  // namespace

SequenceRenderer::SequenceRenderer(const Preset& preset, const RenderOptions& options)
    : preset_(preset),
      options_(options),
      built_(build_scene(preset)),
      trajectory_(built_.path, preset.trajectory, options.seed, options.imu),
      rays_(preset.camera, options.apply_distortion),
      sensor_(preset.photometry) {
  if (options.frames < 0) throw std::runtime_error("frames must be >= 0");
  if (options.threads < 1 || options.threads > 2) throw std::runtime_error("threads must be 1 or 2");
  num_frames_ = options.frames > 0 ? options.frames : preset.frames;
  rays_.set_vignetting(preset.photometry.vignetting);
  // The rig is centred on the body: left camera half a baseline to the left.
  T_BS_left_ = camera_in_body(preset.camera.baseline_m / 2);
  Pose3 T_lr = Pose3::Identity();
  T_lr.translation() = Eigen::Vector3d(preset.camera.baseline_m, 0, 0);
  T_BS_right_ = T_BS_left_ * T_lr;
  renderers_.push_back(std::make_unique<Renderer>(built_.scene, rays_));
  renderers_.push_back(std::make_unique<Renderer>(built_.scene, rays_));
}

SequenceRenderer::~SequenceRenderer() = default;

std::int64_t SequenceRenderer::stamp_ns(int index) const {
  return kFirstStampNs + std::llround(static_cast<double>(index) * 1e9 / preset_.camera.rate_hz);
}

PinholeStereo SequenceRenderer::pinhole_stereo() const {
  const CameraSpec& c = preset_.camera;
  return {c.fx_px, c.fy_px, c.cx_px, c.cy_px, c.baseline_m, c.width_px, c.height_px};
}

void SequenceRenderer::render_camera(int camera, const SynthFrame& frame, cv::Mat& out) {
  Renderer& renderer = *renderers_[static_cast<std::size_t>(camera)];
  const Pose3& T_BS = camera == 0 ? T_BS_left_ : T_BS_right_;
  const int samples = preset_.photometry.motion_blur_samples;
  cv::Mat radiance;
  if (samples <= 1) {
    renderer.render(camera == 0 ? frame.T_wc_left : frame.T_wc_right, radiance);
  } else {
    // Motion blur: average the radiance over the shutter time (centred on the frame stamp).
    cv::Mat sub;
    radiance = cv::Mat::zeros(rays_.height_px(), rays_.width_px(), CV_32F);
    for (int k = 0; k < samples; ++k) {
      const double dt = preset_.photometry.exposure_time_s * ((k + 0.5) / samples - 0.5);
      renderer.render(trajectory_.T_wb(frame.t_s + dt) * T_BS, sub);
      radiance += sub;
    }
    radiance *= 1.0 / samples;
  }
  if (preset_.photometry.lens_blur_px > 0) {
    // The lens point-spread function and the pixel's area: edges are smooth, as in a real camera.
    const double sigma = preset_.photometry.lens_blur_px;
    cv::GaussianBlur(radiance, radiance, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
  }
  const std::uint64_t noise_seed =
      mix_seed(mix_seed(options_.seed ^ kNoiseStream, static_cast<std::uint64_t>(frame.index)),
               static_cast<std::uint64_t>(camera));
  sensor_.expose(radiance, rays_, frame.photometry.for_camera(camera), noise_seed, out);
}

SynthFrame SequenceRenderer::render_frame(int index) {
  if (index < 0 || index >= num_frames_) throw std::runtime_error("frame index out of range");
  SynthFrame f;
  f.index = index;
  f.stamp_ns = stamp_ns(index);
  f.t_s = time_s(index);
  f.T_wb = T_wb(index);
  f.T_wc_left = f.T_wb * T_BS_left_;
  f.T_wc_right = f.T_wb * T_BS_right_;
  if (options_.events) f.photometry = photometric_state(preset_.events, f.t_s);
  if (options_.threads == 2) {
    std::thread right([&] { render_camera(1, f, f.right); });
    render_camera(0, f, f.left);
    right.join();
  } else {
    render_camera(0, f, f.left);
    render_camera(1, f, f.right);
  }
  return f;
}

void SequenceRenderer::render_radiance_left(int index, cv::Mat& radiance, cv::Mat* depth_m) {
  renderers_[0]->render(T_wc_left(index), radiance, depth_m);
}

SynthSequence render(const Preset& preset, const RenderOptions& options) {
  SequenceRenderer renderer(preset, options);
  SynthSequence seq;
  seq.preset = preset;
  seq.options = options;
  seq.marker_corners = renderer.scene().marker_corners;
  seq.T_BS_left = renderer.T_BS_left();
  seq.T_BS_right = renderer.T_BS_right();
  seq.pinhole = renderer.pinhole_stereo();
  for (int i = 0; i < renderer.num_frames(); ++i) seq.frames.push_back(renderer.render_frame(i));
  return seq;
}

}  // namespace heslam::synth
