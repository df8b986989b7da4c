// The synth output read the way ORB-SLAM2's stereo examples read it (ORB-SLAM2 itself is not packaged
// for Debian, so its loaders are re-implemented here from Examples/Stereo/stereo_euroc.cc and
// stereo_kitti.cc and Tracking's settings reads):
//   stereo_euroc VOC SETTINGS SEQ/mav0/cam0/data SEQ/mav0/cam1/data TIMES: one stamp in ns per line
//     of TIMES, images at <folder>/<stamp>.png; LEFT/RIGHT .K .D .R .P .height .width must all be
//     present ("Calibration parameters to rectify stereo are missing!" otherwise), and every image is
//     remapped with initUndistortRectifyMap(K, D, R, P(0:3, 0:3)).
//   stereo_kitti VOC SETTINGS SEQ: SEQ/times.txt (seconds), SEQ/image_0|1/%06d.png.
//   Tracking: Camera.fx/fy/cx/cy/k1/k2/p1/p2/bf/fps/RGB, ThDepth, ORBextractor.* as numbers.
#include <fstream>
#include <iomanip>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "synth_test_util.hpp"
#include "tools/synth/sequence.hpp"
#include "tools/synth/writers.hpp"

namespace heslam::synth {
namespace {

namespace fs = std::filesystem;

struct OrbSlamStereoInput {
  std::vector<std::string> left, right;
  std::vector<double> stamps_s;
};

// stereo_euroc.cc LoadImages.
OrbSlamStereoInput load_euroc(const fs::path& left_dir, const fs::path& right_dir, const fs::path& times) {
  OrbSlamStereoInput in;
  std::ifstream f(times);
  while (!f.eof()) {
    std::string s;
    std::getline(f, s);
    if (!s.empty()) {
      std::stringstream ss;
      ss << s;
      in.left.push_back(left_dir.string() + "/" + ss.str() + ".png");
      in.right.push_back(right_dir.string() + "/" + ss.str() + ".png");
      double t;
      ss >> t;
      in.stamps_s.push_back(t / 1e9);
    }
  }
  return in;
}

// stereo_kitti.cc LoadImages.
OrbSlamStereoInput load_kitti(const fs::path& sequence) {
  OrbSlamStereoInput in;
  std::ifstream f(sequence / "times.txt");
  while (!f.eof()) {
    std::string s;
    std::getline(f, s);
    if (!s.empty()) {
      std::stringstream ss;
      ss << s;
      double t;
      ss >> t;
      in.stamps_s.push_back(t);
    }
  }
  for (std::size_t i = 0; i < in.stamps_s.size(); ++i) {
    std::stringstream ss;
    ss << std::setfill('0') << std::setw(6) << i;
    in.left.push_back((sequence / "image_0").string() + "/" + ss.str() + ".png");
    in.right.push_back((sequence / "image_1").string() + "/" + ss.str() + ".png");
  }
  return in;
}

void expect_images_readable(const OrbSlamStereoInput& in, std::size_t frames, cv::Size size) {
  ASSERT_EQ(in.left.size(), frames);
  ASSERT_EQ(in.right.size(), frames);
  for (std::size_t i = 0; i < frames; ++i) {
    for (const std::string& path : {in.left[i], in.right[i]}) {
      const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);  // CV_LOAD_IMAGE_UNCHANGED
      ASSERT_FALSE(image.empty()) << "ORB-SLAM2 would fail: cannot read " << path;
      EXPECT_EQ(image.type(), CV_8UC1) << path;
      EXPECT_EQ(image.size(), size) << path;
    }
    if (i > 0) {
      EXPECT_GT(in.stamps_s[i], in.stamps_s[i - 1]);
    }
  }
}

// Tracking.cc: every value it reads must be a number (an absent key reads as 0 and breaks it).
void expect_tracking_settings(const cv::FileStorage& fs, double baseline_m) {
  for (const char* key : {"Camera.fx", "Camera.fy", "Camera.cx", "Camera.cy", "Camera.bf", "Camera.fps", "ThDepth",
                          "ORBextractor.nFeatures", "ORBextractor.scaleFactor", "ORBextractor.nLevels",
                          "ORBextractor.iniThFAST", "ORBextractor.minThFAST"}) {
    EXPECT_TRUE(fs[key].isReal() || fs[key].isInt()) << key;
    EXPECT_GT(static_cast<double>(fs[key]), 0.0) << key;
  }
  for (const char* key : {"Camera.k1", "Camera.k2", "Camera.p1", "Camera.p2", "Camera.RGB"}) {
    EXPECT_TRUE(fs[key].isReal() || fs[key].isInt()) << key;
  }
  EXPECT_NEAR(static_cast<double>(fs["Camera.bf"]) / static_cast<double>(fs["Camera.fx"]), baseline_m, 1e-6);
}

// stereo_euroc.cc: the rectification block and the maps it builds from it.
struct EurocRectification {
  cv::Mat M1l, M2l, M1r, M2r;
};

EurocRectification read_euroc_rectification(const cv::FileStorage& fs) {
  cv::Mat K_l, K_r, P_l, P_r, R_l, R_r, D_l, D_r;
  fs["LEFT.K"] >> K_l;
  fs["RIGHT.K"] >> K_r;
  fs["LEFT.P"] >> P_l;
  fs["RIGHT.P"] >> P_r;
  fs["LEFT.R"] >> R_l;
  fs["RIGHT.R"] >> R_r;
  fs["LEFT.D"] >> D_l;
  fs["RIGHT.D"] >> D_r;
  const int rows_l = fs["LEFT.height"];
  const int cols_l = fs["LEFT.width"];
  const int rows_r = fs["RIGHT.height"];
  const int cols_r = fs["RIGHT.width"];
  EurocRectification r;
  const bool missing = K_l.empty() || K_r.empty() || P_l.empty() || P_r.empty() || R_l.empty() || R_r.empty() ||
                       D_l.empty() || D_r.empty() || rows_l == 0 || rows_r == 0 || cols_l == 0 || cols_r == 0;
  EXPECT_FALSE(missing) << "stereo_euroc: ERROR: Calibration parameters to rectify stereo are missing!";
  if (missing) return r;
  cv::initUndistortRectifyMap(K_l, D_l, R_l, P_l.rowRange(0, 3).colRange(0, 3), cv::Size(cols_l, rows_l), CV_32F, r.M1l,
                              r.M2l);
  cv::initUndistortRectifyMap(K_r, D_r, R_r, P_r.rowRange(0, 3).colRange(0, 3), cv::Size(cols_r, rows_r), CV_32F, r.M1r,
                              r.M2r);
  // ORB-SLAM2's stereo model: the right camera's P must carry -fx * baseline, both share fx.
  EXPECT_NEAR(-P_r.at<double>(0, 3) / P_r.at<double>(0, 0),
              static_cast<double>(fs["Camera.bf"]) / static_cast<double>(fs["Camera.fx"]), 1e-6);
  EXPECT_NEAR(P_l.at<double>(0, 0), static_cast<double>(fs["Camera.fx"]), 1e-6);
  return r;
}

TEST(SynthOrbSlam2, StereoEurocReadsDistortedAndUndistortedSequences) {
  for (const bool distorted : {true, false}) {
    SCOPED_TRACE(distorted ? "distorted" : "undistorted");
    const fs::path dir =
        fs::temp_directory_path() / (std::string("heslam_synth_orbslam_euroc_") + (distorted ? "d" : "u"));
    fs::remove_all(dir);
    SequenceRenderer renderer(test::repo_preset("room"), {.seed = 2, .frames = 3, .apply_distortion = distorted});
    ASSERT_EQ(renderer.distortion_applied(), distorted);
    write_sequence(renderer, OutputFormat::kEuroc, dir);

    const OrbSlamStereoInput in =
        load_euroc(dir / "mav0" / "cam0" / "data", dir / "mav0" / "cam1" / "data", dir / "timestamps.txt");
    expect_images_readable(in, 3, cv::Size(752, 480));
    // ORB-SLAM2 divides the ns stamp by 1e9 in double: 1.6e9 s resolves to about 2.4e-7 s (as EuRoC's).
    EXPECT_NEAR(in.stamps_s[1] - in.stamps_s[0], 0.05, 1e-6);

    cv::FileStorage fs((dir / "orbslam2_settings.yaml").string(), cv::FileStorage::READ);
    ASSERT_TRUE(fs.isOpened());
    expect_tracking_settings(fs, 0.11);
    const EurocRectification rect = read_euroc_rectification(fs);
    ASSERT_FALSE(rect.M1l.empty());
    if (!distorted) {
      // Ideal pinhole images: ORB-SLAM2's remap must leave them as they are.
      cv::Mat identity_x(rect.M1l.size(), CV_32F), identity_y(rect.M1l.size(), CV_32F);
      for (int r = 0; r < identity_x.rows; ++r)
        for (int c = 0; c < identity_x.cols; ++c) {
          identity_x.at<float>(r, c) = static_cast<float>(c);
          identity_y.at<float>(r, c) = static_cast<float>(r);
        }
      EXPECT_LT(cv::norm(rect.M1l, identity_x, cv::NORM_INF), 1e-3);
      EXPECT_LT(cv::norm(rect.M2l, identity_y, cv::NORM_INF), 1e-3);
      EXPECT_LT(cv::norm(rect.M1r, identity_x, cv::NORM_INF), 1e-3);
      EXPECT_LT(cv::norm(rect.M2r, identity_y, cv::NORM_INF), 1e-3);
    } else {
      // Distorted images: the maps really undistort (not the identity).
      const cv::Mat left = cv::imread(in.left[0], cv::IMREAD_UNCHANGED);
      cv::Mat rectified;
      cv::remap(left, rectified, rect.M1l, rect.M2l, cv::INTER_LINEAR);
      EXPECT_EQ(rectified.size(), left.size());
      EXPECT_GT(cv::norm(rect.M1l.col(0), cv::NORM_INF), 0.5);
    }
    fs::remove_all(dir);
  }
}

TEST(SynthOrbSlam2, StereoKittiReadsTheKittiLayout) {
  const fs::path dir = fs::temp_directory_path() / "heslam_synth_orbslam_kitti";
  fs::remove_all(dir);
  SequenceRenderer renderer(test::repo_preset("street"), {.seed = 2, .frames = 3, .apply_distortion = false});
  write_sequence(renderer, OutputFormat::kKitti, dir);
  const OrbSlamStereoInput in = load_kitti(dir);
  expect_images_readable(in, 3, cv::Size(1241, 376));
  EXPECT_NEAR(in.stamps_s[0], 0.0, 1e-12);
  EXPECT_NEAR(in.stamps_s[1], 0.1, 1e-9);
  cv::FileStorage fs((dir / "orbslam2_settings.yaml").string(), cv::FileStorage::READ);
  ASSERT_TRUE(fs.isOpened());
  expect_tracking_settings(fs, 0.54);
  EXPECT_DOUBLE_EQ(static_cast<double>(fs["Camera.fx"]), 718.856);
  // ORB-SLAM2's own KITTI settings (Examples/Stereo/KITTI00-02.yaml) ask 2000 features, EuRoC's 1200.
  EXPECT_EQ(static_cast<int>(fs["ORBextractor.nFeatures"]), 2000);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace heslam::synth
