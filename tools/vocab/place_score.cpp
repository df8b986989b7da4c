// Top-candidate precision / recall of a vocabulary against ground-truth camera poses.
#include "tools/vocab/place_score.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "components/core/place/image_descriptors.hpp"
#include "tools/dataset/ground_truth.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::vocab {
namespace {

namespace fs = std::filesystem;

// Ground truth and frames are paired by stamp when they are this close (EuRoC: same stamps).
constexpr double kMaxStampGapS = 0.005;

struct ScoredFrame {
  std::size_t index = 0;  // in the dataset
  double stamp_s = 0;
  Pose3 T_wc = Pose3::Identity();
  BowVector bow;
};

// Camera poses per dataset frame (nullopt-free: frames without ground truth are dropped by the caller).
std::vector<std::optional<Pose3>> ground_truth(const StereoDataset& dataset) {
  std::vector<std::optional<Pose3>> poses(dataset.frames.size());
  if (dataset.format == DatasetFormat::kKitti) {
    const eval::Trajectory t = eval::read_trajectory(dataset.root / "poses.txt", {.format = eval::Format::kitti});
    for (std::size_t i = 0; i < poses.size() && i < t.size(); ++i) poses[i] = t.poses_wc[i];
    return poses;
  }
  const fs::path mav0 = fs::exists(dataset.root / "mav0") ? dataset.root / "mav0" : dataset.root;
  const fs::path csv = euroc_ground_truth_file(mav0);
  if (!fs::exists(csv)) throw std::runtime_error(csv.string() + ": no ground truth (score needs it)");
  const eval::Trajectory t =
      eval::read_trajectory(csv, {.format = eval::Format::euroc, .extrinsic_path = mav0 / "cam0" / "sensor.yaml"});
  std::vector<std::int64_t> stamps_ns;
  for (const StereoFrameFiles& frame : dataset.frames) stamps_ns.push_back(frame.stamp_ns);
  return poses_at_stamps(t, stamps_ns, kMaxStampGapS);
}

double view_angle_deg(const Pose3& a, const Pose3& b) {
  const double cosine = std::clamp(a.linear().col(2).dot(b.linear().col(2)), -1.0, 1.0);
  return std::acos(cosine) * 180.0 / M_PI;
}

}  // namespace

ScoreSummary score_dataset(const ScoreOptions& options, const Vocabulary& vocabulary, std::ostream& out) {
  const StereoDataset dataset = open_dataset(options.dataset);
  const std::vector<std::optional<Pose3>> truth = ground_truth(dataset);
  OrbOptions orb;
  orb.features = options.features;
  ImageDescriptorExtractor extractor({}, orb);

  std::vector<ScoredFrame> frames;
  double transform_ms = 0.0;
  for (std::size_t i = 0; i < dataset.frames.size(); i += options.step) {
    if (!truth[i]) continue;
    const cv::Mat image = cv::imread(dataset.frames[i].left.string(), cv::IMREAD_GRAYSCALE);
    if (image.empty()) throw std::runtime_error(dataset.frames[i].left.string() + ": cannot decode image");
    const std::vector<Descriptor> descriptors = extractor.extract(image);
    ScoredFrame frame{i, dataset.frames[i].stamp_ns * 1e-9, *truth[i], {}};
    const auto start = std::chrono::steady_clock::now();
    vocabulary.transform(descriptors, frame.bow, nullptr, 0);
    transform_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    frames.push_back(std::move(frame));
  }

  struct Query {
    double score;
    bool correct;
  };
  std::vector<Query> queries;
  ScoreSummary summary;
  summary.frames = static_cast<int>(frames.size());
  summary.mean_transform_ms = frames.empty() ? 0.0 : transform_ms / frames.size();
  if (options.verbose) out << "query_frame best_frame score distance_m angle_deg correct revisit\n";
  for (std::size_t q = 0; q < frames.size(); ++q) {
    const ScoredFrame& query = frames[q];
    std::size_t best = frames.size();
    double best_score = -1.0;
    bool revisit = false;
    for (std::size_t c = 0; c < q && frames[c].stamp_s <= query.stamp_s - options.exclude_recent_s; ++c) {
      const double score = vocabulary.score(query.bow, frames[c].bow);
      if (score > best_score) {
        best_score = score;
        best = c;
      }
      const double distance = (frames[c].T_wc.translation() - query.T_wc.translation()).norm();
      revisit = revisit || (distance < options.max_distance_m &&
                            view_angle_deg(frames[c].T_wc, query.T_wc) < options.max_angle_deg);
    }
    if (best == frames.size()) continue;
    const double distance = (frames[best].T_wc.translation() - query.T_wc.translation()).norm();
    const double angle = view_angle_deg(frames[best].T_wc, query.T_wc);
    const bool correct = distance < options.max_distance_m && angle < options.max_angle_deg;
    queries.push_back({best_score, correct});
    summary.revisits += revisit ? 1 : 0;
    summary.correct += correct ? 1 : 0;
    if (options.verbose) {
      char line[160];
      std::snprintf(line, sizeof(line), "%zu %zu %.4f %.2f %.1f %d %d\n", query.index, frames[best].index, best_score,
                    distance, angle, correct ? 1 : 0, revisit ? 1 : 0);
      out << line;
    }
  }
  summary.queries = static_cast<int>(queries.size());
  summary.precision_all = queries.empty() ? 0.0 : static_cast<double>(summary.correct) / queries.size();
  summary.recall_all = summary.revisits == 0 ? 0.0 : static_cast<double>(summary.correct) / summary.revisits;

  // Accept the top candidates scoring at least a threshold: the highest-scoring queries first.
  std::sort(queries.begin(), queries.end(), [](const Query& a, const Query& b) { return a.score > b.score; });
  int true_positives = 0;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    if (!queries[i].correct) break;
    ++true_positives;
    summary.threshold_at_precision_1 = queries[i].score;
  }
  summary.recall_at_precision_1 = summary.revisits == 0 ? 0.0 : static_cast<double>(true_positives) / summary.revisits;
  return summary;
}

}  // namespace heslam::vocab
