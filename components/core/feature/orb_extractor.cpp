// ORB extraction: pyramid, gridded FAST with fallback threshold, quadtree distribution, intensity-
// centroid orientation and rotated BRIEF.
#include "components/core/feature/orb_extractor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "components/core/feature/fast_score_map.hpp"
#include "components/core/feature/orb_pattern.hpp"
#include "components/core/feature/quadtree_distribution.hpp"
#include "components/core/feature/rbrief_descriptor.hpp"
#include "components/core/feature/rotated_orb_pattern.hpp"
#include "components/core/image/yaml_option.hpp"

namespace heslam {
namespace {

// Radius of the intensity-centroid patch (ORB's 31x31 patch).
constexpr int kOrientationRadiusPx = IntensityCentroid::kRadiusPx;
// Keypoints are detected this far from the level edge (ORB-SLAM2: EDGE_THRESHOLD - 3): the
// orientation patch (radius 15) then lies inside the level image.
constexpr int kDetectionMarginPx = kOrbBorderPx - 3;
// FAST's Bresenham circle radius.
constexpr int kFastRadiusPx = FastScoreMap::kRadiusPx;
// How far from its keypoint a rotated pattern point can be read: the smallest integer radius holding
// every pattern point (a rounded rotated offset cannot leave that circle).
constexpr int descriptor_reach_px() {
  int largest_squared = 0;
  for (const auto& q : kOrbPattern) {
    largest_squared = std::max({largest_squared, q[0] * q[0] + q[1] * q[1], q[2] * q[2] + q[3] * q[3]});
  }
  int reach = 0;
  while (reach * reach < largest_squared) ++reach;
  return reach;
}
constexpr int kDescriptorReachPx = descriptor_reach_px();
// Descriptor smoothing (ORB-SLAM2's 7x7 Gaussian, sigma 2, against BRIEF's noise sensitivity) reads
// this far beyond the patterns: it must stay inside the padded level.
static_assert(kDescriptorReachPx - kDetectionMarginPx + DescriptorBlur::kRadiusPx <= kOrbBorderPx,
              "the blurred patch area must lie inside the level's border");

// The orientation patch reads one column beyond its radius (IntensityCentroid's 32-byte rows).
static_assert(kOrientationRadiusPx + 1 <= kDetectionMarginPx, "the orientation patch must lie inside the level");
static_assert(kOrbPatternRadiusPx * 1.4143 < kOrbBorderPx, "rotated pattern must stay inside the border");

// Fills a border of `border` pixels around the inner image of `padded` as cv::BORDER_REFLECT_101
// does (pixel -k = pixel k), in place. The inner image must be larger than the border.
void reflect_border(cv::Mat& padded, int border) {
  const int width = padded.cols - 2 * border;
  const int height = padded.rows - 2 * border;
  for (int y = border; y < border + height; ++y) {
    std::uint8_t* row = padded.ptr<std::uint8_t>(y);
    for (int k = 1; k <= border; ++k) {
      row[border - k] = row[border + k];
      row[border + width - 1 + k] = row[border + width - 1 - k];
    }
  }
  for (int k = 1; k <= border; ++k) {
    const auto bytes = static_cast<std::size_t>(padded.cols);
    std::memcpy(padded.ptr<std::uint8_t>(border - k), padded.ptr<std::uint8_t>(border + k), bytes);
    std::memcpy(padded.ptr<std::uint8_t>(border + height - 1 + k), padded.ptr<std::uint8_t>(border + height - 1 - k),
                bytes);
  }
}

}  // namespace

OrbOptions OrbOptions::from_yaml(const cv::FileNode& root, const std::string& source) {
  OrbOptions o;
  yaml_option::read(root, "ORBextractor.nFeatures", source, o.features);
  yaml_option::read(root, "ORBextractor.scaleFactor", source, o.scale_factor);
  yaml_option::read(root, "ORBextractor.nLevels", source, o.levels);
  yaml_option::read(root, "ORBextractor.iniThFAST", source, o.fast_threshold_initial);
  yaml_option::read(root, "ORBextractor.minThFAST", source, o.fast_threshold_min);
  // The upper bounds only catch typos: a value beyond them is certainly a mistake.
  if (o.features < 1 || o.features > 100000)
    yaml_option::fail(source, "ORBextractor.nFeatures", "an integer in [1, 100000]");
  if (!(o.scale_factor > 1.f) || o.scale_factor > 4.f) {
    yaml_option::fail(source, "ORBextractor.scaleFactor", "a number in (1, 4]");
  }
  if (o.levels < 1 || o.levels > 16) yaml_option::fail(source, "ORBextractor.nLevels", "an integer in [1, 16]");
  if (o.fast_threshold_initial < 1 || o.fast_threshold_initial > 255) {
    yaml_option::fail(source, "ORBextractor.iniThFAST", "an integer in [1, 255]");
  }
  if (o.fast_threshold_min < 1 || o.fast_threshold_min > o.fast_threshold_initial) {
    yaml_option::fail(source, "ORBextractor.minThFAST", "an integer in [1, iniThFAST]");
  }
  return o;
}

OrbExtractor::OrbExtractor(const OrbOptions& options)
    : options_(options), scales_(ScalePyramid::make(options.levels, options.scale_factor)) {
  if (options.levels < 1 || !(options.scale_factor > 1.f) || options.features < 1) {
    throw std::invalid_argument("OrbExtractor: expected levels >= 1, scale_factor > 1, features >= 1");
  }
  share_features(options.features);

  padded_.resize(static_cast<std::size_t>(options.levels));
  level_.resize(static_cast<std::size_t>(options.levels));
  blurred_.resize(static_cast<std::size_t>(options.levels));
  blurs_.resize(static_cast<std::size_t>(options.levels));
  resizes_.resize(static_cast<std::size_t>(options.levels));
  level_keypoints_.resize(static_cast<std::size_t>(options.levels));
  score_maps_.resize(static_cast<std::size_t>(options.levels));
  level_points_.resize(static_cast<std::size_t>(options.levels));
  level_features_.resize(static_cast<std::size_t>(options.levels));
}

void OrbExtractor::share_features(int features) {
  // Geometric share per level: factor^l with factor = 1/s^2 (area) or 1/s (ORB-SLAM2).
  const double factor =
      options_.features_by_area ? 1.0 / (options_.scale_factor * options_.scale_factor) : 1.0 / options_.scale_factor;
  const double first = features * (1.0 - factor) / (1.0 - std::pow(factor, options_.levels));
  int assigned = 0;
  features_per_level_.resize(static_cast<std::size_t>(options_.levels));
  for (int l = 0; l + 1 < options_.levels; ++l) {
    features_per_level_[l] = static_cast<int>(std::lround(first * std::pow(factor, l)));
    assigned += features_per_level_[l];
  }
  features_per_level_.back() = std::max(features - assigned, 0);
}

void OrbExtractor::set_region(const cv::Mat& region, int features) {
  if (!region.empty() && region.type() != CV_8UC1) {
    throw std::invalid_argument("OrbExtractor: expected an 8-bit region mask");
  }
  region_ = region;
  share_features(region.empty() ? options_.features : std::max(features, 0));
}

void OrbExtractor::extract(const cv::Mat& image, OrbFeatures& out) {
  build_pyramid(image);
  detect();
  describe(out);
}

void OrbExtractor::build_pyramid(const cv::Mat& image) {
  if (image.empty() || image.type() != CV_8UC1)
    throw std::invalid_argument("OrbExtractor: expected an 8-bit grey image");
  for (int l = 0; l < options_.levels; ++l) {
    const cv::Size size(static_cast<int>(std::lround(image.cols * scales_.inv_scale[l])),
                        static_cast<int>(std::lround(image.rows * scales_.inv_scale[l])));
    if (size.width <= kOrbBorderPx || size.height <= kOrbBorderPx) {
      // Too small to reflect in place: cv::copyMakeBorder reflects repeatedly.
      const cv::Mat* source = &image;
      if (l > 0) {
        cv::resize(level_[l - 1], resize_scratch_, size, 0, 0, cv::INTER_LINEAR);
        source = &resize_scratch_;
      }
      cv::copyMakeBorder(*source, padded_[l], kOrbBorderPx, kOrbBorderPx, kOrbBorderPx, kOrbBorderPx,
                         cv::BORDER_REFLECT_101);
      level_[l] = padded_[l](cv::Rect(kOrbBorderPx, kOrbBorderPx, size.width, size.height));
      continue;
    }
    // The level straight into its padded buffer (reused across frames; create() is a no-op at the
    // same size), then the border around it: no copy of the level.
    padded_[l].create(size.height + 2 * kOrbBorderPx, size.width + 2 * kOrbBorderPx, CV_8UC1);
    level_[l] = padded_[l](cv::Rect(kOrbBorderPx, kOrbBorderPx, size.width, size.height));
    if (l == 0) {
      image.copyTo(level_[l]);
    } else {
      // Bit-exact with cv::resize(..., INTER_LINEAR), at a fraction of its instructions.
      resizes_[static_cast<std::size_t>(l)].apply(level_[l - 1], level_[l]);
    }
    reflect_border(padded_[l], kOrbBorderPx);
  }
}

void OrbExtractor::detect() {
  for (int l = 0; l < options_.levels; ++l) detect_level(l);
}

void OrbExtractor::detect_level(int level) {
  std::vector<LevelKeypoint>& result = level_keypoints_[static_cast<std::size_t>(level)];
  result.clear();
  const cv::Mat& image = level_[static_cast<std::size_t>(level)];
  const int min_x = kDetectionMarginPx;
  const int min_y = kDetectionMarginPx;
  const int max_x = image.cols - kDetectionMarginPx;  // exclusive
  const int max_y = image.rows - kDetectionMarginPx;
  const int wanted = features_per_level_[static_cast<std::size_t>(level)];
  if (max_x - min_x < 2 * kFastRadiusPx || max_y - min_y < 2 * kFastRadiusPx || wanted <= 0) return;

  // The grid: about cell_size_px square cells over the detection area.
  const int width = max_x - min_x;
  const int height = max_y - min_y;
  const int cols = std::max(1, static_cast<int>(width / options_.cell_size_px));
  const int rows = std::max(1, static_cast<int>(height / options_.cell_size_px));
  const int cell_w = (width + cols - 1) / cols;
  const int cell_h = (height + rows - 1) / rows;

  // FAST scores of the whole area in one pass; corners at the initial threshold over the area, then
  // at the fallback threshold in the cells that found none (each cell suppressing non-maxima among its
  // own pixels, as ORB-SLAM2's per-cell cv::FAST calls do).
  FastScoreMap& scores = score_maps_[static_cast<std::size_t>(level)];
  const cv::Rect area(min_x, min_y, width, height);
  scores.compute(image, area);
  std::vector<ScoredPoint>& points = level_points_[static_cast<std::size_t>(level)];
  points.clear();
  scores.corners(area, options_.fast_threshold_initial, points);
  std::vector<std::uint8_t> cell_found(static_cast<std::size_t>(cols * rows), 0);
  for (const ScoredPoint& p : points) {
    const int col = std::min((static_cast<int>(p.x) - min_x) / cell_w, cols - 1);
    const int row = std::min((static_cast<int>(p.y) - min_y) / cell_h, rows - 1);
    cell_found[static_cast<std::size_t>(row * cols + col)] = 1;
  }
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      if (cell_found[static_cast<std::size_t>(row * cols + col)]) continue;
      const int x0 = min_x + col * cell_w;
      const int y0 = min_y + row * cell_h;
      const int x1 = std::min(x0 + cell_w, max_x);
      const int y1 = std::min(y0 + cell_h, max_y);
      if (x1 - x0 < 1 || y1 - y0 < 1) continue;
      scores.corners(cv::Rect(x0, y0, x1 - x0, y1 - y0), options_.fast_threshold_min, points);
    }
  }

  if (!region_.empty()) {
    const float scale = scales_.scale[static_cast<std::size_t>(level)];
    std::erase_if(points, [&](const ScoredPoint& p) {
      const int x = std::min(static_cast<int>(std::lround(p.x * scale)), region_.cols - 1);
      const int y = std::min(static_cast<int>(std::lround(p.y * scale)), region_.rows - 1);
      return region_.at<std::uint8_t>(y, x) == 0;
    });
  }
  const std::vector<int> kept = distribute_quadtree(points, static_cast<float>(min_x), static_cast<float>(max_x),
                                                    static_cast<float>(min_y), static_cast<float>(max_y), wanted);

  // Orientation by intensity centroid over the circular patch (the level image is not blurred).
  const auto step = static_cast<int>(image.step1());
  result.reserve(kept.size());
  for (int i : kept) {
    const ScoredPoint& p = points[static_cast<std::size_t>(i)];
    const std::uint8_t* center = image.ptr<std::uint8_t>(static_cast<int>(p.y)) + static_cast<int>(p.x);
    const float angle = centroid_.angle_deg(center, step);
    result.push_back({p.x, p.y, p.response, angle});
  }
}

