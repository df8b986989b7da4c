// Stereo matching of rectified ORB features, as ORB-SLAM2: for each left keypoint the best right
// keypoint by Hamming distance within the row band of its octave and the valid disparity range, then
// subpixel refinement by SAD over a window on the keypoint's pyramid level with a fit through the
// SAD minimum (equiangular by default, ORB-SLAM2's parabola as an option), and rejection of outliers
// by SAD statistics. Result per left keypoint: u_right and depth, or kNoStereo.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/feature/features.hpp"
#include "components/core/feature/orb_extractor.hpp"

namespace heslam {

// One settings key, Stereo.rowBand (a rig rectified less exactly needs a wider band); the other fields
// are constants, ORB-SLAM2's or measured here (docs/vision.md), that tests and benchmarks may set.
struct StereoMatcherOptions {
  // Hamming. ORB-SLAM2 uses (TH_HIGH + TH_LOW) / 2 = 75; TH_HIGH = 100 keeps more true matches and
  // the SAD refinement and outlier test remove the false ones (docs/vision.md).
  int max_distance = 100;
  float row_band_px = 2.f;          // |v_left - v_right| allowed, times the right keypoint's scale
  int sad_half_window_px = 5;       // SAD window is (2w+1)^2 pixels on the keypoint's level
  int sad_search_px = 5;            // SAD searched +-L pixels (level) around the matched right keypoint
  float min_depth_baselines = 1.f;  // closest valid depth, in baselines (max disparity = fx / this)
  // Matches whose SAD exceeds this factor x the median SAD are dropped (ORB-SLAM2: 1.5 x 1.4).
  float sad_outlier_factor = 2.1f;
  // Judge outliers by SAD relative to the left patch's variation (sum of |L - mean|) instead of by
  // absolute SAD (ORB-SLAM2), which drops the best-textured patches first.
  bool relative_sad_outliers = true;
  // Brightness normalization of the SAD patches: subtract each patch's mean, or its centre pixel
  // (ORB-SLAM2; noisier: one pixel's noise shifts the whole patch), or nothing. Measured on the
  // synthetic plane (level 0): median disparity error 0.026 px (mean) vs 0.134 px (centre).
  enum class SadNormalization { kCenter, kMean, kNone } sad_normalization = SadNormalization::kMean;
  // Subpixel fit through the SAD minimum and its neighbours: equiangular lines (exact for a
  // V-shaped cost, which SAD is near its minimum) or a parabola (ORB-SLAM2; biased towards whole
  // pixels for SAD: 0.042 px median error vs 0.026 px with mean normalization).
  enum class SubpixelFit { kParabola, kEquiangular } subpixel_fit = SubpixelFit::kEquiangular;

  // Reads Stereo.rowBand.
  static StereoMatcherOptions from_yaml(const cv::FileNode& root, const std::string& source);
  bool operator==(const StereoMatcherOptions&) const = default;
};

// Where left keypoints were lost, for tuning and reports.
struct StereoMatchStats {
  int no_candidate = 0;   // no right keypoint in the row band, octave range and disparity range
  int over_distance = 0;  // best Hamming distance above max_distance
  int sad_at_edge = 0;    // SAD minimum on the edge of the search range
  int bad_fit = 0;        // flat or inconsistent subpixel fit
  int out_of_range = 0;   // refined disparity outside [0, max)
  int sad_outlier = 0;    // dropped by the SAD statistics
  int matched = 0;
};

class StereoMatcher {
 public:
  StereoMatcher(const PinholeStereo& camera, const ScalePyramid& pyramid, const StereoMatcherOptions& options = {});

  // Fills u_right_px and depth_m (size of left.keypoints; kNoStereo where unmatched).
  void match(const OrbFeatures& left, const OrbFeatures& right, std::vector<float>& u_right_px,
             std::vector<float>& depth_m, StereoMatchStats* stats = nullptr) const;

  // match() in three steps, so that callers can split the left keypoints between threads:
  // prepare_rows() indexes the right keypoints by image row; match_range() matches left keypoints
  // [begin, end) and appends their (SAD, index) pairs (u_right_px/depth_m must be sized and filled
  // with kNoStereo); reject_outliers() then drops outliers by the SAD statistics of all pairs.
  void prepare_rows(const OrbFeatures& right, std::vector<std::vector<int>>& rows) const;
  void match_range(const OrbFeatures& left, const OrbFeatures& right, const std::vector<std::vector<int>>& rows,
                   std::size_t begin, std::size_t end, std::vector<float>& u_right_px, std::vector<float>& depth_m,
                   std::vector<std::pair<int, int>>& sad_and_index, StereoMatchStats* stats = nullptr) const;
  void reject_outliers(std::vector<std::pair<int, int>>& sad_and_index, std::vector<float>& u_right_px,
                       std::vector<float>& depth_m, StereoMatchStats* stats = nullptr) const;

  const StereoMatcherOptions& options() const { return options_; }

 private:
  PinholeStereo camera_;
  ScalePyramid pyramid_;
  StereoMatcherOptions options_;
};

}  // namespace heslam
