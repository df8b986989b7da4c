// Images the vision tests share: a real texture shipped with opencv-doc and rectified EuRoC pairs
// from ../shared/data (both located in place, never copied).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "test_support.hpp"

namespace heslam::test {

// A painting photographed by the Oxford affine-covariant-features data set (opencv-doc), grey.
inline const char* kTexturePath = "/usr/share/doc/opencv-doc/examples/data/graf1.png";

inline cv::Mat load_texture() { return cv::imread(kTexturePath, cv::IMREAD_GRAYSCALE); }

#define HESLAM_REQUIRE_TEXTURE()                                                                       \
  do {                                                                                                 \
    if (!std::filesystem::exists(::heslam::test::kTexturePath)) {                                      \
      GTEST_SKIP() << "texture " << ::heslam::test::kTexturePath << " not found (install opencv-doc)"; \
    }                                                                                                  \
  } while (0)

inline const char* kEurocDataset = "euroc_mh01_handheld";

struct RectifiedPair {
  cv::Mat left;
  cv::Mat right;
};

// Rectified EuRoC pairs number `frames` (0-based rows of cam0/data.csv) with the rectifier used.
inline std::vector<RectifiedPair> load_euroc_pairs(const std::vector<int>& frames, PinholeStereo* camera) {
  const std::filesystem::path mav0 = shared_dataset(kEurocDataset) / "mav0";
  const StereoRectifier rectifier(load_euroc_calibration(mav0));
  if (camera) *camera = rectifier.camera();
  std::vector<std::filesystem::path> names;
  for (const auto& entry : std::filesystem::directory_iterator(mav0 / "cam0" / "data")) {
    names.push_back(entry.path().filename());
  }
  std::sort(names.begin(), names.end());
  std::vector<RectifiedPair> pairs;
  for (int f : frames) {
    const auto& name = names.at(static_cast<std::size_t>(f));
    const cv::Mat left = cv::imread((mav0 / "cam0" / "data" / name).string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat right = cv::imread((mav0 / "cam1" / "data" / name).string(), cv::IMREAD_GRAYSCALE);
    RectifiedPair pair;
    rectifier.rectify(left, right, pair.left, pair.right);
    pair.left = pair.left.clone();
    pair.right = pair.right.clone();
    pairs.push_back(pair);
  }
  return pairs;
}

}  // namespace heslam::test
