// heslam-bench-stereo-compare: where does stereo lose accuracy when the cameras are exposed apart?
// Runs the per-frame feature pipeline (HE -> ORB -> stereo) on MH01 pairs twice, exposed equally and
// with the left x L / right x R, and compares the disparity of the same left keypoint (same octave,
// within 0.25 px) in both runs: count, bias and spread, split by whether the right patch touches a
// saturated pixel. Second, every stereo keypoint of the exposed-apart run against a reference: the
// disparity a ZNCC block match finds at the same left pixel in the equally exposed pair (unclipped,
// so it sees the texture the clip edge hides), split by StereoFeatures::near_clip. Its bias, in
// pixels and relative to the disparity, is what a depth (and so the trajectory's scale) inherits.
//
// With --motion: instead, whether the gain run's keypoints move between consecutive frames as the
// ground truth says (feature_motion.hpp), with the run's depths or, --reference-depth, reference ones.
//
// usage: heslam-bench-stereo-compare DATASET L,R [--step N] [--he-stereo shared|matched|separate]
//        [--reference L,R] [--settings FILE] [--motion [--reference-depth]]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "runtime/flags.hpp"
#include "tools/bench/bench_util.hpp"
#include "tools/bench/frontend_offline/euroc_sequence.hpp"
#include "tools/bench/stereo_compare/feature_motion.hpp"
#include "tools/bench/stereo_compare/zncc_reference.hpp"
#include "tools/photometric/photometric_variant.hpp"

namespace {

struct Group {
  std::vector<double> diff_px;
  void add(double d) { diff_px.push_back(d); }
  void print(const char* name) const {
    if (diff_px.empty()) {
      std::printf("  %-14s n 0\n", name);
      return;
    }
    std::vector<double> v = diff_px;
    std::sort(v.begin(), v.end());
    double sum = 0, sum2 = 0;
    int over_half = 0, over_one = 0;
    for (double d : v) {
      sum += d;
      sum2 += d * d;
      over_half += std::abs(d) > 0.5 ? 1 : 0;
      over_one += std::abs(d) > 1.0 ? 1 : 0;
    }
    std::vector<double> a;
    for (double d : v) a.push_back(std::abs(d));
    std::sort(a.begin(), a.end());
    const double n = static_cast<double>(v.size());
    std::printf(
        "  %-14s n %6zu  mean %+.3f  median %+.3f  median|d| %.3f  p90|d| %.3f  rms %.3f  >0.5px %.1f%%  >1px %.1f%%\n",
        name, v.size(), sum / n, v[v.size() / 2], a[a.size() / 2], a[a.size() * 9 / 10], std::sqrt(sum2 / n),
        100.0 * over_half / n, 100.0 * over_one / n);
  }
};

// Relative to the disparity too: a relative bias b scales the depths by about 1 / (1 + b).
struct ReferenceGroup {
  std::vector<double> diff_px, relative;
  void add(double diff, double reference_px) {
    diff_px.push_back(diff);
    relative.push_back(diff / reference_px);
  }
  static void print_one(const char* name, std::vector<double> v, double unit, const char* unit_name) {
    if (v.empty()) {
      std::printf("  %-22s n 0\n", name);
      return;
    }
    std::sort(v.begin(), v.end());
    double sum = 0;
    for (double d : v) sum += d;
    const auto at = [&](double q) { return unit * v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))]; };
    std::printf("  %-22s n %6zu  mean %+.4f  median %+.4f  p25 %+.4f  p75 %+.4f %s\n", name, v.size(),
                unit * sum / static_cast<double>(v.size()), at(0.5), at(0.25), at(0.75), unit_name);
  }
  void print(const char* name) const {
    print_one(name, diff_px, 1.0, "px");
    print_one("  relative", relative, 100.0, "%");
  }
};

heslam::photometric::StereoGain parse(const std::string& s) { return heslam::photometric::parse_stereo_gain(s); }

