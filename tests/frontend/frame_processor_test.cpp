// FrameProcessor (the frontend's chain without DDS) is the chain of the offline harness: same
// calibration and images in, bit-identical poses out.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/frontend/frame_processor.hpp"
#include "components/messages/camera.hpp"
#include "runtime/config.hpp"
#include "test_support.hpp"
#include "tools/bench/frontend_offline/offline_run.hpp"
#include "tools/replay/replay_messages.hpp"

namespace heslam::frontend {
namespace {

TEST(FrameProcessor, EqualsTheOfflineHarnessOnEurocV101) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_v101_head");
  const auto sequence = bench::load_euroc_sequence(test::shared_dataset("euroc_v101_head"));
  const bench::OfflineRun offline = bench::run_offline(sequence, {});

  FrameProcessor processor(load_euroc_calibration(sequence.mav0_dir),
                           FrontendOptions::from_config(runtime::Config::empty()));
  ASSERT_EQ(offline.frames.size(), sequence.frames.size());
  for (std::size_t k = 0; k < sequence.frames.size(); ++k) {
    const cv::Mat left = cv::imread(sequence.frames[k].left_png.string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat right = cv::imread(sequence.frames[k].right_png.string(), cv::IMREAD_GRAYSCALE);
    const FrameOutput output = processor.process(sequence.frames[k].stamp_ns, k, left, right);
    EXPECT_EQ(static_cast<int>(output.stereo_keypoints), offline.frames[k].stereo_features) << "frame " << k;
    ASSERT_EQ(output.result.state, offline.frames[k].state) << "frame " << k;
    EXPECT_EQ(output.result.T_wc.matrix(), offline.frames[k].T_wc.matrix()) << "frame " << k;
  }
}

}  // namespace
}  // namespace heslam::frontend

namespace heslam::frontend {
namespace {

// What heslam-replay publishes (tools/replay/replay_messages.cpp) converted back gives the same
// rectified camera as the calibration file itself.
TEST(FrameProcessor, CalibrationThroughTheMessageRectifiesTheSame) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_v101_head");
  const StereoCalibration calibration = load_euroc_calibration(test::shared_dataset("euroc_v101_head") / "mav0");
  const CalibrationMessage message(calibration, StereoRectifier(calibration).camera());
  const StereoCalibration back = messages::to_calibration(message.get());
  EXPECT_EQ(back.left.T_BS.matrix(), calibration.left.T_BS.matrix());
  EXPECT_EQ(back.right.T_BS.matrix(), calibration.right.T_BS.matrix());
  const FrontendOptions options = FrontendOptions::from_config(runtime::Config::empty());
  const FrameProcessor direct(calibration, options);
  const FrameProcessor through(back, options);
  EXPECT_EQ(direct.camera().fx_px, through.camera().fx_px);
  EXPECT_EQ(direct.camera().cx_px, through.camera().cx_px);
  EXPECT_EQ(direct.camera().baseline_m, through.camera().baseline_m);
}

// A wrong-sized image is blamed on its side: here the right one (the left is fine).
TEST(FrameProcessor, WrongSizedImageNamesItsSide) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_v101_head");
  const StereoCalibration calibration = load_euroc_calibration(test::shared_dataset("euroc_v101_head") / "mav0");
  FrameProcessor processor(calibration, FrontendOptions::from_config(runtime::Config::empty()));
  const cv::Mat good(480, 752, CV_8UC1, cv::Scalar(100));
  const cv::Mat small(480, 640, CV_8UC1, cv::Scalar(100));
  try {
    processor.process(0, 4, good, small);
    ADD_FAILURE() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "stereo frame 4: right image is 640x480, the calibration expects 752x480");
  }
  try {
    processor.process(0, 5, small, good);
    ADD_FAILURE() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "stereo frame 5: left image is 640x480, the calibration expects 752x480");
  }
}

}  // namespace
}  // namespace heslam::frontend
