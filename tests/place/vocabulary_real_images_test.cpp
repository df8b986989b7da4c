// The default vocabulary on real images (EuRoC MH01 hand-held clip, not used for training): a frame
// scores higher against its neighbour frame than against the frame whose view differs most.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "components/core/place/default_vocabulary.hpp"
#include "components/core/place/image_descriptors.hpp"
#include "components/core/place/vocabulary_io.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

struct ClipFrame {
  fs::path image;
  Eigen::Vector3d position;
  Eigen::Quaterniond orientation;
};

// cam0/data.csv rows paired with the ground-truth rows (one per frame, same order and stamps).
std::vector<ClipFrame> read_clip(const fs::path& mav0) {
  std::vector<ClipFrame> frames;
  std::ifstream images(mav0 / "cam0/data.csv");
  std::ifstream truth(mav0 / "state_groundtruth_estimate0/data.csv");
  std::string image_line, truth_line;
  while (std::getline(images, image_line)) {
    if (image_line.empty() || image_line[0] == '#') continue;
    do {
      if (!std::getline(truth, truth_line)) return frames;
    } while (truth_line.empty() || truth_line[0] == '#');
    std::replace(truth_line.begin(), truth_line.end(), ',', ' ');
    std::istringstream values(truth_line);
    double stamp, x, y, z, qw, qx, qy, qz;
    values >> stamp >> x >> y >> z >> qw >> qx >> qy >> qz;
    const std::string file = image_line.substr(image_line.find(',') + 1);
    frames.push_back({mav0 / "cam0/data" / file.substr(0, file.find_last_not_of(" \r") + 1), {x, y, z},
                      Eigen::Quaterniond(qw, qx, qy, qz).normalized()});
  }
  return frames;
}

TEST(VocabularyRealImages, NeighbourFrameScoresHigherThanADistantView) {
  const fs::path clip = test::shared_dataset("euroc_mh01_handheld");
  if (clip.empty()) GTEST_SKIP() << "no " << (test::shared_data() / "euroc_mh01_handheld").string() << " (shared data absent)";
  if (!fs::exists(default_vocabulary_path())) {
    GTEST_SKIP() << "default vocabulary " << default_vocabulary_path().string() << " not built (tools/train-vocabulary.sh)";
  }
  const Vocabulary vocabulary = load_vocabulary(default_vocabulary_path());
  const std::vector<ClipFrame> frames = read_clip(clip / "mav0");
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
