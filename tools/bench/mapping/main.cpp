// heslam-bench-mapping: runs the LocalMapper over a synthetic room sequence (the frontend emulated
// with ground truth: perfect data association, jittered keyframe poses, noisy keypoints) and prints
// per-stage times (median / p90), map growth, keyframe accuracy before / after mapping and the cost
// of writing the map file.
// `heslam-bench-mapping --help` lists the flags.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "components/core/mapping/local_mapper.hpp"
#include "runtime/flags.hpp"
#include "tests/mapping/synthetic_world.hpp"
#include "tools/bench/bench_util.hpp"

namespace {

using heslam::bench::percentile;

constexpr double kYawStepRad = 0.06;  // ~3.4 deg between keyframes: ORB-SLAM2-like keyframe density
constexpr int kSaveEvery = 10;        // keyframes between map snapshots

struct Args {
  int keyframes = 120;
  int points = 6000;
  double pose_jitter_m = 0.01;
  std::filesystem::path map_file = std::filesystem::temp_directory_path() / "heslam-bench-mapping.map";
  heslam::LocalMapperOptions options;
};

Args parse(int argc, char** argv) {
  Args args;
  bool help = false;
  heslam::runtime::Flags flags("heslam-bench-mapping [options]");
  flags.integer("--keyframes", "N", &args.keyframes, "keyframes of the synthetic room (120; >= 2)")
      .integer("--points", "N", &args.points, "map points of the room (6000; >= 100)")
      .number("--pose-jitter-m", "M", &args.pose_jitter_m, "keyframe pose jitter in metres (0.01)")
      .path("--map-file", "PATH", &args.map_file, "where the map snapshots are written")
      .custom("--disable", "triangulation|fusion|ba|kf-culling", "a stage to leave out (repeatable)",
              [&args](const std::string& value) {
                if (value == "triangulation") {
                  args.options.enable_triangulation = false;
                } else if (value == "fusion") {
                  args.options.enable_fusion = false;
                } else if (value == "ba") {
                  args.options.enable_bundle_adjustment = false;
                } else if (value == "kf-culling") {
                  args.options.enable_keyframe_culling = false;
                } else {
                  heslam::runtime::throw_bad_flag_value("--disable", "triangulation, fusion, ba or kf-culling", value);
                }
              })
      .toggle("--help", &help, "this help")
      .alias("-h");
  flags.parse(argc, argv);
  if (help) {
    std::cout << flags.usage();
    std::exit(0);
  }
  if (args.keyframes < 2 || args.points < 100) throw std::runtime_error("need --keyframes >= 2 and --points >= 100");
  return args;
}

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

int run(int argc, char** argv) {
  using namespace heslam;
  const Args args = parse(argc, argv);
  const test::SyntheticWorld world = test::make_room(args.points, 2026, 4.0, 3.0);
  test::ViewOptions view_options;
  view_options.clutter = 100;
  LocalMapper mapper(world.camera, args.options);
  test::FrontendEmulator frontend(world);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);