void OrbExtractor::describe(OrbFeatures& out) {
  for (int l = 0; l < options_.levels; ++l) describe_level(l);
  collect(out);
}

void OrbExtractor::detect_and_describe_level(int level) {
  detect_level(level);
  describe_level(level);
}

void OrbExtractor::collect(OrbFeatures& out) const {
  out.keypoints.clear();
  out.descriptors.clear();
  out.pyramid.assign(level_.begin(), level_.end());
  std::size_t total = 0;
  for (const auto& k : level_features_) total += k.keypoints.size();
  out.keypoints.reserve(total);
  out.descriptors.reserve(total);
  for (const OrbFeatures& level : level_features_) {
    out.keypoints.insert(out.keypoints.end(), level.keypoints.begin(), level.keypoints.end());
    out.descriptors.insert(out.descriptors.end(), level.descriptors.begin(), level.descriptors.end());
  }
}

void OrbExtractor::describe_level(int l) {
  OrbFeatures& level_out = level_features_[static_cast<std::size_t>(l)];
  level_out.keypoints.clear();
  level_out.descriptors.clear();
  const std::vector<LevelKeypoint>& kps = level_keypoints_[static_cast<std::size_t>(l)];
  if (kps.empty()) return;
  level_out.keypoints.reserve(kps.size());
  level_out.descriptors.reserve(kps.size());
  // Blur only the keypoints' bounding box grown by the patterns' reach (padded coordinates): the
  // same pixels there as cv::GaussianBlur of the whole padded level (DescriptorBlur is bit-exact).
  float min_x = kps.front().x, max_x = min_x, min_y = kps.front().y, max_y = min_y;
  for (const LevelKeypoint& k : kps) {
    min_x = std::min(min_x, k.x);
    max_x = std::max(max_x, k.x);
    min_y = std::min(min_y, k.y);
    max_y = std::max(max_y, k.y);
  }
  const int x0 = static_cast<int>(min_x) + kOrbBorderPx - kDescriptorReachPx;
  const int y0 = static_cast<int>(min_y) + kOrbBorderPx - kDescriptorReachPx;
  const int x1 = static_cast<int>(max_x) + kOrbBorderPx + kDescriptorReachPx + 1;  // exclusive
  const int y1 = static_cast<int>(max_y) + kOrbBorderPx + kDescriptorReachPx + 1;
  blurs_[static_cast<std::size_t>(l)].apply(padded_[l], cv::Rect(x0, y0, x1 - x0, y1 - y0), blurred_[l]);
  const cv::Mat& blurred = blurred_[l];
  const auto step = static_cast<int>(blurred.step1());
  const float scale = scales_.scale[static_cast<std::size_t>(l)];
  for (const LevelKeypoint& k : kps) {
    const std::uint8_t* center =
        blurred.ptr<std::uint8_t>(static_cast<int>(k.y) + kOrbBorderPx) + static_cast<int>(k.x) + kOrbBorderPx;
    const float radians = k.angle_deg * static_cast<float>(std::numbers::pi / 180.0);
    const float c = std::cos(radians);
    const float s = std::sin(radians);
    RotatedOrbPattern offsets;
    rotate_orb_pattern(c, s, step, offsets);
    const Descriptor d = rbrief_descriptor(center, offsets);
    Keypoint kp;
    kp.u_px = k.x * scale;
    kp.v_px = k.y * scale;
    kp.angle_deg = k.angle_deg;
    kp.response = k.response;
    kp.octave = l;
    level_out.keypoints.push_back(kp);
    level_out.descriptors.push_back(d);
  }
}

}  // namespace heslam
