// The default vocabulary on real images (EuRoC MH01 hand-held clip, not used for training): a frame
// scores higher against its neighbour frame than against the frame whose view differs most.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>

#include "components/core/place/default_vocabulary.hpp"
#include "components/core/place/image_descriptors.hpp"
#include "components/core/place/vocabulary_io.hpp"
#include "test_support.hpp"
#include "tools/dataset/ground_truth.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

struct ClipFrame {
  fs::path image;
  Eigen::Vector3d position;
  Eigen::Quaterniond orientation;
};

// The clip's left images with their ground-truth body poses (the project's dataset and ground-truth
// readers, tools/dataset), frames without a ground-truth pose within 1 ms left out.
std::vector<ClipFrame> read_clip(const fs::path& clip) {
  DatasetOptions options;
  options.load_calibration = false;
  const StereoDataset dataset = open_dataset(clip, options);
  std::vector<std::int64_t> stamps;
  for (const StereoFrameFiles& frame : dataset.frames) stamps.push_back(frame.stamp_ns);
  const std::vector<std::optional<Pose3>> poses =
      poses_at_stamps(eval::read_trajectory(euroc_ground_truth_file(clip / "mav0")), stamps, /*max_gap_s=*/0.001);
  std::vector<ClipFrame> frames;
  for (std::size_t i = 0; i < dataset.frames.size(); ++i) {
    if (!poses[i]) continue;
    frames.push_back({dataset.frames[i].left, poses[i]->translation(), Eigen::Quaterniond(poses[i]->linear())});
  }
  return frames;
}

TEST(VocabularyRealImages, NeighbourFrameScoresHigherThanADistantView) {
  const fs::path clip = test::shared_dataset("euroc_mh01_handheld");
  if (clip.empty())
    GTEST_SKIP() << "no " << (test::shared_data() / "euroc_mh01_handheld").string() << " (shared data absent)";
  if (!fs::exists(default_vocabulary_path())) {
    GTEST_SKIP() << "default vocabulary " << default_vocabulary_path().string()
                 << " not built (tools/train-vocabulary.sh)";
  }
  const Vocabulary vocabulary = load_vocabulary(default_vocabulary_path());
  const std::vector<ClipFrame> frames = read_clip(clip);
  ASSERT_GE(frames.size(), 100u);

  // The two frames whose body orientations differ most (27 degrees: the clip shakes back and forth
  // over the same part of the hall): the earlier is the query, the later its distant view.
  std::size_t query = 0;
  std::size_t distant = 0;
  double largest_angle = 0.0;
  for (std::size_t i = 0; i + 1 < frames.size(); ++i) {
    for (std::size_t j = i + 1; j < frames.size(); ++j) {
      const double angle = frames[i].orientation.angularDistance(frames[j].orientation);
      if (angle > largest_angle) {
        largest_angle = angle;
        query = i;
        distant = j;
      }
    }
  }
  ASSERT_GT(largest_angle, 20.0 * M_PI / 180.0);

  ImageDescriptorExtractor extractor;
  auto bow_of = [&](std::size_t i) {
    const cv::Mat image = cv::imread(frames[i].image.string(), cv::IMREAD_GRAYSCALE);
    EXPECT_FALSE(image.empty()) << frames[i].image;
    BowVector bow;
    vocabulary.transform(extractor.extract(image), bow, nullptr, 0);
    return bow;
  };
  const BowVector q = bow_of(query);
  const double neighbour_score = vocabulary.score(q, bow_of(query + 1));
  const double distant_score = vocabulary.score(q, bow_of(distant));
  std::cout << "frame " << query << ": neighbour score " << neighbour_score << ", distant (frame " << distant << ", "
            << largest_angle * 180.0 / M_PI << " deg) " << distant_score << "\n";
  EXPECT_GT(neighbour_score, 1.5 * distant_score);
}

}  // namespace
}  // namespace heslam
