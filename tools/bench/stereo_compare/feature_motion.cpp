// Keypoint motion against the ground truth's (feature_motion.hpp).
#include "tools/bench/stereo_compare/feature_motion.hpp"

#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "tools/bench/stereo_compare/zncc_reference.hpp"
#include "tools/dataset/ground_truth.hpp"

namespace heslam::bench {
namespace {

constexpr double kSearchWindowPx = 10.0;     // +- around the predicted position, level 0
constexpr int kMaxHammingDistance = 50;      // ORB-SLAM2's TH_LOW
constexpr double kRatio = 0.8;               // best < ratio x second best
constexpr double kMaxResidualLevelPx = 3.0;  // a farther match is a different point
constexpr double kCloseDepthM = 3.0;

struct SlopeGroup {
  double dot = 0.0, predicted2 = 0.0, along_sum = 0.0;
  long n = 0;
  void add(const Eigen::Vector2d& predicted, const Eigen::Vector2d& measured) {
    dot += measured.dot(predicted);
    predicted2 += predicted.squaredNorm();
    if (predicted.norm() > 1e-9) along_sum += (measured - predicted).dot(predicted.normalized());
    ++n;
  }
  void print(const char* name) const {
    std::printf("  %-16s n %7ld  slope %.4f  mean residual along the motion %+.4f px\n", name, n,
                predicted2 > 0.0 ? dot / predicted2 : 0.0, n > 0 ? along_sum / static_cast<double>(n) : 0.0);
  }
};

int hamming(const Descriptor& a, const Descriptor& b) {
  int distance = 0;
  for (std::size_t i = 0; i < a.size(); ++i) distance += __builtin_popcount(static_cast<unsigned>(a[i] ^ b[i]));
  return distance;
}

// Body poses of the ground truth at each frame's stamp (load_euroc_sequence read them); throws when a
// frame has none.
std::vector<Pose3> ground_truth_at_frames(const EurocSequence& sequence) {
  const std::filesystem::path path = euroc_ground_truth_file(sequence.mav0_dir);
  if (!std::filesystem::exists(path)) throw std::runtime_error("cannot open " + path.string());
  std::vector<Pose3> poses;
  for (const EurocFrame& frame : sequence.frames) {
    if (!frame.T_WB_truth) {
      throw std::runtime_error(path.string() + ": no ground truth row at frame stamp " +
                               std::to_string(frame.stamp_ns));
    }
    poses.push_back(*frame.T_WB_truth);
  }
  return poses;
}

cv::Mat read_grey(const std::filesystem::path& png) {
  cv::Mat image = cv::imread(png.string(), cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw std::runtime_error(png.string() + ": cannot read the image");
  return image;
}

}  // namespace

void print_feature_motion(const EurocSequence& sequence, const photometric::StereoGain& gain,
                          const FeatureMotionOptions& options) {
  const std::vector<Pose3> T_wb = ground_truth_at_frames(sequence);
  const StereoRectifier rectifier(load_euroc_calibration(sequence.mav0_dir));
  const PinholeStereo& camera = rectifier.camera();
  StereoFeaturePipeline pipeline(camera, options.pipeline);

  std::vector<StereoFeatures> frames;
  for (const EurocFrame& frame : sequence.frames) {
    const cv::Mat left = read_grey(frame.left_png), right = read_grey(frame.right_png);
    cv::Mat left_gain = left.clone(), right_gain = right.clone(), left_rect, right_rect;
    photometric::apply_gain(left_gain, gain.left);
    photometric::apply_gain(right_gain, gain.right);
    rectifier.rectify(left_gain, right_gain, left_rect, right_rect);
    StereoFeatures features = pipeline.process(left_rect, right_rect);
    if (options.reference_depth) {
      cv::Mat left_plain, right_plain;
      rectifier.rectify(left, right, left_plain, right_plain);
      for (std::size_t i = 0; i < features.size(); ++i) {
        if (!features.has_stereo(i)) continue;
        const Keypoint& kp = features.keypoints[i];
        const float scale = features.pyramid.scale[static_cast<std::size_t>(kp.octave)];
        const int half = std::max(options.pipeline.stereo.sad_half_window_px,
                                  static_cast<int>(std::lround(options.pipeline.stereo.sad_half_window_px * scale)));
        const double disparity = kp.u_px - features.u_right_px[i];
        const auto reference = zncc_reference_disparity(left_plain, right_plain, kp.u_px, kp.v_px, half, disparity);
        if (!reference || std::abs(*reference - disparity) > kMaxReferenceDiffPx || *reference < 1.0) {
          features.u_right_px[i] = kNoStereo;  // no trustworthy reference: left out
          features.depth_m[i] = kNoStereo;
          continue;
        }
        features.u_right_px[i] = static_cast<float>(kp.u_px - *reference);
        features.depth_m[i] = static_cast<float>(camera.bf() / *reference);
      }
    }
    frames.push_back(std::move(features));
  }

  SlopeGroup all, near_clip, clear, close, far;
  for (std::size_t k = 0; k + 1 < frames.size(); ++k) {
    const StereoFeatures& a = frames[k];
    const StereoFeatures& b = frames[k + 1];
    const Pose3 T_ba = (T_wb[k + 1] * rectifier.T_B_rect()).inverse() * (T_wb[k] * rectifier.T_B_rect());
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (!a.has_stereo(i)) continue;
      const Keypoint& ka = a.keypoints[i];
      const Eigen::Vector3d p_b = T_ba * camera.unproject(ka.u_px, ka.v_px, a.depth_m[i]);
      if (p_b.z() <= 0.0) continue;
      const Eigen::Vector2d predicted = camera.project(p_b);
      int best = -1, best_distance = kMaxHammingDistance + 1, second_distance = 256;
      for (std::size_t j = 0; j < b.size(); ++j) {
        const Keypoint& kb = b.keypoints[j];
        if (kb.octave != ka.octave || std::abs(kb.u_px - predicted.x()) > kSearchWindowPx ||
            std::abs(kb.v_px - predicted.y()) > kSearchWindowPx) {
          continue;
        }
        const int distance = hamming(a.descriptors[i], b.descriptors[j]);
        if (distance < best_distance) {
          second_distance = best_distance;
          best_distance = distance;
          best = static_cast<int>(j);
        } else if (distance < second_distance) {
          second_distance = distance;
        }
      }
      if (best < 0 || best_distance >= kRatio * second_distance) continue;
      const Keypoint& kb = b.keypoints[static_cast<std::size_t>(best)];
      const Eigen::Vector2d from(ka.u_px, ka.v_px);
      const Eigen::Vector2d predicted_motion = predicted - from;
      const Eigen::Vector2d measured_motion = Eigen::Vector2d(kb.u_px, kb.v_px) - from;
      if ((measured_motion - predicted_motion).norm() >
          kMaxResidualLevelPx * a.pyramid.scale[static_cast<std::size_t>(ka.octave)]) {
        continue;
      }
      all.add(predicted_motion, measured_motion);
      (a.stereo_near_clip(i) ? near_clip : clear).add(predicted_motion, measured_motion);
      (a.depth_m[i] < kCloseDepthM ? close : far).add(predicted_motion, measured_motion);
    }
  }
  std::printf("keypoint motion frame k -> k+1 against the ground truth's, gain %s, depths from %s:\n",
              gain.describe().c_str(), options.reference_depth ? "the unaltered pair (ZNCC)" : "the run's stereo");
  all.print("all");
  near_clip.print("near a clip edge");
  clear.print("not near");
  close.print("depth < 3 m");
  far.print("depth >= 3 m");
}

}  // namespace heslam::bench
