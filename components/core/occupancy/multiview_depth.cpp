// Multi-view refinement of stereo disparity (see multiview_depth.hpp).
#include "components/core/occupancy/multiview_depth.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "runtime/atomic_file.hpp"

namespace heslam {
namespace {

// A window's grey-level variance (per pixel) below this is no texture to correlate.
constexpr float kMinVariance = 1.0f;
// A view's sample point must lie this far in front of its camera (metres).
constexpr float kMinViewDepthM = 0.05f;
// The sampling position given to remap for pixels without a surface: far outside any image (sampled as 0).
constexpr float kOutside = -1.0e4f;

[[noreturn]] void fail(const std::string& source, const std::string& field, const std::string& expected) {
  throw std::runtime_error(source + ": " + field + " must be " + expected);
}

cv::Mat box_sum(const cv::Mat& values, int radius) {
  cv::Mat sum;
  const int side = 2 * radius + 1;
  cv::boxFilter(values, sum, CV_32F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_REPLICATE);
  return sum;
}

// A view as the keyframe's pixels see it: its image, the rotation of the keyframe's camera into the view's
// applied to each pixel's ray (x_n, y_n, 1) (three planes), and the keyframe's centre in the view's frame.
struct Target {
  cv::Mat image;  // CV_32F, prefiltered
  cv::Mat ray[3];
  Eigen::Vector3f t = Eigen::Vector3f::Zero();
  bool neighbour = true;  // false: the right image
};

// The base surface of a disparity image (<= 0: none): the window mean of the valid disparities where the
// window holds no step of step_px or more, else the pixel's own value.
cv::Mat base_surface(const cv::Mat& disparity, int radius, float step) {
  cv::Mat base(disparity.size(), CV_32F, cv::Scalar(-1.f));
  const cv::Mat valid_mask = disparity > 0.f;
  cv::Mat valid;
  valid_mask.convertTo(valid, CV_32F, 1.0 / 255.0);
  const cv::Mat values = disparity.mul(valid);
  const int side = 2 * radius + 1;
  cv::Mat sum, count, high, low = disparity.clone();
  cv::boxFilter(values, sum, CV_32F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(valid, count, CV_32F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(side, side));
  low.setTo(std::numeric_limits<float>::max(), ~valid_mask);
  cv::dilate(disparity, high, kernel);
  cv::erode(low, low, kernel);
  for (int v = 0; v < disparity.rows; ++v) {
    const float *d = disparity.ptr<float>(v), *su = sum.ptr<float>(v), *c = count.ptr<float>(v);
    const float *h = high.ptr<float>(v), *l = low.ptr<float>(v);
    float* b = base.ptr<float>(v);
    for (int u = 0; u < disparity.cols; ++u) {
      if (c[u] >= 1.f && h[u] - l[u] < step) {
        b[u] = su[u] / c[u];
      } else if (d[u] > 0.f) {
        b[u] = d[u];
      }
    }
  }
  return base;
}

}  // namespace

void MultiViewDepthOptions::check(const std::string& source) const {
  if (neighbours < 0 || neighbours > 8) fail(source, "multiview.neighbours", "0..8");
  if (!(min_baseline_ratio >= 0.0) || !std::isfinite(min_baseline_ratio)) {
    fail(source, "multiview.min_baseline_ratio", ">= 0");
  }
  if (!(max_baseline_m > 0.0) || !std::isfinite(max_baseline_m)) fail(source, "multiview.max_baseline_m", "> 0");
  if (!(search_range_px > 0.0) || search_range_px > 8.0) fail(source, "multiview.search_range_px", "in (0, 8]");
  if (!(step_px > 0.0) || step_px > 4.0) fail(source, "multiview.step_px", "in (0, 4]");
  if (max_candidates < 3 || max_candidates > 129) fail(source, "multiview.max_candidates", "3..129");
  if (patch_radius_px < 1 || patch_radius_px > 8) fail(source, "multiview.patch_radius_px", "1..8");
  if (base_radius_px < 0 || base_radius_px > 16) fail(source, "multiview.base_radius_px", "0..16");
  if (!(base_step_px > 0.0) || !std::isfinite(base_step_px)) fail(source, "multiview.base_step_px", "> 0");
  if (!(prefilter_sigma_px >= 0.0) || prefilter_sigma_px > 8.0) fail(source, "multiview.prefilter_sigma_px", "0..8");
  if (level < 0 || level > 2) fail(source, "multiview.level", "0..2");
  if (passes < 1 || passes > 4) fail(source, "multiview.passes", "1..4");
  if (!(pass_range_factor > 0.0) || pass_range_factor > 1.0) fail(source, "multiview.pass_range_factor", "in (0, 1]");
  if (!(min_zncc >= -1.0) || !(min_zncc <= 1.0)) fail(source, "multiview.min_zncc", "in [-1, 1]");
}

MultiViewDepth::MultiViewDepth(const PinholeStereo& camera, const MultiViewDepthOptions& options)
    : camera_(camera), options_(options) {
  options_.check("multi-view depth options");
  if (!(camera.fx_px > 0.0) || !(camera.fy_px > 0.0) || !(camera.baseline_m > 0.0) || camera.width_px <= 0 ||
      camera.height_px <= 0) {
    throw std::runtime_error("multi-view depth: the rectified camera needs fx, fy > 0, baseline > 0 and a size");
  }
}

namespace {

// An image as matched at `level`: grey float, smoothed by the prefilter, halved `level` times (pyrDown: pixel
// i of a level is pixel 2 i of the one below).
cv::Mat prepare(const cv::Mat& image, double prefilter_sigma, int level) {
  cv::Mat f;
  image.convertTo(f, CV_32F);
  if (prefilter_sigma > 0.0) cv::GaussianBlur(f, f, cv::Size(0, 0), prefilter_sigma);
  for (int i = 0; i < level; ++i) cv::pyrDown(f, f);
  return f;
}

PinholeStereo at_level(const PinholeStereo& camera, int level) {
  PinholeStereo c = camera;
  for (int i = 0; i < level; ++i) {
    c.fx_px *= 0.5;
    c.fy_px *= 0.5;
    c.cx_px *= 0.5;
    c.cy_px *= 0.5;
    c.width_px = (c.width_px + 1) / 2;
    c.height_px = (c.height_px + 1) / 2;
  }
  return c;
}

}  // namespace

void MultiViewDepth::add_view(const cv::Mat& left, const Pose3& T_wc) {
  if (!options_.enabled()) return;
  View view;
  view.image = prepare(left, options_.prefilter_sigma_px, options_.level);
  view.T_wc = T_wc;
  views_.push_back(std::move(view));
  while (static_cast<int>(views_.size()) > options_.neighbours) views_.pop_front();
}

cv::Mat MultiViewDepth::refine(const cv::Mat& disparity, const cv::Mat& left, const cv::Mat& right, const Pose3& T_wc,
                               MultiViewDepthStats* stats) const {
  MultiViewDepthStats local;
  MultiViewDepthStats& s = stats ? *stats : local;
  s = {};
  const cv::Size full_size(camera_.width_px, camera_.height_px);
  if (disparity.size() != full_size || disparity.type() != CV_32F || left.size() != full_size ||
      right.size() != full_size) {
    throw std::runtime_error("multi-view depth: disparity and images must be of the camera's size");
  }
  cv::Mat out = disparity.clone();
  const int level = options_.level;
  const int scale = 1 << level;
  const PinholeStereo camera = at_level(camera_, level);
  const cv::Size size(camera.width_px, camera.height_px);
  const int rows = size.height, cols = size.width;
  const float bf = static_cast<float>(camera.bf());

  // The kept views that qualify, the latest first (a fixed order), then the right image.
  const double min_baseline = options_.min_baseline_ratio * camera_.baseline_m;
  std::vector<Pose3> T_kc;  // keyframe camera -> view camera
  std::vector<cv::Mat> images;
  for (auto it = views_.rbegin(); it != views_.rend(); ++it) {
    const Pose3 T = it->T_wc.inverse() * T_wc;
    const double baseline = T.translation().norm();
    if (!T.matrix().allFinite() || baseline < min_baseline || baseline > options_.max_baseline_m) continue;
    T_kc.push_back(T);
    images.push_back(it->image);
  }
  if (T_kc.empty()) return out;
  if (options_.use_right) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(-camera_.baseline_m, 0.0, 0.0);
    T_kc.push_back(T);
    images.push_back(prepare(right, options_.prefilter_sigma_px, level));
  }
  // Each pixel's normalized ray, turned into each view.
  std::vector<float> xn(static_cast<std::size_t>(cols)), yn(static_cast<std::size_t>(rows));
  for (int u = 0; u < cols; ++u) xn[u] = static_cast<float>((u - camera.cx_px) / camera.fx_px);
  for (int v = 0; v < rows; ++v) yn[v] = static_cast<float>((v - camera.cy_px) / camera.fy_px);
  std::vector<Target> targets;
  for (std::size_t k = 0; k < T_kc.size(); ++k) {
    Target target;
    target.image = images[k];
    target.neighbour = !(options_.use_right && k + 1 == T_kc.size());
    const Eigen::Matrix3f R = T_kc[k].linear().cast<float>();
    target.t = T_kc[k].translation().cast<float>();
    for (cv::Mat& plane : target.ray) plane.create(size, CV_32F);
    for (int v = 0; v < rows; ++v) {
      float *rx = target.ray[0].ptr<float>(v), *ry = target.ray[1].ptr<float>(v), *rz = target.ray[2].ptr<float>(v);
      for (int u = 0; u < cols; ++u) {
        const Eigen::Vector3f r = R * Eigen::Vector3f(xn[u], yn[v], 1.f);
        rx[u] = r.x();
        ry[u] = r.y();
        rz[u] = r.z();
      }
    }
    targets.push_back(std::move(target));
  }
  s.views_used = targets.size();

