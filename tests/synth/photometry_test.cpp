// Each photometric event of room_exposure changes the images as configured inside its time range and
// leaves them untouched (same bytes) outside it; a stereo_gain event exposes the two cameras apart.
#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "synth_test_util.hpp"
#include "tools/synth/sequence.hpp"

namespace heslam::synth {
namespace {

struct Stats {
  double mean = 0, stddev = 0;
};

Stats stats(const cv::Mat& m) {
  cv::Scalar mean, stddev;
  cv::meanStdDev(m, mean, stddev);
  return {mean[0], stddev[0]};
}

class SynthEvents : public ::testing::Test {
 protected:
  void SetUp() override {
    preset_ = test::repo_preset("room_exposure");
    // Noise-free, so the ratios are exactly the configured ones up to clipping and rounding.
    preset_.photometry.noise = false;
    // No vignetting either: it shades the haze's airlight too and would add contrast of its own.
    preset_.photometry.vignetting = 0.0;
    on_ = std::make_unique<SequenceRenderer>(preset_, RenderOptions{.seed = 2});
    off_ = std::make_unique<SequenceRenderer>(preset_, RenderOptions{.seed = 2, .events = false});
  }

  // The frame at time t with events and without (same pose, same noise seed).
  std::pair<cv::Mat, cv::Mat> with_and_without(double t_s) {
    const int index = static_cast<int>(std::lround(t_s * preset_.camera.rate_hz));
    return {on_->render_frame(index).left, off_->render_frame(index).left};
  }

  const ExposureEvent& event(EventKind kind) const {
    for (const auto& e : preset_.events)
      if (e.kind == kind) return e;
    throw std::runtime_error("preset room_exposure lacks an event");
  }

  Preset preset_;
  std::unique_ptr<SequenceRenderer> on_, off_;
};

TEST_F(SynthEvents, PresetHasAllFourKinds) {
  EXPECT_EQ(preset_.events.size(), 4u);
  for (EventKind k : {EventKind::kOverexposure, EventKind::kDarkness, EventKind::kHaze, EventKind::kDrift})
    EXPECT_NO_THROW(event(k));
}

TEST_F(SynthEvents, OverexposureBrightensAndSaturates) {
  const ExposureEvent& e = event(EventKind::kOverexposure);
  const auto [on, off] = with_and_without(0.5 * (e.start_s + e.end_s));
  const double ratio = stats(on).mean / stats(off).mean;
  EXPECT_GT(ratio, 2.0);
  EXPECT_LE(ratio, e.strength * 1.02);  // clipping can only take brightness away
  EXPECT_GT(cv::countNonZero(on == 255), on.total() / 5) << "a lamp blows out much of the image";
}

TEST_F(SynthEvents, DarknessScalesMeanByStrength) {
  const ExposureEvent& e = event(EventKind::kDarkness);
  const auto [on, off] = with_and_without(0.5 * (e.start_s + e.end_s));
  EXPECT_NEAR(stats(on).mean / stats(off).mean, e.strength, 0.01);
}

TEST_F(SynthEvents, HazeLowersContrastByItsFraction) {
  const ExposureEvent& e = event(EventKind::kHaze);
  const auto [on, off] = with_and_without(0.5 * (e.start_s + e.end_s));
  // Contrast (std) scales by 1 - fraction (rounding to 8 bits adds a little).
  EXPECT_NEAR(stats(on).stddev / stats(off).stddev, 1.0 - e.strength, 0.02);
}

TEST_F(SynthEvents, DriftPeaksMidRange) {
  const ExposureEvent& e = event(EventKind::kDrift);
  const double mid = 0.5 * (e.start_s + e.end_s);
  const auto [on, off] = with_and_without(mid);
  const double ratio = stats(on).mean / stats(off).mean;
  EXPECT_GT(ratio, 1.6);
  EXPECT_LE(ratio, e.strength * 1.02);
  const auto [q_on, q_off] = with_and_without(e.start_s + 0.25 * (e.end_s - e.start_s));
  const double quarter = stats(q_on).mean / stats(q_off).mean;
  EXPECT_GT(quarter, 1.2);
  EXPECT_LT(quarter, ratio) << "the swell is still rising at a quarter of its range";
}

TEST_F(SynthEvents, OutsideEveryRangeImagesAreUntouched) {
  for (const auto& e : preset_.events) {
    for (double t : {e.start_s - 0.2, e.end_s + 0.2}) {
      const auto [on, off] = with_and_without(t);
      EXPECT_EQ(cv::countNonZero(on != off), 0) << to_string(e.kind) << " at t=" << t;
    }
  }
}

// stereo_gain: the left camera x0.5, the right x2 (clipped), ramped in over 0.1 s; both cameras
// untouched outside the event. Noise-free, so the ratios are the configured gains up to clipping.
TEST(SynthStereoGain, ExposesTheTwoCamerasWithTheirOwnGain) {
  Preset preset = test::repo_preset("room");
  preset.photometry.noise = false;
  ExposureEvent event;
  event.kind = EventKind::kStereoGain;
  event.start_s = 0.5;
  event.end_s = 1.5;
  event.ramp_s = 0.1;
  event.left = 0.5;
  event.right = 2.0;
  preset.events = {event};
  SequenceRenderer on(preset, RenderOptions{.seed = 2, .frames = 40});
  SequenceRenderer off(preset, RenderOptions{.seed = 2, .frames = 40, .events = false});

  const SynthFrame inside = on.render_frame(20);  // t = 1.0 s
  const SynthFrame reference = off.render_frame(20);
  EXPECT_DOUBLE_EQ(inside.photometry.left_gain, 0.5);
  EXPECT_DOUBLE_EQ(inside.photometry.right_gain, 2.0);
  EXPECT_DOUBLE_EQ(inside.photometry.gain, 1.0) << "a stereo gain is not a gain of both cameras";
  EXPECT_NEAR(stats(inside.left).mean / stats(reference.left).mean, 0.5, 0.01);
  const double right_ratio = stats(inside.right).mean / stats(reference.right).mean;
  EXPECT_GT(right_ratio, 1.5);
  EXPECT_LE(right_ratio, 2.0 * 1.01);  // clipping can only take brightness away
  EXPECT_GT(cv::countNonZero(inside.right == 255), cv::countNonZero(reference.right == 255) + 1000)
      << "the brighter camera clips";

  for (const int index : {5, 35}) {  // t = 0.25 s and 1.75 s: outside the event
    const SynthFrame a = on.render_frame(index);
    const SynthFrame b = off.render_frame(index);
    EXPECT_EQ(cv::countNonZero(a.left != b.left), 0) << "frame " << index;
    EXPECT_EQ(cv::countNonZero(a.right != b.right), 0) << "frame " << index;
  }
}

}  // namespace
}  // namespace heslam::synth
