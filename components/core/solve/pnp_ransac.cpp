// PnP RANSAC: minimal AP3P hypotheses on seeded samples, inliers by chi-square, EPnP + LM refinement.
#include "components/core/solve/pnp_ransac.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace heslam {
namespace {

constexpr int kSampleSize = 4;  // AP3P: three points give up to four poses, the fourth picks one

struct Hypothesis {
  bool valid = false;
  Pose3 T_cw = Pose3::Identity();
};

Hypothesis solve(const std::vector<PnpCorrespondence>& all, const std::vector<int>& subset, const cv::Mat& K, int flags,
                 const Pose3* guess) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  object.reserve(subset.size());
  image.reserve(subset.size());
  for (int i : subset) {
    object.emplace_back(all[i].p_w.x(), all[i].p_w.y(), all[i].p_w.z());
    image.emplace_back(all[i].u_px, all[i].v_px);
  }
  cv::Mat rvec;
  cv::Mat tvec;
  bool use_guess = false;
  if (guess != nullptr) {
    cv::Mat R;
    cv::eigen2cv(Eigen::Matrix3d(guess->rotation()), R);
    cv::Rodrigues(R, rvec);
    tvec = (cv::Mat_<double>(3, 1) << guess->translation().x(), guess->translation().y(), guess->translation().z());
    use_guess = true;
  }
  Hypothesis h;
  try {
    h.valid = cv::solvePnP(object, image, K, cv::noArray(), rvec, tvec, use_guess, flags);
  } catch (const cv::Exception&) {
    h.valid = false;  // degenerate sample (e.g. collinear points): just another failed hypothesis
  }
  if (!h.valid || rvec.empty() || tvec.empty()) return {};
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d R_e;
  cv::cv2eigen(R, R_e);
  h.T_cw.linear() = R_e;
  h.T_cw.translation() = Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  if (!h.T_cw.matrix().allFinite()) return {};
  return h;
}

int classify(const PinholeStereo& camera, const std::vector<PnpCorrespondence>& all, const Pose3& T_cw,
             double chi2_threshold, std::vector<bool>& inlier) {
  inlier.assign(all.size(), false);
  int count = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    const Eigen::Vector3d p_c = T_cw * all[i].p_w;
    if (p_c.z() <= 0.0) continue;
    const Eigen::Vector2d uv = camera.project(p_c);
    const double e2 = (uv - Eigen::Vector2d(all[i].u_px, all[i].v_px)).squaredNorm() / all[i].sigma2;
    if (e2 < chi2_threshold) {
      inlier[i] = true;
      ++count;
    }
  }
  return count;
}

}  // namespace

std::optional<PnpRansacResult> PnpRansac::compute(const PinholeStereo& camera,
                                                  const std::vector<PnpCorrespondence>& correspondences) const {
  const int n = static_cast<int>(correspondences.size());
  if (n < std::max(kSampleSize, options_.min_inliers)) return std::nullopt;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1);

  // mt19937_64's output sequence is fixed by the standard; sampling uses it directly (no distribution
  // objects, whose algorithms differ between standard libraries) so runs are reproducible everywhere.
  std::mt19937_64 rng(options_.seed);
  PnpRansacResult best;
  std::vector<bool> inlier;
  int needed_iterations = options_.max_iterations;
  int iteration = 0;
  std::vector<int> sample;
  for (; iteration < needed_iterations; ++iteration) {
    sample.clear();
    while (static_cast<int>(sample.size()) < kSampleSize) {
      const int index = static_cast<int>(rng() % static_cast<std::uint64_t>(n));
      if (std::find(sample.begin(), sample.end(), index) == sample.end()) sample.push_back(index);
    }
    const Hypothesis h = solve(correspondences, sample, K, cv::SOLVEPNP_AP3P, nullptr);
    if (!h.valid) continue;
    const int count = classify(camera, correspondences, h.T_cw, options_.chi2_threshold, inlier);
    if (count > best.inliers) {
      best.inliers = count;
      best.T_cw = h.T_cw;
      best.inlier = inlier;
      // Adaptive stop: iterations for `probability` of drawing one all-inlier sample at this ratio.
      const double ratio = static_cast<double>(count) / n;
      const double p_all_inliers = std::pow(ratio, kSampleSize);
      if (p_all_inliers >= 1.0) {
        needed_iterations = iteration + 1;
      } else if (p_all_inliers > 0.0) {
        const double k = std::log(1.0 - options_.probability) / std::log(1.0 - p_all_inliers);
        needed_iterations = std::min(options_.max_iterations, static_cast<int>(std::ceil(k)));
      }
    }
  }
  if (best.inliers < std::max(kSampleSize, options_.min_inliers)) return std::nullopt;

  // Refine on the inliers (iterative LM from the best hypothesis), then reclassify; twice, since the
  // refined pose usually gathers a few more inliers.
  for (int refinement = 0; refinement < 2; ++refinement) {
    std::vector<int> subset;
    for (int i = 0; i < n; ++i) {
      if (best.inlier[i]) subset.push_back(i);
    }
    const Hypothesis refined = solve(correspondences, subset, K, cv::SOLVEPNP_ITERATIVE, &best.T_cw);
    if (!refined.valid) break;
    const int count = classify(camera, correspondences, refined.T_cw, options_.chi2_threshold, inlier);
    if (count < best.inliers) break;
    best.T_cw = refined.T_cw;
    best.inlier = inlier;
    best.inliers = count;
  }
  best.iterations = iteration;
  if (best.inliers < options_.min_inliers) return std::nullopt;
  return best;
}

}  // namespace heslam
