// The full system (replay -> frontend -> local mapper -> loop closer -> recorder, lockstep
// config/pipelines/euroc.yaml with its shipped configs) on MH01 with the two cameras exposed apart,
// as users run it: copies of the clip written by heslam-photometric's library with the
// left x L / right x R (clipped to 8 bit), against the equal-exposure run of the same build.
// Measured (docs/benchmarks.md at 5c1f792, cameras exposed apart tenth pass): equal 3.831 mm / 15 keyframes;
// x0.35/x2 3.887 mm (1.01x) / 16; x1/x4 4.373 mm (1.14x) / 16 (before the left-only keypoints 4.965,
// 1.30x). A single run is one draw from a spread (x1/x4 4.0-4.9 mm under 1-2 % gain changes), so the
// ATE bound is 1.2x, a guard against regressions with room for the spread, and the keyframe bound the
// issue's 1.5x.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "pipeline_runs.hpp"
#include "test_support.hpp"
#include "tools/photometric/dataset_copy.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr double kMaxAteRatio = 1.2;
constexpr double kMaxKeyframeRatio = 1.5;
constexpr std::size_t kFrames = 160;

struct RunFigures {
  std::size_t poses = 0;
  int keyframes = 0;
  double ate_m = 0.0;
};

int lines_without_comment(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  int count = 0;
  while (std::getline(in, line)) count += !line.empty() && line[0] != '#' ? 1 : 0;
  return count;
}

// Runs the full system on `dataset` (a ground truth in the folder scores it); fails the test on a
// non-zero exit.
RunFigures run_full_system(const fs::path& dataset, const fs::path& dir, const std::string& label) {
  auto supervisor = test::start_pipeline("euroc", dataset, dir, label, test::exclusive_domain_id());
  const int rc = test::finish(*supervisor);
  EXPECT_EQ(rc, 0) << supervisor->out() << supervisor->err();
  RunFigures figures;
  if (rc != 0) return figures;
  figures.poses = eval::read_trajectory(dir / (label + ".txt")).size();
  figures.keyframes = lines_without_comment(dir / (label + ".keyframes.txt"));
  figures.ate_m = test::ate_rmse_m(dataset, dir / (label + ".txt"));
  return figures;
}

void expect_like_equal_exposure(const fs::path& source, const fs::path& dir, const RunFigures& equal,
                                photometric::StereoGain gain) {
  char label_text[64];
  std::snprintf(label_text, sizeof label_text, "gain_%g_%g", gain.left, gain.right);
  const std::string label = label_text;
  const fs::path copy = dir / label;
  photometric::DatasetCopyOptions options;
  options.stereo_gain = {gain};
  photometric::write_dataset_copy(source, copy, options);
  const RunFigures apart = run_full_system(copy, dir, label);
  std::printf(
      "[ figures  ] MH01 full system, left x%g / right x%g: ATE %.3f mm (%.2fx equal), %d keyframes (equal %d)\n",
      gain.left, gain.right, apart.ate_m * 1e3, apart.ate_m / equal.ate_m, apart.keyframes, equal.keyframes);
  EXPECT_EQ(apart.poses, kFrames) << label;
  EXPECT_LE(apart.keyframes, kMaxKeyframeRatio * equal.keyframes) << label;
  EXPECT_LT(apart.ate_m, kMaxAteRatio * equal.ate_m) << label;
}

TEST(FullSystemStereoGain, Mh01CamerasExposedApartTrackEveryFrameNearEqualExposure) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("exposed_apart");
  const RunFigures equal = run_full_system(dataset, dir.path(), "equal");
  ASSERT_EQ(equal.poses, kFrames);
  ASSERT_GT(equal.keyframes, 0);
  std::printf("[ figures  ] MH01 full system, equal exposure: ATE %.3f mm, %d keyframes\n", equal.ate_m * 1e3,
              equal.keyframes);
  expect_like_equal_exposure(dataset, dir.path(), equal, {0.35, 2.0});
  expect_like_equal_exposure(dataset, dir.path(), equal, {1.0, 4.0});
}

}  // namespace
}  // namespace heslam
