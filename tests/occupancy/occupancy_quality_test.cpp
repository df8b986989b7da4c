// The occupancy map's quality on the synthetic room with exact geometry, each stage on its own so that a
// low IoU can be pinned on one of them: the ground-truth depth the renderer knows (the fusion, the grid
// and the truth's convention alone), then the dense stereo of the rendered pair (SGBM's noise added),
// both at the ground-truth poses (no SLAM pose error). The full pipeline (poses from SLAM) is scored
// by heslam-occupancy-compare in docs/occupancy.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "components/core/occupancy/dense_stereo.hpp"
#include "components/core/occupancy/multiview_depth.hpp"
#include "components/core/occupancy/occupancy_grid.hpp"
#include "components/core/occupancy/occupancy_map.hpp"
#include "tools/synth/occupancy_truth.hpp"
#include "tools/synth/preset.hpp"
#include "tools/synth/sequence.hpp"

namespace heslam {
namespace {

enum class DepthSource { kTruth, kStereo };

struct Keyframe {
  Pose3 T_c0c;
  cv::Mat disparity;
};

struct Room {
  PinholeStereo camera;
  std::vector<Keyframe> keyframes;
  OccupancyGrid truth;
  OccupancyGrid seen;            // the part of the truth the keyframes see within max_depth_m
  double disparity_cpu_s = 0.0;  // SGBM's process CPU time over the keyframes (printed, never asserted)
};

// The seen truth: what the left camera sees within 5 m (the shipped stereo.max_depth_m when it was made),
// fixed whatever the matcher's settings so that no setting narrows the truth it is scored on.
constexpr double kSeenMaxDepthM = 5.0;

double cpu_s() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

double env_or(const char* name, double value) {
  const char* e = std::getenv(name);
  return e ? std::atof(e) : value;
}

// The rectified camera of a renderer's ideal pinhole pairs.
PinholeStereo pinhole_of(const synth::SequenceRenderer& renderer) {
  const synth::CameraSpec& spec = renderer.preset().camera;
  PinholeStereo camera;
  camera.fx_px = spec.fx_px;
  camera.fy_px = spec.fy_px;
  camera.cx_px = spec.cx_px;
  camera.cy_px = spec.cy_px;
  camera.baseline_m = spec.baseline_m;
  camera.width_px = spec.width_px;
  camera.height_px = spec.height_px;
  return camera;
}

// The pipeline's keyframes on the room are ~6 frames apart (103 of 600 frames): the multi-view
// refinement's neighbours are the frames kNeighbourSpacing, 2 kNeighbourSpacing, ... before the keyframe
// (after it near the start), at their true poses. D_MV_SPACING overrides it.
constexpr int kNeighbourSpacing = 6;

// The multi-view options of the tests (the shipped config/occupancy/multiview.yaml's: the core defaults with
// 3 neighbours), D_MV_* overriding them.
MultiViewDepthOptions multiview_options() {
  MultiViewDepthOptions m;
  m.neighbours = static_cast<int>(env_or("D_MV_N", 3));
  m.search_range_px = env_or("D_MV_RANGE", m.search_range_px);
  m.step_px = env_or("D_MV_STEP", m.step_px);
  m.max_candidates = static_cast<int>(env_or("D_MV_MAXC", m.max_candidates));
  m.patch_radius_px = static_cast<int>(env_or("D_MV_PATCH", m.patch_radius_px));
  m.prefilter_sigma_px = env_or("D_MV_PRE", m.prefilter_sigma_px);
  m.passes = static_cast<int>(env_or("D_MV_PASSES", m.passes));
  m.level = static_cast<int>(env_or("D_MV_LEVEL", m.level));
  m.pass_range_factor = env_or("D_MV_PASSF", m.pass_range_factor);
  m.base_radius_px = static_cast<int>(env_or("D_MV_BASE", m.base_radius_px));
  m.min_zncc = env_or("D_MV_ZNCC", m.min_zncc);
  m.min_baseline_ratio = env_or("D_MV_MINB", m.min_baseline_ratio);
  m.max_baseline_m = env_or("D_MV_MAXB", m.max_baseline_m);
  m.use_right = env_or("D_MV_RIGHT", m.use_right) != 0;
  m.keep_unrefined = env_or("D_MV_KEEP", m.keep_unrefined) != 0;
  return m;
}

// A keyframe's disparity refined against the left images of its neighbouring frames at true poses (see
// kNeighbourSpacing); CPU time of the refinement (and stats) added to *cpu_s_total.
cv::Mat multiview_disparity(synth::SequenceRenderer& renderer, const PinholeStereo& camera, int index,
                            const synth::SynthFrame& frame, const cv::Mat& disparity,
                            const MultiViewDepthOptions& options, double* cpu_s_total,
                            MultiViewDepthStats* stats = nullptr) {
  MultiViewDepth refiner(camera, options);
  const int spacing = static_cast<int>(env_or("D_MV_SPACING", kNeighbourSpacing));
  const int direction = index >= options.neighbours * spacing ? -1 : 1;
  for (int k = options.neighbours; k >= 1; --k) {  // the oldest first, as a process keeps them
    const int other = index + direction * k * spacing;
    if (other < 0 || other >= renderer.num_frames()) continue;
    refiner.add_view(renderer.render_frame(other).left, renderer.T_wc_left(other));
  }
  const double start = cpu_s();
  cv::Mat out = refiner.refine(disparity, frame.left, frame.right, renderer.T_wc_left(index), stats);
  if (cpu_s_total) *cpu_s_total += cpu_s() - start;
  return out;
}

// Every `stride`-th frame of the room as a keyframe at its true pose (world = the first left camera),
// with its disparity: the renderer's depth, or SGBM of the rendered ideal pinhole pair.
Room render_room(DepthSource source, int stride, const DenseStereoOptions& stereo_options, const GridBand& band,
                 double resolution_m, bool sensor_noise = true, const MultiViewDepthOptions& multiview = {}) {
  synth::RenderOptions render;
  render.apply_distortion = false;  // ideal pinhole pairs: rectified as the process sees them
  synth::Preset preset = synth::load_preset(synth::find_preset("room"));
  preset.photometry.noise = sensor_noise;
  synth::SequenceRenderer renderer(preset, render);
  Room room;
  room.camera = pinhole_of(renderer);
  const DenseStereo stereo(room.camera, stereo_options);
  const Pose3 T_c0w = renderer.T_wc_left(0).inverse();
  for (int index = 0; index < renderer.num_frames(); index += stride) {
    Keyframe keyframe{T_c0w * renderer.T_wc_left(index), {}};
    if (source == DepthSource::kTruth) {
      cv::Mat radiance, depth;
      renderer.render_radiance_left(index, radiance, &depth);
      keyframe.disparity = cv::Mat(depth.size(), CV_32F, cv::Scalar(-1.f));
      for (int v = 0; v < depth.rows; ++v) {
        for (int u = 0; u < depth.cols; ++u) {
          const float z = depth.at<float>(v, u);
          if (z > 0.f) keyframe.disparity.at<float>(v, u) = static_cast<float>(room.camera.bf() / z);
        }
      }
    } else {
      const synth::SynthFrame frame = renderer.render_frame(index);
      const double start = cpu_s();
      keyframe.disparity = stereo.disparity(frame.left, frame.right);
      room.disparity_cpu_s += cpu_s() - start;
      if (multiview.enabled()) {
        keyframe.disparity = multiview_disparity(renderer, room.camera, index, frame, keyframe.disparity, multiview,
                                                 &room.disparity_cpu_s);
      }
    }
    room.keyframes.push_back(std::move(keyframe));
  }
  room.truth = synth::occupancy_truth(renderer.scene(), renderer.T_wc_left(0), resolution_m, band);
  room.seen = synth::occupancy_truth_seen(renderer, stride, kSeenMaxDepthM, resolution_m, band);
  return room;
}

// The grid's agreement with the whole truth and with the seen truth.
std::pair<GridAgreement, GridAgreement> fuse_room(const Room& room, const DenseStereoOptions& stereo_options,
                                                  const OccupancyMapOptions& map_options, const std::string& label) {
  const DenseStereo stereo(room.camera, stereo_options);
  const bool use_normals = map_options.voxels.model == FusionModel::kTsdf;
  OccupancyMap map(map_options);
  std::uint64_t id = 0;
  double cloud_cpu_s = 0.0, fusion_cpu_s = 0.0;
  for (const Keyframe& keyframe : room.keyframes) {
    map.set_pose(id, keyframe.T_c0c);
    const double start = cpu_s();
    KeyframeCloud cloud{0, {}, stereo.sigma_per_m2(), {}};
    stereo.cloud_from_disparity(keyframe.disparity, cloud.points_c, use_normals ? &cloud.normals_c : nullptr);
    const double fusion_start = cpu_s();
    map.add_cloud(id, std::move(cloud));
    map.fuse_pending();
    cloud_cpu_s += fusion_start - start;
    fusion_cpu_s += cpu_s() - fusion_start;
    ++id;
  }
  const double n = static_cast<double>(room.keyframes.size());
  std::printf("%s: CPU per keyframe: disparity %.1f ms, cloud %.1f ms (%.0f points), fusion %.1f ms\n", label.c_str(),
              1e3 * room.disparity_cpu_s / n, 1e3 * cloud_cpu_s / n, static_cast<double>(map.cloud_points()) / n,
              1e3 * fusion_cpu_s / n);
  const OccupancyGrid grid = map.grid();
  if (std::getenv("D_DUMP")) {
    std::map<std::tuple<int, int, int>, char> fit_state;
    map.voxels().for_each_state([&](const VoxelIndex& v, VoxelMap::VoxelState st) {
      fit_state[{v.x, v.y, v.z}] = "UFON"[static_cast<int>(st)];
    });
    int shown = 0;
    for (const auto& [ij, state] : room.seen.cells()) {
      if (state != CellState::kOccupied || grid.at(ij.first, ij.second) != CellState::kFree) continue;
      if (++shown > 12) break;
      std::printf("cell %d %d:", ij.first, ij.second);
      const VoxelMap& vm = map.voxels();
      for (int k = -14; k <= 6; ++k) {
        const VoxelIndex v{ij.first, ij.second, k};
        if (!vm.observed(v)) continue;
        std::printf(" [%d %.3f w%.2f c%.0f %c]", k, vm.sdf(v), vm.weight(v), vm.crossed(v), fit_state[{v.x, v.y, v.z}]);
      }
      std::printf("\n");
    }
  }
  const GridAgreement a = compare(grid, room.truth);
  const GridAgreement b = compare(grid, room.seen);
  if (const char* dir = std::getenv("HESLAM_OCCUPANCY_DIAG_DIR")) {
    grid.write_map_server(std::string(dir) + "/" + label);
    room.truth.write_map_server(std::string(dir) + "/room_gt");
    room.seen.write_map_server(std::string(dir) + "/room_gt_seen");
  }
  std::printf(
      "%s, %zu keyframes at true poses: occupied IoU %.4f (%zu of %zu truth cells, %zu grid cells), "
      "truth-occupied free %zu, unknown %zu\n",
      label.c_str(), room.keyframes.size(), a.occupied_iou, a.both_occupied, a.truth_occupied, a.grid_occupied,
      a.free_in_truth_occupied, a.truth_occupied_unknown);
  std::printf("%s against the seen truth: occupied IoU %.4f (%zu of %zu), free %zu, unknown %zu\n", label.c_str(),
              b.occupied_iou, b.both_occupied, b.truth_occupied, b.free_in_truth_occupied, b.truth_occupied_unknown);
  std::printf(
      "%s against the seen truth: grid cells outside it at 1/2/3+ cells %zu/%zu/%zu, missed at 1/2/3+ %zu/%zu/%zu\n",
      label.c_str(), b.extra_at[0], b.extra_at[1], b.extra_at[2], b.missed_at[0], b.missed_at[1], b.missed_at[2]);
  std::fflush(stdout);
  return {a, b};
}

// 25 keyframes (every 24th frame of 600): enough views of every wall, and the test stays short.
constexpr int kStride = 24;

// The fusion, the grid and the truth alone: exact depth at exact poses finds the seen walls and box
// tops (seen-truth IoU 0.965, 2676 of 2773 cells, none outside the truth; 51 seen cells free where a
// box top or wall is only seen at grazing angles), where every 4th pixel found 0.79. The whole truth
// (IoU 0.70) also counts the table no keyframe looks at.
TEST(OccupancyQuality, RoomFromTrueDepthAtTruePoses) {
  const OccupancyMapOptions map_options;
  const Room room = render_room(DepthSource::kTruth, kStride, {}, map_options.band, map_options.voxels.resolution_m);
  const GridAgreement seen = fuse_room(room, {}, map_options, "room_truth_depth").second;
  EXPECT_GE(seen.occupied_iou, 0.95);
  EXPECT_EQ(seen.grid_occupied, seen.both_occupied) << "true depth marks no cell outside the truth";
  EXPECT_LE(seen.free_in_truth_occupied, 60u);
}

// SGBM's noise added (still at the true poses): seen-truth IoU 0.302 (2501 of 2773 seen cells found,
// but 7999 grid cells: a fringe of false hits 0.1-0.5 m in front of the walls), 228 seen wall cells
// free. This is the stage that misses the target (0.85); the floor here guards against it getting worse.
TEST(OccupancyQuality, RoomFromStereoAtTruePoses) {
  const OccupancyMapOptions map_options;
  const Room room = render_room(DepthSource::kStereo, kStride, {}, map_options.band, map_options.voxels.resolution_m);
  const GridAgreement seen = fuse_room(room, {}, map_options, "room_sgbm").second;
  EXPECT_GE(seen.occupied_iou, 0.28);
  EXPECT_GE(seen.both_occupied, 2400u);
}

// The TSDF settings measured best on this room (docs/occupancy.md, Quality).
OccupancyMapOptions tsdf_map_options() {
  OccupancyMapOptions m;
  m.voxels.model = FusionModel::kTsdf;
  m.voxels.hit_max_sigma_m = 0.15;
  m.voxels.tsdf_truncation_m = 0.2;
  m.voxels.tsdf_occupied_m = 0.04;
  m.voxels.tsdf_min_weight = 0.5;
  m.voxels.tsdf_zero_crossing = true;
  m.voxels.tsdf_fit_radius = 1;
  return m;
}

DenseStereoOptions tsdf_stereo_options() {
  DenseStereoOptions o;
  o.edge_radius_px = 2;
  o.disparity_sigma_px = 0.3;
  return o;
}

// The TSDF of tsdf.yaml (zero crossing, plane fit over 27 voxels, the points weighed as SGBM's) with exact
// depth: seen-truth IoU 0.844, 3 seen cells free (the log-odds hits: 0.965 and 51). Without the fit 0.741:
// far walls' points weigh (cell / sigma)^2 < the floor of 0.5, where the fit pools 27 voxels' weights.
TEST(OccupancyQuality, RoomTsdfFromTrueDepthAtTruePoses) {
  const OccupancyMapOptions m = tsdf_map_options();
  const DenseStereoOptions o = tsdf_stereo_options();
  const Room room = render_room(DepthSource::kTruth, kStride, o, m.band, m.voxels.resolution_m);
  const GridAgreement seen = fuse_room(room, o, m, "room_tsdf_truth_depth").second;
  EXPECT_GE(seen.occupied_iou, 0.83);
  EXPECT_LE(seen.free_in_truth_occupied, 12u);
}

// The TSDF of tsdf.yaml with SGBM (edge filter, sigma 0.3 px) at true poses: seen-truth IoU 0.492 where the
// log-odds hits give 0.302 and the TSDF without the plane fit 0.406: the fringe in front of and behind the
// walls averages out (3184 grid cells, 7999 with hits), far walls are found by the fit's pooled weight;
// 200 seen wall cells are free (263 without the fit). Not the target (0.85); a floor against getting worse.
TEST(OccupancyQuality, RoomTsdfFromStereoAtTruePoses) {
  const OccupancyMapOptions m = tsdf_map_options();
  const DenseStereoOptions o = tsdf_stereo_options();
  const Room room = render_room(DepthSource::kStereo, kStride, o, m.band, m.voxels.resolution_m);
  const GridAgreement seen = fuse_room(room, o, m, "room_tsdf_sgbm").second;
  EXPECT_GE(seen.occupied_iou, 0.47);
  EXPECT_LE(seen.grid_occupied, 3600u);
  EXPECT_LE(seen.free_in_truth_occupied, 230u);
}

// A tuning harness (disabled; --gtest_also_run_disabled_tests): the SGBM room fused with the settings
// of the environment (D_TSDF=1, D_SIGMA px, D_HITSIG m, D_EDGE_R px, D_TRUNC m, D_TOCC m, D_TMINW, ...;
// D_TRUTH=1: true depth; D_NOISE=0: the pair rendered without sensor noise; D_DUMP=1: the voxels of truth-occupied
// cells the grid calls free, with their states; D_ZERO=1: the TSDF's zero crossing; D_FIT: voxel.tsdf_fit_radius;
// D_BAND_MIN / D_BAND_MAX m: the grid's height band, the truth's with it).
TEST(OccupancyQuality, DISABLED_TuneFusion) {
  OccupancyMapOptions m;
  DenseStereoOptions o;
  if (env_or("D_BEST", 0)) {
    m = tsdf_map_options();
    o = tsdf_stereo_options();
  }
  o.uniqueness_ratio = static_cast<int>(env_or("D_UNIQ", o.uniqueness_ratio));
  o.disp12_max_diff = static_cast<int>(env_or("D_LR", o.disp12_max_diff));
  o.edge_radius_px = static_cast<int>(env_or("D_EDGE_R", o.edge_radius_px));
  o.edge_step_px = env_or("D_EDGE_STEP", o.edge_step_px);
  o.smooth_radius_px = static_cast<int>(env_or("D_SMOOTH", o.smooth_radius_px));
  o.disparity_sigma_px = env_or("D_SIGMA", o.disparity_sigma_px);
  o.refine_iterations = static_cast<int>(env_or("D_REFINE_IT", o.refine_iterations));
  o.refine_radius_px = static_cast<int>(env_or("D_REFINE_R", o.refine_radius_px));
  o.refine_max_change_px = env_or("D_REFINE_MAX", o.refine_max_change_px);
  o.refine_prefilter_sigma_px = env_or("D_PRE", o.refine_prefilter_sigma_px);
  o.max_depth_m = env_or("D_MAXD", o.max_depth_m);
  MultiViewDepthOptions mv;
  if (env_or("D_MV", 0)) mv = multiview_options();
  m.voxels.free_margin_m = env_or("D_MARGIN", m.voxels.free_margin_m);
  m.voxels.hit_max_sigma_m = env_or("D_HITSIG", m.voxels.hit_max_sigma_m);
  m.voxels.free_sigmas = env_or("D_FREESIG", m.voxels.free_sigmas);
  m.voxels.occupied_log_odds = static_cast<float>(env_or("D_OCC", m.voxels.occupied_log_odds));
  if (env_or("D_TSDF", 0)) m.voxels.model = FusionModel::kTsdf;
  m.voxels.tsdf_truncation_m = env_or("D_TRUNC", m.voxels.tsdf_truncation_m);
  m.voxels.tsdf_occupied_m = env_or("D_TOCC", m.voxels.tsdf_occupied_m);
  m.voxels.tsdf_min_weight = env_or("D_TMINW", m.voxels.tsdf_min_weight);
  m.voxels.tsdf_free_ratio = env_or("D_TFREE", m.voxels.tsdf_free_ratio);
  m.voxels.tsdf_zero_crossing = env_or("D_ZERO", m.voxels.tsdf_zero_crossing) != 0;
  m.band.min_m = env_or("D_BAND_MIN", m.band.min_m);
  m.band.max_m = env_or("D_BAND_MAX", m.band.max_m);
  m.voxels.tsdf_fit_radius = static_cast<int>(env_or("D_FIT", m.voxels.tsdf_fit_radius));
  const int stride = static_cast<int>(env_or("D_STRIDE", kStride));
  const Room room = render_room(env_or("D_TRUTH", 0) ? DepthSource::kTruth : DepthSource::kStereo, stride, o, m.band,
                                m.voxels.resolution_m, env_or("D_NOISE", 1) != 0, mv);
  fuse_room(room, o, m, "diag");
}

// A diagnostic (disabled): the pose error's share. D_KEYFRAMES=FILE is a room run's STEM.keyframes.txt
// (TUM, body frame, world = the body at the first keyframe); its keyframes' frames are rendered (ideal
// pinhole) and their SGBM depth fused with the settings of DISABLED_TuneFusion (D_BEST, D_ZERO, ...)
// once at the true poses and once at the SLAM poses, scored against the seen truth. D_MV=1: each keyframe's
// disparity refined against the previous keyframes (MultiViewDepth, D_MV_*) at the poses it is fused at.
TEST(OccupancyQuality, DISABLED_SlamPosesAgainstTruePoses) {
  const char* file = std::getenv("D_KEYFRAMES");
  if (!file) GTEST_SKIP() << "D_KEYFRAMES=STEM.keyframes.txt of a room run";
  OccupancyMapOptions m;
  DenseStereoOptions o;
  if (env_or("D_BEST", 0)) {
    m = tsdf_map_options();
    o = tsdf_stereo_options();
  }
  m.voxels.tsdf_zero_crossing = env_or("D_ZERO", m.voxels.tsdf_zero_crossing) != 0;
  m.voxels.tsdf_min_weight = env_or("D_TMINW", m.voxels.tsdf_min_weight);
  m.voxels.tsdf_fit_radius = static_cast<int>(env_or("D_FIT", m.voxels.tsdf_fit_radius));
  o.disparity_sigma_px = env_or("D_SIGMA", o.disparity_sigma_px);
  synth::RenderOptions render;
  render.apply_distortion = false;
  synth::SequenceRenderer renderer(synth::load_preset(synth::find_preset("room")), render);
  Room room = render_room(DepthSource::kTruth, kStride, o, m.band, m.voxels.resolution_m);
  room.keyframes.clear();  // the camera and the truths (seen: every kStride-th frame, as the other tests)
  const DenseStereo stereo(room.camera, o);
  MultiViewDepthOptions multiview;
  if (env_or("D_MV", 0)) multiview = multiview_options();
  MultiViewDepth refine_true(room.camera, multiview), refine_slam(room.camera, multiview);
  const Pose3 T_BS = renderer.T_BS_left();
  const Pose3 T_c0w = renderer.T_wc_left(0).inverse();
  std::vector<Keyframe> slam;
  std::FILE* in = std::fopen(file, "r");
  ASSERT_NE(in, nullptr) << file;
  char line[512];
  while (std::fgets(line, sizeof(line), in)) {
    double t, x, y, z, qx, qy, qz, qw;
    if (line[0] == '#' || std::sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %lf", &t, &x, &y, &z, &qx, &qy, &qz, &qw) != 8)
      continue;
    const int index =
        static_cast<int>(std::lround((t - renderer.stamp_ns(0) * 1e-9) * renderer.preset().camera.rate_hz));
    if (index < 0 || index >= renderer.num_frames()) continue;
    Pose3 T_wb = Pose3::Identity();
    T_wb.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    T_wb.translation() = Eigen::Vector3d(x, y, z);
    const synth::SynthFrame frame = renderer.render_frame(index);
    const cv::Mat disparity = stereo.disparity(frame.left, frame.right);
    const Pose3 T_true = T_c0w * renderer.T_wc_left(index);
    const Pose3 T_slam = T_BS.inverse() * T_wb * T_BS;  // world = the first keyframe's camera
    if (multiview.enabled()) {
      // Each keyframe refined against the previous keyframes, at the poses it is fused at (as the process).
      room.keyframes.push_back({T_true, refine_true.refine(disparity, frame.left, frame.right, T_true)});
      slam.push_back({T_slam, refine_slam.refine(disparity, frame.left, frame.right, T_slam)});
      refine_true.add_view(frame.left, T_true);
      refine_slam.add_view(frame.left, T_slam);
      continue;
    }
    room.keyframes.push_back({T_true, disparity});
    slam.push_back({T_slam, disparity});
  }
  std::fclose(in);
  ASSERT_FALSE(slam.empty());
  fuse_room(room, o, m, "true_poses");
  room.keyframes = slam;
  fuse_room(room, o, m, "slam_poses");
}

struct ErrorBin {
  long n = 0, valid = 0, e05 = 0, e1 = 0, e3 = 0, pos3 = 0;
  double sum = 0, sum2 = 0;
  double valid_ratio() const { return static_cast<double>(valid) / static_cast<double>(n); }
  double over(long count) const { return static_cast<double>(count) / static_cast<double>(valid); }
  double mean() const { return sum / static_cast<double>(valid); }
  double rms_below_1px() const { return std::sqrt(sum2 / static_cast<double>(valid - e1)); }
};

// The upper edges of the true-depth bins (m).
constexpr double kDepthBins[] = {1, 2, 3, 4, 5, 1e9};
constexpr int kNumDepthBins = 6;

struct DisparityErrors {
  ErrorBin bins[2][kNumDepthBins];  // [near a depth step][true depth bin]
  ErrorBin all_off_edges;
  double cpu_s_per_frame = 0.0;  // process CPU time of DenseStereo::disparity (printed, never asserted)
};

// A matcher's disparity against the renderer's (every 24th frame of the room, ideal pinhole pairs),
// binned by true depth and by whether a depth step of more than 1 px is within 3 px (an occlusion edge).
// supersample > 1: the pair is rendered at supersample x the resolution (the lens blur scaled with it) and
// area-averaged down, i.e. each pixel integrates its area as a sensor's does, where the renderer samples one
// point per pixel; noise false: no shot or read noise.
DisparityErrors disparity_errors(const DenseStereoOptions& options, const char* label, int supersample = 1,
                                 bool noise = true, const MultiViewDepthOptions& multiview = {}) {
  synth::RenderOptions render;
  render.apply_distortion = false;
  synth::Preset preset = synth::load_preset(synth::find_preset("room"));
  preset.photometry.noise = noise;
  synth::SequenceRenderer renderer(preset, render);
  synth::Preset fine_preset = preset;
  fine_preset.camera.width_px *= supersample;
  fine_preset.camera.height_px *= supersample;
  fine_preset.camera.fx_px *= supersample;
  fine_preset.camera.fy_px *= supersample;
  // Pixel u of the image is the mean of fine pixels s u + k (k < s), centred on u: fine c = s c + (s - 1) / 2.
  fine_preset.camera.cx_px = supersample * preset.camera.cx_px + 0.5 * (supersample - 1);
  fine_preset.camera.cy_px = supersample * preset.camera.cy_px + 0.5 * (supersample - 1);
  fine_preset.photometry.lens_blur_px *= supersample;
  synth::SequenceRenderer fine_renderer(fine_preset, render);
  const PinholeStereo camera = pinhole_of(renderer);
  const DenseStereo stereo(camera, options);
  DisparityErrors out;
  int frames = 0;
  for (int index = 0; index < renderer.num_frames(); index += 24) {
    cv::Mat radiance, depth;
    renderer.render_radiance_left(index, radiance, &depth);
    synth::SynthFrame frame = (supersample > 1 ? fine_renderer : renderer).render_frame(index);
    if (supersample > 1) {
      for (cv::Mat* image : {&frame.left, &frame.right}) {
        cv::resize(*image, *image, cv::Size(camera.width_px, camera.height_px), 0, 0, cv::INTER_AREA);
      }
    }
    const double start = cpu_s();
    cv::Mat d = stereo.disparity(frame.left, frame.right);
    out.cpu_s_per_frame += cpu_s() - start;
    if (multiview.enabled()) {
      MultiViewDepthStats stats;
      d = multiview_disparity(renderer, camera, index, frame, d, multiview, &out.cpu_s_per_frame, &stats);
      std::printf("%s frame %d: %zu views, %zu candidates, %zu of %zu pixels refined, mean change %.3f px\n", label,
                  index, stats.views_used, stats.candidates, stats.refined, stats.pixels, stats.mean_abs_change_px);
    }
    ++frames;
    for (int v = 3; v < depth.rows - 3; ++v) {
      for (int u = 64; u < depth.cols - 3; ++u) {
        const float z = depth.at<float>(v, u);
        if (!(z > 0.f)) continue;
        const double td = camera.bf() / z;
        bool edge = false;
        for (int dv = -3; dv <= 3 && !edge; ++dv)
          for (int du = -3; du <= 3; ++du) {
            const float z2 = depth.at<float>(v + dv, u + du);
            if (!(z2 > 0.f) || std::abs(camera.bf() / z2 - td) > 1.0) {
              edge = true;
              break;
            }
          }
        int b = 0;
        while (z > kDepthBins[b]) ++b;
        for (ErrorBin* bin : {&out.bins[edge][b], edge ? nullptr : &out.all_off_edges}) {
          if (!bin) continue;
          ++bin->n;
          const float sd = d.at<float>(v, u);
          if (!(sd > 0.f)) continue;
          ++bin->valid;
          const double err = sd - td;
          bin->sum += err;
          if (std::abs(err) < 1) bin->sum2 += err * err;
          if (std::abs(err) > 0.5) ++bin->e05;
          if (std::abs(err) > 1) ++bin->e1;
          if (std::abs(err) > 3) {
            ++bin->e3;
            if (err > 0) ++bin->pos3;
          }
        }
      }
    }
  }
  out.cpu_s_per_frame /= frames;
  const auto print = [label](const ErrorBin& x, const char* what) {
    std::printf(
        "%s disparity, %s: n %ld valid %.3f |err|>0.5 %.3f >1 %.3f >3 %.3f (closer %.3f) mean %.3f rms(<1) %.3f\n",
        label, what, x.n, x.valid_ratio(), x.over(x.e05), x.over(x.e1), x.over(x.e3), x.over(x.pos3), x.mean(),
        x.rms_below_1px());
  };
  for (int e = 0; e < 2; ++e)
    for (int b = 0; b < kNumDepthBins; ++b) {
      if (!out.bins[e][b].valid) continue;
      char what[64];
      std::snprintf(what, sizeof(what), "edge %d, true depth < %g m", e, kDepthBins[b]);
      print(out.bins[e][b], what);
    }
  print(out.all_off_edges, "off edges, all depths");
  std::printf("%s disparity: CPU %.1f ms per 752x480 pair\n", label, 1e3 * out.cpu_s_per_frame);
  std::fflush(stdout);
  return out;
}

// Where the SGBM depth goes wrong (docs/occupancy.md, Quality): off edges 10-15% of the pixels are more
// than 0.5 px off, 4-7% more than 1 px, the rms of the rest ~0.3 px and biased ~-0.12 px (too far):
// at 4 m, 0.3 px is 0.1 m, two cells; on edges a third is more than 1 px off.
TEST(OccupancyQuality, RoomSgbmDisparityErrorAgainstTruth) {
  const DisparityErrors sgbm = disparity_errors(DenseStereoOptions{}, "SGBM");
  for (int b = 0; b < kNumDepthBins; ++b) {
    const ErrorBin& x = sgbm.bins[0][b];
    if (!x.valid) continue;
    EXPECT_LT(x.over(x.e1), 0.08) << kDepthBins[b];
    EXPECT_LT(x.rms_below_1px(), 0.35) << kDepthBins[b];
  }
}

DenseStereoOptions refined_stereo_options() {
  DenseStereoOptions o;
  o.refine_iterations = static_cast<int>(env_or("D_REFINE_IT", 4));
  o.refine_radius_px = static_cast<int>(env_or("D_REFINE_R", o.refine_radius_px));
  o.refine_max_change_px = env_or("D_REFINE_MAX", o.refine_max_change_px);
  o.refine_prefilter_sigma_px = env_or("D_PRE", o.refine_prefilter_sigma_px);
  return o;
}

// A diagnostic harness (disabled): the errors of SGBM and of the refinement with the pair rendered
// D_SS x supersampled (pixel area integrated), D_NOISE=0: without sensor noise.
TEST(OccupancyQuality, DISABLED_DisparityErrorRendering) {
  const int ss = static_cast<int>(env_or("D_SS", 1));
  const bool noise = env_or("D_NOISE", 1) != 0;
  disparity_errors(DenseStereoOptions{}, "SGBM", ss, noise);
  disparity_errors(refined_stereo_options(), "refined", ss, noise);
}

// A diagnostic harness (disabled): the errors of SGBM and of SGBM refined across views (D_MV_* options;
// D_NOISE=0: the pairs rendered without sensor noise).
TEST(OccupancyQuality, DISABLED_MultiViewDisparityError) {
  const bool noise = env_or("D_NOISE", 1) != 0;
  disparity_errors(DenseStereoOptions{}, "SGBM", 1, noise);
  disparity_errors(DenseStereoOptions{}, "multi-view", 1, noise, multiview_options());
}

// The texture the matcher has to work with: per pixel, the standard deviation of the horizontal grey
// gradient (central difference, DN/px) over its 11x11 window; the share of pixels below 1, 2 and 4 DN/px
// and the median. A disparity's sub-pixel error is about the noise over this times the window's side.
void print_texture_statistics(const std::vector<cv::Mat>& images, const char* label) {
  std::vector<float> all;
  for (const cv::Mat& image : images) {
    cv::Mat grey, gradient, mean, mean2;
    image.convertTo(grey, CV_32F);
    cv::Sobel(grey, gradient, CV_32F, 1, 0, 1, 0.5);
    cv::boxFilter(gradient, mean, CV_32F, cv::Size(11, 11));
    cv::boxFilter(gradient.mul(gradient), mean2, CV_32F, cv::Size(11, 11));
    for (int v = 8; v < grey.rows - 8; v += 2)
      for (int u = 72; u < grey.cols - 8; u += 2) {
        const float m = mean.at<float>(v, u);
        all.push_back(std::sqrt(std::max(0.f, mean2.at<float>(v, u) - m * m)));
      }
  }
  std::sort(all.begin(), all.end());
  const auto below = [&](float x) {
    return static_cast<double>(std::lower_bound(all.begin(), all.end(), x) - all.begin()) / all.size();
  };
  std::printf("%s: %zu images, gradient std in 11x11: < 1 DN/px %.3f, < 2 %.3f, < 4 %.3f, median %.2f\n", label,
              images.size(), below(1.f), below(2.f), below(4.f), all[all.size() / 2]);
}

// A diagnostic (disabled): the texture statistics of the room's pairs (with and without sensor noise)
// and of the EuRoC MH01 clip's left images (HESLAM_EUROC_DIR, default /work/shared/data/euroc_mh01_handheld).
TEST(OccupancyQuality, DISABLED_TextureAgainstEuroc) {
  for (const bool noise : {true, false}) {
    synth::RenderOptions render;
    render.apply_distortion = false;
    synth::Preset preset = synth::load_preset(synth::find_preset("room"));
    preset.photometry.noise = noise;
    synth::SequenceRenderer renderer(preset, render);
    std::vector<cv::Mat> images;
    for (int index = 0; index < renderer.num_frames(); index += 24) images.push_back(renderer.render_frame(index).left);
    print_texture_statistics(images, noise ? "room" : "room without noise");
  }
  const char* dir = std::getenv("HESLAM_EUROC_DIR");
  const std::string cam0 = std::string(dir ? dir : "/work/shared/data/euroc_mh01_handheld") + "/mav0/cam0/data";
  std::vector<cv::String> files;
  cv::glob(cam0 + "/*.png", files);
  std::vector<cv::Mat> images;
  for (std::size_t i = 0; i < files.size(); i += 8) images.push_back(cv::imread(files[i], cv::IMREAD_GRAYSCALE));
  if (images.empty()) GTEST_SKIP() << "no EuRoC images in " << cam0;
  print_texture_statistics(images, "EuRoC MH01 cam0");
}

// SGBM refined by the 1-D Lucas-Kanade (DenseStereoOptions::refine_iterations, 4 steps, 11x11 window,
// pair smoothed by 1 px): off edges its mean error is -0.005 px where SGBM's is -0.10 (too far) and 1.1%
// of its pixels are more than 1 px off (SGBM 5%), but its rms is no better (0.29 px against 0.30) and it
// keeps 63% of the pixels (SGBM 95%): on the room the error is the sensor noise over the texture's weak
// gradient, not SGBM's sub-pixel fit (docs/occupancy.md, Quality).
TEST(OccupancyQuality, RoomRefinedDisparityErrorAgainstTruth) {
  const DisparityErrors refined = disparity_errors(refined_stereo_options(), "refined");
  const ErrorBin& x = refined.all_off_edges;
  EXPECT_LT(std::abs(x.mean()), 0.02) << "unbiased";
  EXPECT_LT(x.over(x.e1), 0.02);
  EXPECT_LT(x.rms_below_1px(), 0.31);
  EXPECT_GT(x.valid_ratio(), 0.55);
}

// Multi-view refinement (MultiViewDepth, the shipped options) at true poses, neighbours 6, 12 and 18 frames
// earlier (0.24-0.72 m, as the pipeline's keyframes): the refined pixels (the others dropped here) off
// edges are unbiased (mean -0.001 px, SGBM -0.10) with 0.17 px rms (SGBM 0.30), 0.8% more than 1 px off
// (SGBM 5%), 77% of the pixels kept. The same input refined twice is the same image (no thread-order effect).
TEST(OccupancyQuality, RoomMultiViewDisparityErrorAgainstTruth) {
  MultiViewDepthOptions options = multiview_options();
  options.keep_unrefined = false;
  const DisparityErrors refined = disparity_errors(DenseStereoOptions{}, "multi-view", 1, true, options);
  const ErrorBin& x = refined.all_off_edges;
  EXPECT_LT(std::abs(x.mean()), 0.02) << "unbiased";
  EXPECT_LT(x.over(x.e1), 0.015);
  EXPECT_LT(x.rms_below_1px(), 0.2) << "SGBM: 0.30 px";
  EXPECT_GT(x.valid_ratio(), 0.7);

  synth::RenderOptions render;
  render.apply_distortion = false;
  synth::SequenceRenderer renderer(synth::load_preset(synth::find_preset("room")), render);
  const PinholeStereo camera = pinhole_of(renderer);
  const synth::SynthFrame frame = renderer.render_frame(240);
  const cv::Mat sgbm = DenseStereo(camera, {}).disparity(frame.left, frame.right);
  const cv::Mat first = multiview_disparity(renderer, camera, 240, frame, sgbm, options, nullptr);
  const cv::Mat second = multiview_disparity(renderer, camera, 240, frame, sgbm, options, nullptr);
  EXPECT_EQ(cv::norm(first, second, cv::NORM_INF), 0.0);
  EXPECT_NE(cv::norm(first, sgbm, cv::NORM_INF), 0.0);
}

// The TSDF (tsdf.yaml) with the multi-view refined disparity (config/occupancy/multiview.yaml) at true poses,
// 25 keyframes: seen-truth IoU 0.512 where SGBM alone gives 0.492 (3300 grid cells, 3184), 192 seen wall
// cells free (200). Not the target (0.85); a floor against getting worse.
TEST(OccupancyQuality, RoomTsdfFromMultiViewStereoAtTruePoses) {
  const OccupancyMapOptions m = tsdf_map_options();
  const DenseStereoOptions o = tsdf_stereo_options();
  const Room room =
      render_room(DepthSource::kStereo, kStride, o, m.band, m.voxels.resolution_m, true, multiview_options());
  const GridAgreement seen = fuse_room(room, o, m, "room_tsdf_multiview").second;
  EXPECT_GE(seen.occupied_iou, 0.49);
  EXPECT_LE(seen.grid_occupied, 3550u);
  EXPECT_LE(seen.free_in_truth_occupied, 220u);
}

}  // namespace
}  // namespace heslam