  std::vector<double> cpu, insertion, culling, triangulation, fusion, bundle, kf_culling, total, features, tracked;
  std::vector<double> save_ms, serialize_ms, save_cpu_ms;
  double frontend_error = 0.0;
  std::map<KeyframeId, Pose3> truth;
  MapFileWriteStats last_save;
  int triangulated = 0;
  int culled_kfs = 0;
  int fused = 0;
  for (int k = 0; k < args.keyframes; ++k) {
    const KeyframeId id = static_cast<KeyframeId>(k + 1);
    const Pose3 T_wc = test::circle_pose(k, kYawStepRad, 1.0);
    truth[id] = T_wc;
    const auto view = test::make_view(world, id, T_wc, 7000 + static_cast<unsigned>(k), view_options);
    Pose3 estimate = T_wc;
    if (k > 0) estimate.translation() += args.pose_jitter_m * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    frontend_error += (estimate.translation() - T_wc.translation()).norm();
    auto [kf, points] = frontend.keyframe(mapper.map(), view, estimate);
    features.push_back(static_cast<double>(kf.features.size()));
    tracked.push_back(static_cast<double>(
        std::count_if(kf.point_ids.begin(), kf.point_ids.end(), [](PointId p) { return p != kNoId; })));
    const double cpu_start = thread_cpu_ms();
    const MapChanges changes = mapper.process_keyframe(std::move(kf), std::move(points));
    cpu.push_back(thread_cpu_ms() - cpu_start);
    insertion.push_back(changes.timings.insertion_ms);
    culling.push_back(changes.timings.point_culling_ms);
    triangulation.push_back(changes.timings.triangulation_ms);
    fusion.push_back(changes.timings.fusion_ms);
    bundle.push_back(changes.timings.bundle_adjustment_ms);
    kf_culling.push_back(changes.timings.keyframe_culling_ms);
    total.push_back(changes.timings.total_ms);
    triangulated += changes.counts.triangulated_points;
    culled_kfs += changes.counts.culled_keyframes;
    fused += changes.counts.fused_points;
    if ((k + 1) % kSaveEvery == 0) {
      const double save_start = thread_cpu_ms();
      last_save = mapper.save(args.map_file);
      save_cpu_ms.push_back(thread_cpu_ms() - save_start);
      save_ms.push_back(last_save.serialize_ms + last_save.write_ms);
      serialize_ms.push_back(last_save.serialize_ms);
    }
  }
  double mapper_error = 0.0;
  int live = 0;
  for (const auto& [id, kf] : mapper.map().keyframes) {
    if (kf.culled) continue;
    mapper_error += (kf.T_wc.translation() - truth.at(id).translation()).norm();
    if (std::getenv("HESLAM_BENCH_VERBOSE") != nullptr) {
      std::printf("  kf %3llu parent %3llu error %.2f mm, %zu covisible\n", static_cast<unsigned long long>(id),
                  static_cast<unsigned long long>(kf.parent),
                  1000.0 * (kf.T_wc.translation() - truth.at(id).translation()).norm(), kf.covisible.size());
    }
    ++live;
  }
  const MapFileWriteStats synced = mapper.save(args.map_file, true);

  std::printf("synthetic room: %d keyframes, %d world points, median %.0f keypoints / %.0f tracked per keyframe\n",
              args.keyframes, args.points, percentile(features, 0.5), percentile(tracked, 0.5));
  std::printf("per-keyframe stage times (ms):\n");
  const auto line = [](const char* name, const std::vector<double>& v) {
    std::printf("  %-18s median %8.2f   p90 %8.2f   max %8.2f\n", name, percentile(v, 0.5), percentile(v, 0.9),
                percentile(v, 1.0));
  };
  line("insertion", insertion);
  line("point culling", culling);
  line("triangulation", triangulation);
  line("fusion", fusion);
  line("local BA", bundle);
  line("keyframe culling", kf_culling);
  line("total", total);
  line("total (thread CPU)", cpu);  // what the wall time would be on an idle core
  std::printf("map: %zu live keyframes of %d (%d culled), %zu points, %d triangulated, %d fused\n",
              static_cast<std::size_t>(live), args.keyframes, culled_kfs, mapper.map().points.size(), triangulated,
              fused);
  std::printf("keyframe position error: frontend %.2f mm mean, after mapping %.2f mm mean\n",
              1000.0 * frontend_error / args.keyframes, 1000.0 * mapper_error / live);
  std::printf("map file %s: %.2f MB at the end (%.1f kB per keyframe)\n", args.map_file.c_str(),
              static_cast<double>(last_save.bytes) / 1e6, static_cast<double>(last_save.bytes) / 1e3 / args.keyframes);
  std::printf(
      "  snapshot every %d keyframes: median %.2f ms wall (serialize %.2f ms), %.2f ms thread CPU; "
      "last %.2f ms wall; final one with fsync %.2f ms wall\n",
      kSaveEvery, percentile(save_ms, 0.5), percentile(serialize_ms, 0.5), percentile(save_cpu_ms, 0.5),
      save_ms.empty() ? 0.0 : save_ms.back(), synced.serialize_ms + synced.write_ms);
  std::filesystem::remove(args.map_file);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return heslam::bench::bench_main("heslam-bench-mapping", argc, argv, run); }