  // The base surface at full resolution, and the disparities and base at the level's pixels (pixel i of
  // the level is pixel scale i of the image), in the level's pixels.
  const cv::Mat full_base =
      base_surface(disparity, options_.base_radius_px * scale, static_cast<float>(options_.base_step_px));
  cv::Mat level_disparity(size, CV_32F), base(size, CV_32F);
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) {
      const int fv = std::min(scale * v, full_size.height - 1), fu = std::min(scale * u, full_size.width - 1);
      const float d = disparity.at<float>(fv, fu), b = full_base.at<float>(fv, fu);
      level_disparity.at<float>(v, u) = d > 0.f ? d / scale : -1.f;
      base.at<float>(v, u) = b > 0.f ? b / scale : -1.f;
    }
  }
  const cv::Mat first_base = base.clone();
  // The step: step_px in the view whose projection moves most per stereo pixel (sampled over the image).
  double sensitivity = 0.0;
  for (int v = rows / 16; v < rows; v += rows / 8) {
    for (int u = cols / 16; u < cols; u += cols / 8) {
      const float b = base.at<float>(v, u);
      if (!(b > 0.25f)) continue;
      for (const Target& target : targets) {
        const auto project = [&](float d) {
          const float z = bf / d;
          const Eigen::Vector3f p(z * target.ray[0].at<float>(v, u) + target.t.x(),
                                  z * target.ray[1].at<float>(v, u) + target.t.y(),
                                  z * target.ray[2].at<float>(v, u) + target.t.z());
          return Eigen::Vector2f(static_cast<float>(camera.fx_px) * p.x() / p.z(),
                                 static_cast<float>(camera.fy_px) * p.y() / p.z());
        };
        sensitivity = std::max(sensitivity, static_cast<double>((project(b + 0.05f) - project(b)).norm()) / 0.05);
      }
    }
  }
  if (!(sensitivity > 0.0)) return out;
  const double step = options_.step_px / sensitivity;

  // The keyframe's window statistics.
  const int radius = options_.patch_radius_px;
  const float n = static_cast<float>((2 * radius + 1) * (2 * radius + 1));
  const cv::Mat a = prepare(left, options_.prefilter_sigma_px, level);
  const cv::Mat sa = box_sum(a, radius), saa = box_sum(a.mul(a), radius);
  const float margin = static_cast<float>(radius + 1);
  const float fx = static_cast<float>(camera.fx_px), fy = static_cast<float>(camera.fy_px);
  const float cx = static_cast<float>(camera.cx_px), cy = static_cast<float>(camera.cy_px);
  const float max_u = static_cast<float>(cols - 1) - margin, max_v = static_cast<float>(rows - 1) - margin;
  const float nan = std::numeric_limits<float>::quiet_NaN();

  cv::Mat best(size, CV_32F), before(size, CV_32F), after(size, CV_32F), best_index(size, CV_32S),
      previous(size, CV_32F);
  cv::Mat score_sum(size, CV_32F), score_count(size, CV_32F), neighbour_count(size, CV_32F);
  cv::Mat map_x(size, CV_32F), map_y(size, CV_32F), inside(size, CV_8U), warped;
  cv::Mat refined(size, CV_32F);  // the pass's result (NaN: not refined)
  double range = options_.search_range_px / scale;
  for (int pass = 0; pass < options_.passes; ++pass) {
    if (pass > 0) {
      // The previous pass's values (SGBM's where it failed) make the next base; the range shrinks.
      cv::Mat next = level_disparity.clone();
      for (int v = 0; v < rows; ++v) {
        const float* r = refined.ptr<float>(v);
        float* d = next.ptr<float>(v);
        for (int u = 0; u < cols; ++u) {
          if (std::isfinite(r[u])) d[u] = r[u];
        }
      }
      base = base_surface(next, options_.base_radius_px, static_cast<float>(options_.base_step_px) / scale);
      range *= options_.pass_range_factor;
    }
    double pass_step = step;
    int half = static_cast<int>(std::ceil(range / pass_step));
    if (2 * half + 1 > options_.max_candidates) {
      half = (options_.max_candidates - 1) / 2;
      pass_step = range / half;
    }
    const int candidates = 2 * half + 1;
    s.candidates += static_cast<std::size_t>(candidates);
    // Per candidate, the views' mean ZNCC; per pixel the best candidate and the scores beside it.
    best.setTo(-2.f);
    before.setTo(nan);
    after.setTo(nan);
    best_index.setTo(-1);
    previous.setTo(nan);
    for (int j = 0; j < candidates; ++j) {
      const float offset = static_cast<float>((j - half) * pass_step);
      score_sum.setTo(0.f);
      score_count.setTo(0.f);
      neighbour_count.setTo(0.f);
      for (const Target& target : targets) {
        for (int v = 0; v < rows; ++v) {
          const float* b = base.ptr<float>(v);
          const float *rx = target.ray[0].ptr<float>(v), *ry = target.ray[1].ptr<float>(v),
                      *rz = target.ray[2].ptr<float>(v);
          float *mx = map_x.ptr<float>(v), *my = map_y.ptr<float>(v);
          unsigned char* in = inside.ptr<unsigned char>(v);
          for (int u = 0; u < cols; ++u) {
            const float d = b[u] + offset;
            mx[u] = my[u] = kOutside;
            in[u] = 0;
            if (!(b[u] > 0.f) || !(d > 0.f)) continue;
            const float z = bf / d;
            const float pz = z * rz[u] + target.t.z();
            if (!(pz > kMinViewDepthM)) continue;
            const float x = fx * (z * rx[u] + target.t.x()) / pz + cx;
            const float y = fy * (z * ry[u] + target.t.y()) / pz + cy;
            mx[u] = x;
            my[u] = y;
            in[u] = x >= margin && y >= margin && x <= max_u && y <= max_v;
          }
        }
        cv::remap(target.image, warped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
        const cv::Mat sw = box_sum(warped, radius), sww = box_sum(warped.mul(warped), radius),
                      saw = box_sum(a.mul(warped), radius);
        const float neighbour = target.neighbour ? 1.f : 0.f;
        for (int v = 0; v < rows; ++v) {
          const unsigned char* in = inside.ptr<unsigned char>(v);
          const float *pa = sa.ptr<float>(v), *paa = saa.ptr<float>(v), *pw = sw.ptr<float>(v),
                      *pww = sww.ptr<float>(v), *paw = saw.ptr<float>(v);
          float *ss = score_sum.ptr<float>(v), *sc = score_count.ptr<float>(v), *nc = neighbour_count.ptr<float>(v);
          for (int u = 0; u < cols; ++u) {
            if (!in[u]) continue;
            const float var_a = paa[u] - pa[u] * pa[u] / n;
            const float var_w = pww[u] - pw[u] * pw[u] / n;
            if (!(var_a > kMinVariance * n) || !(var_w > kMinVariance * n)) continue;
            ss[u] += (paw[u] - pa[u] * pw[u] / n) / std::sqrt(var_a * var_w);
            sc[u] += 1.f;
            nc[u] += neighbour;
          }
        }
      }
      for (int v = 0; v < rows; ++v) {
        const float *ss = score_sum.ptr<float>(v), *sc = score_count.ptr<float>(v), *nc = neighbour_count.ptr<float>(v);
        float *pb = best.ptr<float>(v), *pbefore = before.ptr<float>(v), *pafter = after.ptr<float>(v);
        float* prev = previous.ptr<float>(v);
        int* index = best_index.ptr<int>(v);
        for (int u = 0; u < cols; ++u) {
          const float score = nc[u] >= 1.f ? ss[u] / sc[u] : nan;
          if (score > pb[u]) {
            pb[u] = score;
            index[u] = j;
            pbefore[u] = prev[u];
            pafter[u] = nan;
          } else if (index[u] >= 0 && index[u] == j - 1) {
            pafter[u] = score;
          }
          prev[u] = score;
        }
      }
    }
    // The best candidate inside the range, fitted by a parabola, where its score is high enough.
    for (int v = 0; v < rows; ++v) {
      const float* d = level_disparity.ptr<float>(v);
      const float *b = base.ptr<float>(v), *pb = best.ptr<float>(v), *pbefore = before.ptr<float>(v),
                  *pafter = after.ptr<float>(v);
      const int* index = best_index.ptr<int>(v);
      float* r = refined.ptr<float>(v);
      for (int u = 0; u < cols; ++u) {
        r[u] = nan;  // a pixel the last pass does not refine keeps SGBM's value, not an earlier pass's
        if (!(d[u] > 0.f)) continue;
        const bool inner = index[u] > 0 && index[u] < candidates - 1;
        const float curvature = pbefore[u] - 2.f * pb[u] + pafter[u];
        if (!inner || !(pb[u] >= options_.min_zncc) || !std::isfinite(pbefore[u]) || !std::isfinite(pafter[u]) ||
            !(curvature < 0.f)) {
          continue;
        }
        const float sub = std::clamp(0.5f * (pbefore[u] - pafter[u]) / curvature, -0.5f, 0.5f);
        const float value = b[u] + static_cast<float>((index[u] - half + sub) * pass_step);
        if (value > 0.f) r[u] = value;
      }
    }
  }

  // Each pixel takes the offset of its nearest level pixel from the first base, on its own base.
  double change = 0.0;
  for (int v = 0; v < full_size.height; ++v) {
    float* d = out.ptr<float>(v);
    const float* fb = full_base.ptr<float>(v);
    const int lv = std::min((v + scale / 2) / scale, rows - 1);
    const float* r = refined.ptr<float>(lv);
    const float* b0 = first_base.ptr<float>(lv);
    for (int u = 0; u < full_size.width; ++u) {
      if (!(d[u] > 0.f)) continue;
      ++s.pixels;
      const int lu = std::min((u + scale / 2) / scale, cols - 1);
      const float value = level == 0 ? r[lu] : fb[u] + static_cast<float>(scale) * (r[lu] - b0[lu]);
      if (std::isfinite(value) && value > 0.f && fb[u] > 0.f) {
        change += std::abs(value - d[u]);
        d[u] = value;
        ++s.refined;
      } else if (!options_.keep_unrefined) {
        d[u] = -1.f;
      }
    }
  }
  s.mean_abs_change_px = s.refined ? change / static_cast<double>(s.refined) : 0.0;
  return out;
}

