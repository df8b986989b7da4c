// ORB extraction as ORB-SLAM2 does it: scale pyramid, FAST per grid cell with a threshold fallback,
// quadtree distribution of the requested number of features over the image and over the levels,
// orientation by intensity centroid, rotated BRIEF (256 bit, pattern in orb_pattern.hpp).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/feature/descriptor_blur.hpp"
#include "components/core/feature/fast_score_map.hpp"
#include "components/core/feature/features.hpp"
#include "components/core/feature/intensity_centroid.hpp"
#include "components/core/feature/linear_resize.hpp"

namespace heslam {

// Pixels of replicated (reflect-101) border around every pyramid level, so a rotated BRIEF pattern
// (radius 13 * sqrt(2) < 19) and the stereo SAD window may read outside the level image.
inline constexpr int kOrbBorderPx = 19;

struct OrbOptions {
  int features = 1200;        // per image: ORB-SLAM2's EuRoC value (KITTI: 2000)
  float scale_factor = 1.2f;  // between pyramid levels
  int levels = 8;
  int fast_threshold_initial = 20;  // FAST threshold tried first in every grid cell
  int fast_threshold_min = 7;       // used in cells where the initial threshold finds nothing
  // Constants, not settings keys (tests and benchmarks may set them):
  float cell_size_px = 30.f;  // FAST grid cell: ORB-SLAM2's W = 30, tuned with its FAST thresholds
  // Share of features per level proportional to the level's area (1/scale^2). false: proportional to
  // 1/scale, as ORB-SLAM2's code does.
  bool features_by_area = true;

  // Reads ORB-SLAM2's ORBextractor.nFeatures, .scaleFactor, .nLevels, .iniThFAST, .minThFAST.
  static OrbOptions from_yaml(const cv::FileNode& root, const std::string& source);
  bool operator==(const OrbOptions&) const = default;
};

// Keypoints (level-0 coordinates), descriptors and the pyramid they came from.
struct OrbFeatures {
  std::vector<Keypoint> keypoints;
  std::vector<Descriptor> descriptors;
  // Level images (not blurred), ROI views with kOrbBorderPx readable pixels around them. They share
  // the extractor's buffers: valid until that extractor's next extract().
  std::vector<cv::Mat> pyramid;
};

class OrbExtractor {
 public:
  explicit OrbExtractor(const OrbOptions& options = {});

  // Input: 8-bit grey image. Deterministic. Not thread-safe (reuses its buffers); use one extractor
  // per image stream.
  void extract(const cv::Mat& image, OrbFeatures& out);

  // The stages of extract(), public for per-stage benchmarks: build_pyramid(image); detect();
  // describe(out) give the same result as extract(image, out).
  void build_pyramid(const cv::Mat& image);
  void detect();
  void describe(OrbFeatures& out);

  // Per-level work for callers that spread the levels of several images over threads: after
  // build_pyramid(), detect_and_describe_level(l) for every level (different levels may run on
  // different threads at once), then collect(out). Same result as extract().
  void detect_and_describe_level(int level);
  void collect(OrbFeatures& out) const;

  // Detection limited to `region` (8-bit, level-0 size, non-zero = allowed) with `features` wanted
  // in all, shared over the levels as options().features is; an empty region restores the whole
  // image and options().features. FAST corners outside the region are dropped before the quadtree
  // distribution, so the features spread over the region alone. The region must stay valid until
  // the next detection.
  void set_region(const cv::Mat& region, int features);

  const ScalePyramid& scale_pyramid() const { return scales_; }
  const OrbOptions& options() const { return options_; }
  // Features wanted on each level (sums to options().features).
  const std::vector<int>& features_per_level() const { return features_per_level_; }

 private:
  struct LevelKeypoint {
    float x;  // level coordinates (inside the level image, without border)
    float y;
    float response;
    float angle_deg;
  };

  void detect_level(int level);
  void share_features(int features);
  void describe_level(int level);

  OrbOptions options_;
  ScalePyramid scales_;
  std::vector<int> features_per_level_;
  cv::Mat region_;              // set_region's; empty = the whole image
  IntensityCentroid centroid_;  // keypoint orientation

  std::vector<cv::Mat> padded_;  // level image with border
  std::vector<cv::Mat> level_;   // ROI of padded_ without border
  // padded_ blurred for the descriptors: only the part the keypoints' patterns read is computed.
  std::vector<cv::Mat> blurred_;
  std::vector<DescriptorBlur> blurs_;  // one per level: levels may be described on different threads
  cv::Mat resize_scratch_;
  std::vector<LinearResize> resizes_;                   // one per level: its column plan is kept across frames
  std::vector<FastScoreMap> score_maps_;                // FAST scores per level (reused buffers)
  std::vector<std::vector<ScoredPoint>> level_points_;  // FAST corners per level before distribution
  std::vector<std::vector<LevelKeypoint>> level_keypoints_;
  std::vector<OrbFeatures> level_features_;  // keypoints and descriptors per level (no pyramid)
};

}  // namespace heslam
