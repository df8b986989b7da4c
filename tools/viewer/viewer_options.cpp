// Command-line reading of heslam-viewer's options, and its help text.
#include "tools/viewer/viewer_options.hpp"

#include <stdexcept>

#include "runtime/flags.hpp"

namespace heslam::viewer {
namespace {

// Bounds that reject typos but allow any sensible use.
constexpr double kMaxRateHz = 120.0;
constexpr double kMaxSnapshotPeriodS = 86400.0;
constexpr int kMaxRecentKeyframes = 100000;
constexpr int kMaxCovisibilityWeight = 100000;

// The options, declared once for the parser and the usage.
runtime::Flags viewer_flags(ViewerOptions& o) {
  runtime::Flags flags(
      "heslam-viewer [options] [common options]",
      "Shows the map being built (3D) and the current frame (2D) of a running pipeline; joins at any time.");
  flags
      .toggle("--headless", &o.headless,
              "no window: render off-screen, write PNG snapshots to --out\n(also when $DISPLAY is unset)")
      .path("--out", "DIR", &o.out_dir,
            "snapshots (map_*.png top view, frame_*.png, map_final.png,\n"
            "frame_final.png) and viewer_stats.txt at the end")
      .number("--snapshot-every", "S", &o.snapshot_every_s, 0.0, kMaxSnapshotPeriodS,
              "also write snapshots every S seconds (default 0: only at the end)")
      .path("--record", "FILE.mp4", &o.record_file, "record the 2D view (VideoWriter mp4v; PNG sequence if no codec)")
      .path("--gt", "FILE", &o.gt_file, "ground truth drawn over the map (TUM, EuRoC csv, KITTI), aligned SE(3)")
      .path("--gt-extrinsic", "sensor.yaml", &o.gt_extrinsic, "EuRoC T_BS: body ground truth -> camera poses")
      .number("--rate", "HZ", &o.draw_rate_hz, 0.1, kMaxRateHz,
              "drawing rate (default 20); faster frames are dropped and counted")
      .integer("--recent-keyframes", "N", &o.recent_keyframes, 0, kMaxRecentKeyframes,
               "points of the N newest keyframes are 'recent' (default 5)")
      .integer("--covisibility-min-weight", "W", &o.covisibility_min_weight, 0, kMaxCovisibilityWeight,
               "covisibility edges with >= W shared points (default 100)")
      .custom("--fit", "WHAT",
              "top view fitted to the 'trajectory' (default: estimate, ground truth,\n"
              "current camera) or the whole 'map' (points, keyframes)",
              [&o](const std::string& what) {
                if (what == "trajectory") {
                  o.fit = TopViewFit::kTrajectory;
                } else if (what == "map") {
                  o.fit = TopViewFit::kMap;
                } else {
                  runtime::throw_bad_flag_value("--fit", "trajectory or map", what);
                }
              })
      .custom("--he-mode", "MODE", "equalization shown: none global clipped clahe adaptive (default clipped)",
              [&o](const std::string& mode) {
                try {
                  o.he_mode = parse_he_mode(mode);
                } catch (const std::exception&) {
                  runtime::throw_bad_flag_value("--he-mode", "none, global, clipped, clahe or adaptive", mode);
                }
              })
      .note("Keys (3D window or 2D window):")
      .note("p  map points       u  culled points      k  keyframe frustums")
      .note("c  covisibility     t  spanning tree      g  ground truth     j  trajectory")
      .note("o  occupancy grid (heslam-occupancy's map/occupancy_grid, under the top view)")
      .note("f  follow camera / free camera (mouse)    s  write a snapshot now (needs --out)")
      .note("q  close the viewer (the pipeline goes on)")
      .note(
          "Colours: points black = map, red = recent, magenta = merged by a loop closure, grey = culled;\n"
          "keyframes blue, current camera green, covisibility green lines, spanning tree orange,\n"
          "trajectory dark blue over the ground truth (wide, light orange). Top view: grid of round\n"
          "steps (1, 2, 5 x 10^k m), scale bar of one step bottom left, x / z arrows bottom right; under it the\n"
          "occupancy grid (occupied cells dark slate, free cells pale green). 2D view: raw left | "
          "rectified + equalized left with features\n"
          "(green = map point match, blue = stereo only) on keyframes, local map points projected at the\n"
          "tracked pose on other frames (green crosses).");
  return flags;
}

}  // namespace

ViewerOptions ViewerOptions::parse(const std::vector<std::string>& rest) {
  ViewerOptions o;
  viewer_flags(o).parse(rest);
  if (o.headless && o.out_dir.empty()) throw std::runtime_error("--headless needs --out DIR (where the snapshots go)");
  if (o.snapshot_every_s > 0.0 && o.out_dir.empty()) throw std::runtime_error("--snapshot-every needs --out DIR");
  if (!o.gt_extrinsic.empty() && o.gt_file.empty()) throw std::runtime_error("--gt-extrinsic needs --gt FILE");
  return o;
}

std::string ViewerOptions::usage() {
  ViewerOptions unused;
  return viewer_flags(unused).usage();
}

}  // namespace heslam::viewer