namespace {

constexpr char kViewMagic[8] = {'H', 'E', 'S', 'V', 'I', 'E', 'W', '1'};

template <typename T>
void append(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(value));
}

}  // namespace

void write_view(const std::filesystem::path& file, const KeptView& view) {
  if (view.left.type() != CV_8UC1 || view.left.empty()) {
    throw std::invalid_argument(file.string() + ": a kept view is an 8-bit grey image");
  }
  std::string out(kViewMagic, sizeof(kViewMagic));
  append(out, view.keyframe_id);
  append(out, view.sequence);
  const Eigen::Matrix4d T = view.T_wc.matrix();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) append(out, T(r, c));
  }
  append(out, static_cast<std::int32_t>(view.left.rows));
  append(out, static_cast<std::int32_t>(view.left.cols));
  for (int r = 0; r < view.left.rows; ++r) out.append(view.left.ptr<char>(r), static_cast<std::size_t>(view.left.cols));
  runtime::replace_file_contents(file, out, /*sync=*/false);
}

KeptView read_view(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + ": cannot open");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  constexpr std::size_t kHeader = sizeof(kViewMagic) + 2 * sizeof(std::uint64_t) + 16 * sizeof(double) + 8;
  if (bytes.size() < kHeader || std::memcmp(bytes.data(), kViewMagic, sizeof(kViewMagic)) != 0) {
    throw std::runtime_error(file.string() + ": not a heslam-occupancy kept view (magic HESVIEW1)");
  }
  KeptView view;
  const char* at = bytes.data() + sizeof(kViewMagic);
  std::memcpy(&view.keyframe_id, at, 8);
  std::memcpy(&view.sequence, at + 8, 8);
  Eigen::Matrix4d T;
  for (int i = 0; i < 16; ++i) std::memcpy(&T(i / 4, i % 4), at + 16 + 8 * i, 8);
  std::int32_t rows = 0, cols = 0;
  std::memcpy(&rows, at + 16 + 128, 4);
  std::memcpy(&cols, at + 16 + 128 + 4, 4);
  if (rows <= 0 || cols <= 0 || bytes.size() != kHeader + static_cast<std::size_t>(rows) * cols) {
    throw std::runtime_error(file.string() + ": " + std::to_string(bytes.size()) + " bytes for a " +
                             std::to_string(cols) + "x" + std::to_string(rows) + " image");
  }
  if (!T.allFinite() || T.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
    throw std::runtime_error(file.string() + ": the pose is not a finite rigid transform");
  }
  view.T_wc.matrix() = T;
  view.left = cv::Mat(rows, cols, CV_8UC1);
  std::memcpy(view.left.data, bytes.data() + kHeader, static_cast<std::size_t>(rows) * cols);
  return view;
}

}  // namespace heslam