int run(int argc, char** argv) {
  std::vector<std::string> positional;
  heslam::photometric::StereoGain reference;
  int step = 4;
  heslam::StereoFeaturePipelineOptions options;
  options.parallel = false;
  bool motion = false;
  bool reference_depth = false;
  bool help = false;
  heslam::runtime::Flags flags("heslam-bench-stereo-compare DATASET L,R [options]",
                               "  DATASET an EuRoC folder; L,R the gains of the pair exposed apart");
  flags.integer("--step", "N", &step, 1, std::numeric_limits<int>::max(), "every Nth frame (4)")
      .custom("--he-stereo", "M", "shared, matched or separate equalization of the pair",
              [&options](const std::string& value) { options.he.stereo = heslam::parse_stereo_photometry(value); })
      .custom("--reference", "L,R", "the gains of the reference pair (default: equal exposure)",
              [&reference](const std::string& value) { reference = parse(value); })
      .custom("--settings", "FILE", "the pipeline's settings (replaces the options given before it)",
              [&options](const std::string& value) {
                options = heslam::StereoFeaturePipelineOptions::load(value);
                options.parallel = false;
              })
      .toggle("--motion", &motion, "whether keypoints move between frames as the ground truth says")
      .toggle("--reference-depth", &reference_depth, "--motion: with the reference pair's depth")
      .toggle("--help", &help, "this help")
      .alias("-h")
      .positional("DATASET L,R", "", [&positional](const std::string& arg) {
        if (positional.size() == 2) throw std::runtime_error("unexpected argument '" + arg + "' (see --help)");
        positional.push_back(arg);
      });
  flags.parse(argc, argv);
  if (help) {
    std::fputs(flags.usage().c_str(), stdout);
    return 0;
  }
  if (positional.size() != 2) throw std::runtime_error("expected DATASET L,R\n" + flags.usage());
  const auto sequence = heslam::bench::load_euroc_sequence(positional[0]);
  const auto gain = parse(positional[1]);
  if (motion) {
    heslam::bench::FeatureMotionOptions motion_options;
    motion_options.pipeline = options;
    motion_options.reference_depth = reference_depth;
    heslam::bench::print_feature_motion(sequence, gain, motion_options);
    return 0;
  }
  if (reference_depth) throw std::runtime_error("--reference-depth: only with --motion");
  const heslam::StereoRectifier rectifier(heslam::load_euroc_calibration(sequence.mav0_dir));
  heslam::StereoFeaturePipeline pipeline_ref(rectifier.camera(), options);
  heslam::StereoFeaturePipeline pipeline_gain(rectifier.camera(), options);
  Group all, saturated, clear;
  ReferenceGroup reference_near_clip, reference_clear;
  long stereo_ref = 0, stereo_gain = 0, features_gain = 0, common_keypoints = 0, lost = 0, gained = 0;
  for (std::size_t k = 0; k < sequence.frames.size(); k += static_cast<std::size_t>(step)) {
    const cv::Mat left = cv::imread(sequence.frames[k].left_png.string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat right = cv::imread(sequence.frames[k].right_png.string(), cv::IMREAD_GRAYSCALE);
    cv::Mat l_ref = left.clone(), r_ref = right.clone(), l_gain = left.clone(), r_gain = right.clone();
    heslam::photometric::apply_gain(l_ref, reference.left);
    heslam::photometric::apply_gain(r_ref, reference.right);
    heslam::photometric::apply_gain(l_gain, gain.left);
    heslam::photometric::apply_gain(r_gain, gain.right);
    cv::Mat lr, rr, lg, rg;
    rectifier.rectify(l_ref, r_ref, lr, rr);
    rectifier.rectify(l_gain, r_gain, lg, rg);
    const heslam::StereoFeatures a = pipeline_ref.process(lr, rr);
    const heslam::StereoFeatures b = pipeline_gain.process(lg, rg);
    std::map<std::pair<int, int>, std::vector<std::size_t>> grid;
    for (std::size_t i = 0; i < a.size(); ++i) {
      grid[{static_cast<int>(a.keypoints[i].u_px), static_cast<int>(a.keypoints[i].v_px)}].push_back(i);
      stereo_ref += a.has_stereo(i) ? 1 : 0;
    }
    features_gain += static_cast<long>(b.size());
    for (std::size_t i = 0; i < b.size(); ++i) {
      if (!b.has_stereo(i)) continue;
      const auto& kb = b.keypoints[i];
      const float scale = b.pyramid.scale[static_cast<std::size_t>(kb.octave)];
      const int half = std::max(options.stereo.sad_half_window_px,
                                static_cast<int>(std::lround(options.stereo.sad_half_window_px * scale)));
      const double disparity = kb.u_px - b.u_right_px[i];
      const auto reference = heslam::bench::zncc_reference_disparity(lr, rr, kb.u_px, kb.v_px, half, disparity);
      if (!reference || std::abs(disparity - *reference) > heslam::bench::kMaxReferenceDiffPx) continue;
      (b.stereo_near_clip(i) ? reference_near_clip : reference_clear).add(disparity - *reference, *reference);
    }
    for (std::size_t i = 0; i < b.size(); ++i) {
      stereo_gain += b.has_stereo(i) ? 1 : 0;
      const auto& kb = b.keypoints[i];
      long match = -1;
      for (int du = -1; du <= 1 && match < 0; ++du) {
        for (int dv = -1; dv <= 1 && match < 0; ++dv) {
          const auto it = grid.find({static_cast<int>(kb.u_px) + du, static_cast<int>(kb.v_px) + dv});
          if (it == grid.end()) continue;
          for (std::size_t j : it->second) {
            const auto& ka = a.keypoints[j];
            if (ka.octave == kb.octave && std::abs(ka.u_px - kb.u_px) < 0.25f && std::abs(ka.v_px - kb.v_px) < 0.25f) {
              match = static_cast<long>(j);
              break;
            }
          }
        }
      }
      if (match < 0) continue;
      ++common_keypoints;
      const auto j = static_cast<std::size_t>(match);
      if (a.has_stereo(j) && !b.has_stereo(i)) ++lost;
      if (!a.has_stereo(j) && b.has_stereo(i)) ++gained;
      if (!a.has_stereo(j) || !b.has_stereo(i)) continue;
      const double d = static_cast<double>((kb.u_px - b.u_right_px[i]) - (a.keypoints[j].u_px - a.u_right_px[j]));
      all.add(d);
      // Does the right patch (window 5 on the level, plus the search) touch a saturated raw pixel?
      const float scale = b.pyramid.scale[static_cast<std::size_t>(kb.octave)];
      const int r = static_cast<int>(std::ceil(6 * scale));
      const int u0 = static_cast<int>(std::lround(b.u_right_px[i])), v0 = static_cast<int>(std::lround(kb.v_px));
      bool sat = false;
      for (int v = std::max(0, v0 - r); v <= std::min(rg.rows - 1, v0 + r) && !sat; ++v) {
        for (int u = std::max(0, u0 - r); u <= std::min(rg.cols - 1, u0 + r); ++u) {
          if (rg.at<std::uint8_t>(v, u) >= 250) {
            sat = true;
            break;
          }
        }
      }
      (sat ? saturated : clear).add(d);
    }
  }
  std::printf(
      "gain %s vs reference %s: stereo points ref %ld, gain %ld of %ld features; common keypoints %ld "
      "(stereo lost %ld, gained %ld)\n",
      gain.describe().c_str(), reference.describe().c_str(), stereo_ref, stereo_gain, features_gain, common_keypoints,
      lost, gained);
  std::printf("disparity(gain) - disparity(ref), px at level 0, common keypoints with stereo in both:\n");
  all.print("all");
  clear.print("right clear");
  saturated.print("right sat.");
  std::printf(
      "disparity(gain) - ZNCC reference at the same left pixel of the reference pair, every stereo keypoint "
      "of the gain run (|difference| <= %.0f px):\n",
      heslam::bench::kMaxReferenceDiffPx);
  reference_clear.print("not near a clip edge");
  reference_near_clip.print("near a clip edge");
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return heslam::bench::bench_main("heslam-bench-stereo-compare", argc, argv, run); }
