// Command-line reading of heslam-viewer's options, and its help text.
#include "tools/viewer/viewer_options.hpp"

#include <stdexcept>

namespace heslam::viewer {
namespace {

// Bounds that reject typos but allow any sensible use.
constexpr double kMaxRateHz = 120.0;
constexpr double kMaxSnapshotPeriodS = 86400.0;
constexpr int kMaxRecentKeyframes = 100000;
constexpr int kMaxCovisibilityWeight = 100000;

double to_double(const std::string& flag, const std::string& text, double low, double high) {
  try {
    std::size_t used = 0;
    const double value = std::stod(text, &used);
    if (used == text.size() && value >= low && value <= high) return value;
  } catch (const std::exception&) {
  }
  throw std::runtime_error(flag + ": expected a number in [" + std::to_string(low) + ", " + std::to_string(high) +
                           "], got '" + text + "'");
}

int to_int(const std::string& flag, const std::string& text, int low, int high) {
  const double value = to_double(flag, text, low, high);
  if (value != static_cast<int>(value)) throw std::runtime_error(flag + ": expected an integer, got '" + text + "'");
  return static_cast<int>(value);
}

}  // namespace

ViewerOptions ViewerOptions::parse(const std::vector<std::string>& rest) {
  ViewerOptions o;
  for (std::size_t i = 0; i < rest.size(); ++i) {
    const std::string& flag = rest[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= rest.size()) throw std::runtime_error(flag + ": missing value");
      return rest[++i];
    };
    if (flag == "--headless") {
      o.headless = true;
    } else if (flag == "--snapshot-every") {
      o.snapshot_every_s = to_double(flag, value(), 0.0, kMaxSnapshotPeriodS);
    } else if (flag == "--out") {
      o.out_dir = value();
    } else if (flag == "--gt") {
      o.gt_file = value();
    } else if (flag == "--gt-extrinsic") {
      o.gt_extrinsic = value();
    } else if (flag == "--record") {
      o.record_file = value();
    } else if (flag == "--rate") {
      o.draw_rate_hz = to_double(flag, value(), 0.1, kMaxRateHz);
    } else if (flag == "--recent-keyframes") {
      o.recent_keyframes = to_int(flag, value(), 0, kMaxRecentKeyframes);
    } else if (flag == "--covisibility-min-weight") {
      o.covisibility_min_weight = to_int(flag, value(), 0, kMaxCovisibilityWeight);
    } else if (flag == "--he-mode") {
      const std::string& mode = value();
      try {
        o.he_mode = parse_he_mode(mode);
      } catch (const std::exception&) {
        throw std::runtime_error("--he-mode: expected none, global, clipped, clahe or adaptive, got '" + mode + "'");
      }
    } else {
      throw std::runtime_error("unknown argument '" + flag + "' (see heslam-viewer --help)");
    }
  }
  if (o.headless && o.out_dir.empty()) throw std::runtime_error("--headless needs --out DIR (where the snapshots go)");
  if (o.snapshot_every_s > 0.0 && o.out_dir.empty()) throw std::runtime_error("--snapshot-every needs --out DIR");
  if (!o.gt_extrinsic.empty() && o.gt_file.empty()) throw std::runtime_error("--gt-extrinsic needs --gt FILE");
  return o;
}

std::string ViewerOptions::usage() {
  return "usage: heslam-viewer [options] [common options]\n"
         "Shows the map being built (3D) and the current frame (2D) of a running pipeline; joins at any time.\n"
         "  --headless                  no window: render off-screen, write PNG snapshots to --out\n"
         "                              (also when $DISPLAY is unset)\n"
         "  --out DIR                   snapshots (map_*.png top view, frame_*.png, map_final.png,\n"
         "                              frame_final.png) and viewer_stats.txt at the end\n"
         "  --snapshot-every S          also write snapshots every S seconds (default 0: only at the end)\n"
         "  --record FILE.mp4           record the 2D view (VideoWriter mp4v; PNG sequence if no codec)\n"
         "  --gt FILE                   ground truth drawn over the map (TUM, EuRoC csv, KITTI), aligned SE(3)\n"
         "  --gt-extrinsic sensor.yaml  EuRoC T_BS: body ground truth -> camera poses\n"
         "  --rate HZ                   drawing rate (default 20); faster frames are dropped and counted\n"
         "  --recent-keyframes N        points of the N newest keyframes are 'recent' (default 5)\n"
         "  --covisibility-min-weight W covisibility edges with >= W shared points (default 100)\n"
         "  --he-mode MODE              equalization shown: none global clipped clahe adaptive (default clipped)\n"
         "Keys (3D window or 2D window):\n"
         "  p  map points       u  culled points      k  keyframe frustums\n"
         "  c  covisibility     t  spanning tree      g  ground truth     j  trajectory\n"
         "  f  follow camera / free camera (mouse)    s  write a snapshot now (needs --out)\n"
         "  q  close the viewer (the pipeline goes on)\n"
         "Colours: points black = map, red = recent, magenta = merged by a loop closure, grey = culled;\n"
         "keyframes blue, current camera green, covisibility green lines, spanning tree orange,\n"
         "ground truth purple. 2D view: raw left | rectified + equalized left with features\n"
         "(green = map point match, blue = stereo only) on keyframes, local map points projected at the\n"
         "tracked pose on other frames (green crosses).\n";
}

}  // namespace heslam::viewer
