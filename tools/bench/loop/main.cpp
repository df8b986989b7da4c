// heslam-bench-loop: what closing a loop costs as the map grows. For each size N it builds
// a drifted synthetic loop of N stereo keyframes (tests/loop/loop_world.hpp scaled up: the test
// world's keyframe spacing and point density on a longer circle, so every point is seen by ~20
// consecutive keyframes; covisibility and spanning tree as the mapper keeps them) and prints median /
// p90 of each step of the loop closer (BoW detection, SE(3) RANSAC, essential graph, pose graph, whole
// correction, global BA) and of the mapper applying the correction. Reports numbers; asserts nothing.
// `heslam-bench-loop --help` lists the flags.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "components/core/loop/bow_loop_detector.hpp"
#include "components/core/loop/essential_graph.hpp"
#include "components/core/loop/global_bundle_adjustment.hpp"
#include "components/core/loop/loop_correction_builder.hpp"
#include "components/core/loop/pose_graph.hpp"
#include "components/core/loop/se3_ransac.hpp"
#include "components/core/mapping/correction_application.hpp"
#include "components/core/mapping/local_mapper.hpp"
#include "components/core/place/image_descriptors.hpp"
#include "components/core/place/vocabulary_setting.hpp"
#include "runtime/flags.hpp"
#include "tests/loop/loop_world.hpp"
#include "tools/bench/bench_util.hpp"
#include "tools/bench/frontend_offline/euroc_sequence.hpp"

namespace {

using namespace heslam;

// The test loop world's geometry (36 keyframes on a 2 m circle, 2500 points on a 6 m ring), kept
// per keyframe and per metre of wall when the circle grows.
constexpr int kRevisitKeyframes = 4;                           // the last ones revisit the first
constexpr double kKeyframeSpacingM = 2.0 * M_PI * 2.0 / 36.0;  // 0.35 m
constexpr double kWallDistanceM = 4.0;
constexpr double kPointsPerWallMetre = 2500.0 / (2.0 * M_PI * 6.0);  // ~460 points in view
// Odometry drift injected: this much heading error accumulated over the whole loop (0.05 rad ~ 3 deg)
// plus the world's translation bias per keyframe (~0.7 % of the path).
constexpr double kLoopYawDriftRad = 0.05;
// The loop pair's RANSAC problem: this many matches (the loop closer sees 40-400), this share wrong.
constexpr std::size_t kRansacMatches = 300;
constexpr double kRansacOutlierFraction = 0.3;

struct Args {
  std::vector<int> keyframes{100, 1000, 5000};
  int repeats = 3;            // global BA dominates: ~16 s a run at 1,000 keyframes
  int queries = 20;           // BoW detection: the last Q keyframes are queried in order
  int ba_max_points = 40000;  // global BA: beyond this, every k-th point only (the others culled)
  std::string vocabulary;     // empty: the build's default vocabulary
  std::string dataset = "../shared/data/euroc_mh01_handheld";  // descriptors for the world's points
  std::string poses_out;  // non-empty: the corrected poses of each size written to PREFIX<N>.txt
  bool global_ba = true;
};

Args parse(int argc, char** argv) {
  Args args;
  bool help = false;
  runtime::Flags flags("heslam-bench-loop [options]");
  flags
      .integer_list("--keyframes", "N,N,...", &args.keyframes, 2 * kRevisitKeyframes + 10, 1000000,
                    "the loop sizes (100,1000,5000)")
      .integer("--repeats", "R", &args.repeats, 1, std::numeric_limits<int>::max(), "runs per size (3)")
      .integer("--queries", "Q", &args.queries, 1, std::numeric_limits<int>::max(),
               "BoW detection: the last Q keyframes are queried (20)")
      .integer("--ba-max-points", "P", &args.ba_max_points, 100, std::numeric_limits<int>::max(),
               "global BA: beyond this, every k-th point only (40000)")
      .text("--vocabulary", "FILE", &args.vocabulary, "the vocabulary (default: the build's)")
      .text("--dataset", "DIR|none", &args.dataset, "descriptors for the world's points (MH01)")
      .text("--poses-out", "PREFIX", &args.poses_out,
            "write the corrected poses (LoopCorrectionBuilder) of size N to PREFIX<N>.txt and print a digest of "
            "the map after apply_loop_correction, to compare builds")
      .toggle("--no-global-ba", &args.global_ba, "skip the global BA", false)
      .toggle("--help", &help, "this help")
      .alias("-h");
  flags.parse(argc, argv);
  if (help) {
    std::cout << flags.usage();
    std::exit(0);
  }
  for (const int n : args.keyframes) {
    if (n < 2 * kRevisitKeyframes + 10) throw std::runtime_error("--keyframes: each size must be >= 18");
  }
  if (args.repeats < 1 || args.queries < 1 || args.ba_max_points < 100) {
    throw std::runtime_error("need --repeats >= 1, --queries >= 1, --ba-max-points >= 100");
  }
  return args;
}

// Wall and CPU time of the timed sections (the machine is shared: CPU is what an idle core would
// take). Everything timed here is single-threaded, so the process CPU clock is this work's.
class Timings {
 public:
  void start() {
    wall_start_ = std::chrono::steady_clock::now();
    cpu_start_ = std::clock();
  }
  void stop() {
    const auto wall = std::chrono::steady_clock::now() - wall_start_;
    wall_ms_.push_back(std::chrono::duration<double, std::milli>(wall).count());
    cpu_ms_.push_back(1e3 * static_cast<double>(std::clock() - cpu_start_) / CLOCKS_PER_SEC);
  }
  // One line: what, the map's size, median / p90 wall, median CPU, then the measurement's own sizes.
  void report(const char* what, const Map& map, const std::string& detail) const {
    std::printf("%-30s %5zu kf %7zu pts | median %9.2f ms  p90 %9.2f ms  cpu %9.2f ms | n=%zu %s\n", what,
                map.keyframes.size(), map.points.size(), bench::percentile(wall_ms_, 0.5),
                bench::percentile(wall_ms_, 0.9), bench::percentile(cpu_ms_, 0.5), wall_ms_.size(), detail.c_str());
    std::fflush(stdout);
  }

 private:
  std::chrono::steady_clock::time_point wall_start_;
  std::clock_t cpu_start_ = 0;
  std::vector<double> wall_ms_;
  std::vector<double> cpu_ms_;
};

// `run()` timed `repeats` times (the input it works on is the same each time).
template <typename Run>
Timings repeated(int repeats, Run run) {
  Timings timings;
  for (int r = 0; r < repeats; ++r) {
    timings.start();
    run();
    timings.stop();
  }
  return timings;
}

std::string format(const char* pattern, auto... values) {
  char line[512];
  std::snprintf(line, sizeof line, pattern, values...);
  return line;
}

std::vector<Descriptor> real_descriptors(const std::string& dataset) {
  if (dataset == "none") return {};
  const auto sequence = bench::load_euroc_sequence(dataset);
  ImageDescriptorExtractor extractor;
  std::vector<Descriptor> pool;
  for (const auto& frame : sequence.frames) {
    const auto image = extractor.extract(cv::imread(frame.left_png.string(), cv::IMREAD_GRAYSCALE));
    pool.insert(pool.end(), image.begin(), image.end());
  }
  std::printf("descriptors: %zu ORB descriptors of %zu images of %s, cycled over the world's points\n", pool.size(),
              sequence.frames.size(), dataset.c_str());
  return pool;
}

test::LoopWorld make_world(int keyframes, const std::vector<Descriptor>& pool) {
  test::LoopWorldOptions options;
  options.keyframes = keyframes;
  options.keyframes_per_turn = keyframes - kRevisitKeyframes;
  options.camera_radius_m = kKeyframeSpacingM * options.keyframes_per_turn / (2.0 * M_PI);
  options.ring_radius_m = options.camera_radius_m + kWallDistanceM;
  options.points = static_cast<int>(kPointsPerWallMetre * 2.0 * M_PI * options.ring_radius_m);
  options.yaw_bias_rad = kLoopYawDriftRad / keyframes;
  options.descriptor_pool = pool;
  return test::make_loop_world(options);
}

std::size_t covisibility_edges(const Map& map) {
  std::size_t ends = 0;
  for (const auto& [id, kf] : map.keyframes) ends += kf.covisible.size();
  return ends / 2;
}

double rotation_deg(const Pose3& T) { return Eigen::AngleAxisd(T.linear()).angle() * 180.0 / M_PI; }

// The loop pair's stereo matches, the loop side of a share of them replaced by another match's (wrong
// matches with realistic image positions and depths).
std::vector<Se3Correspondence> ransac_problem(const test::LoopWorld& w, KeyframeId matched, KeyframeId loop,
                                              int& outliers) {
  std::vector<Se3Correspondence> matches = test::correspondences_between(w, matched, loop);
  if (matches.size() > kRansacMatches) matches.resize(kRansacMatches);
  const std::vector<Se3Correspondence> original = matches;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<std::size_t> other(0, matches.size() - 1);
  outliers = 0;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (unit(rng) >= kRansacOutlierFraction) continue;
    std::size_t j = other(rng);
    while (j == i) j = other(rng);
    matches[i].p_b = original[j].p_b;
    matches[i].uv_b_px = original[j].uv_b_px;
    matches[i].sigma2_b = original[j].sigma2_b;
    ++outliers;
  }
  return matches;
}

// FNV-1a over the bytes of what a correction changes (poses; point positions, normals, distance
// ranges, descriptors, reference keyframes): equal digests, equal maps.
std::uint64_t digest(const Map& map) {
  std::uint64_t hash = 1469598103934665603ull;
  const auto add = [&hash](const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
  };
  for (const auto& [id, kf] : map.keyframes) add(kf.T_wc.matrix().data(), sizeof(double) * 16);
  for (const auto& [id, point] : map.points) {
    add(&id, sizeof id);
    add(point.p_w.data(), sizeof(double) * 3);
    add(point.normal.data(), sizeof(double) * 3);
    add(&point.min_distance_m, sizeof point.min_distance_m);
    add(&point.max_distance_m, sizeof point.max_distance_m);
    add(point.descriptor.data(), point.descriptor.size());
    add(&point.reference_kf, sizeof point.reference_kf);
  }
  return hash;
}

// One line per keyframe: id, translation, quaternion (x y z w), 17 significant digits.
void write_poses(const std::string& path, const LoopCorrection& correction) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) throw std::runtime_error("--poses-out: cannot write " + path);
  for (const auto& [id, T_wc] : correction.corrected_T_wc) {
    const Eigen::Quaterniond q(T_wc.rotation());
    const Eigen::Vector3d& t = T_wc.translation();
    std::fprintf(file, "%llu %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", static_cast<unsigned long long>(id), t.x(),
                 t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  }
  if (std::fclose(file) != 0) throw std::runtime_error("--poses-out: cannot write " + path);
  std::printf("corrected poses written to %s\n", path.c_str());
}

void bench_size(const Args& args, int keyframes, const std::vector<Descriptor>& pool,
                const std::shared_ptr<const Vocabulary>& vocabulary) {
  const auto build_start = std::chrono::steady_clock::now();
  const test::LoopWorld w = make_world(keyframes, pool);
  const Map& map = w.map;
  const PinholeStereo& camera = w.world.camera;
  const KeyframeId loop_kf = test::loop_kf_id(keyframes - 1);
  const KeyframeId matched_kf = test::loop_kf_id(kRevisitKeyframes - 1);
  std::size_t observations = 0;
  for (const auto& [id, point] : map.points) observations += point.observations.size();
  const Pose3& drifted = map.keyframes.at(loop_kf).T_wc;
  const Pose3& truth = w.true_T_wc.at(loop_kf);
  std::printf(
      "\n== %d keyframes (loop %.0f m): %zu points, %.1f observations per point, %zu covisibility edges; "
      "drift at the loop keyframe %.2f m / %.2f deg; built in %.1f s\n",
      keyframes, kKeyframeSpacingM * keyframes, map.points.size(),
      static_cast<double>(observations) / static_cast<double>(map.points.size()), covisibility_edges(map),
      (drifted.translation() - truth.translation()).norm(), rotation_deg(drifted.inverse() * truth),
      std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count());

  // BoW detection: the database is filled with all N keyframes (the first call), then the last
  // queries keyframes are queried in keyframe order (the consistency check keeps state across them).
  if (vocabulary) {
    BowLoopDetector detector(vocabulary, BowLoopDetectorOptions{});
    Timings fill;
    fill.start();
    detector.detect(map, test::loop_kf_id(0));
    fill.stop();
    fill.report("KeyframeDatabase fill (all N)", map, format("%zu keyframes added", detector.database().size()));
    Timings detect;
    Timings match;
    int with_candidates = 0;
    int matches = 0;
    const int queries = std::min(args.queries, keyframes - 1);
    for (int k = keyframes - queries; k < keyframes; ++k) {
      detect.start();
      const LoopCandidates candidates = detector.detect(map, test::loop_kf_id(k));
      detect.stop();
      if (candidates.keyframes.empty()) continue;
      ++with_candidates;
      match.start();
      matches = static_cast<int>(detector.match(map, test::loop_kf_id(k), candidates.keyframes.front()).size());
      match.stop();
    }
    detect.report("BowLoopDetector::detect", map,
                  format("per query keyframe; %d of %d queries returned a verified-consistent candidate",
                         with_candidates, queries));
    if (with_candidates > 0) {
      match.report("BowLoopDetector::match", map, format("query vs best candidate, %d BoW matches (last)", matches));
    }
  }

  // SE(3) RANSAC on the loop pair.
  int outliers = 0;
  const std::vector<Se3Correspondence> matches = ransac_problem(w, matched_kf, loop_kf, outliers);
  std::optional<Se3RansacResult> verified;
  const Timings ransac = repeated(args.repeats, [&] { verified = Se3Ransac().compute(camera, matches); });
  if (!verified) throw std::runtime_error("Se3Ransac found no transform for the loop pair");
  const Pose3 true_T_ab = w.true_T_wc.at(matched_kf).inverse() * w.true_T_wc.at(loop_kf);
  const Pose3 error = verified->T_ab.inverse() * true_T_ab;
  ransac.report(
      "Se3Ransac", map,
      format("%zu matches (%d wrong): %d inliers, %d hypotheses, error %.1f mm / %.3f deg", matches.size(), outliers,
             verified->inliers, verified->iterations, 1000.0 * error.translation().norm(), rotation_deg(error)));
  const LoopCandidate loop{loop_kf, matched_kf, verified->T_ab, {}};

  // The essential graph and its optimization on their own, as LoopCorrectionBuilder sets them up
  // (loop group moved rigidly, the loop - matched link as the one new loop edge, matched kf fixed).
  std::map<KeyframeId, Pose3> corrected_group;
  const Pose3 correction_w = map.keyframes.at(matched_kf).T_wc * loop.T_matched_loop * drifted.inverse();
  corrected_group[loop_kf] = correction_w * drifted;
  for (const auto& [neighbour, weight] : map.keyframes.at(loop_kf).covisible) {
    corrected_group[neighbour] = correction_w * map.keyframes.at(neighbour).T_wc;
  }
  EssentialGraph graph;
  const Timings essential = repeated(args.repeats, [&] {
    graph = EssentialGraphBuilder().compute(map, corrected_group, {{loop_kf, matched_kf, 0, true}}, {});
  });
  essential.report("EssentialGraphBuilder", map,
                   format("%zu edges: %d spanning tree, %d covisibility >= 100, %d loop", graph.edges.size(),
                          graph.spanning_tree_edges, graph.covisibility_edges, graph.new_loop_edges));
  std::map<KeyframeId, Pose3> initial_T_wc;
  for (const auto& [id, kf] : map.keyframes) {
    const auto corrected = corrected_group.find(id);
    initial_T_wc[id] = corrected != corrected_group.end() ? corrected->second : kf.T_wc;
  }
  PoseGraphResult optimized;
  const Timings pose_graph =
      repeated(args.repeats, [&] { optimized = PoseGraph().compute(initial_T_wc, graph.edges, {matched_kf}); });
  pose_graph.report(
      "PoseGraph", map,
      format("%d vertices, %d edges, %d iterations, cost %.3g -> %.3g", optimized.stats.vertices, optimized.stats.edges,
             optimized.stats.iterations, optimized.stats.initial_cost, optimized.stats.final_cost));

  // The whole correction.
  LoopCorrectionOutput output;
  const Timings builder =
      repeated(args.repeats, [&] { output = LoopCorrectionBuilder().compute(map, camera, loop, {}); });
  if (!output.error.empty()) throw std::runtime_error("LoopCorrectionBuilder: " + output.error);
  const LoopCorrectionStats& stats = output.stats;
  const EssentialGraph& edges = stats.graph_edges;
  double corrected_error_m = 0.0;
  for (const auto& [id, T_wc] : output.correction.corrected_T_wc) {
    corrected_error_m = std::max(corrected_error_m, (T_wc.translation() - w.true_T_wc.at(id).translation()).norm());
  }
  builder.report(
      "LoopCorrectionBuilder::compute", map,
      format("groups %d / %d kf, %d merges, %d graph edges, fusion %.1f ms, pose graph %.1f ms "
             "(%d it); worst kf error after %.2f m",
             stats.loop_group_keyframes, stats.matched_group_keyframes, stats.point_merges,
             edges.new_loop_edges + edges.spanning_tree_edges + edges.previous_loop_edges + edges.covisibility_edges,
             stats.fusion_ms, stats.pose_graph.time_ms, stats.pose_graph.iterations, corrected_error_m));
  LoopCorrection correction = output.correction;
  correction.id = 1;
  if (!args.poses_out.empty()) write_poses(args.poses_out + std::to_string(keyframes) + ".txt", correction);

  // The mapper's side: applying the correction to its own N-keyframe map (a fresh copy each time).
  Timings apply;
  MapChanges applied;
  Map applied_map;
  for (int r = 0; r < args.repeats; ++r) {
    Map copy = map;
    applied = MapChanges{};
    apply.start();
    apply_loop_correction(copy, correction, {}, applied);
    apply.stop();
    if (r + 1 == args.repeats) applied_map = std::move(copy);
  }
  if (!args.poses_out.empty()) {
    std::printf("applied map digest %016llx\n", static_cast<unsigned long long>(digest(applied_map)));
  }
  apply.report("apply_loop_correction", map,
               format("%zu poses, %zu points changed, %zu merged away", correction.corrected_T_wc.size(),
                      applied.changed_points.size(), applied.removed_points.size()));
  Timings mapper_apply;
  Map corrected_map;
  for (int r = 0; r < args.repeats; ++r) {
    LocalMapper mapper(camera, LocalMapperOptions{}, MapSnapshot{map, MapperState{}, std::nullopt, {}});
    mapper_apply.start();
    applied = mapper.apply_correction(correction);
    mapper_apply.stop();
    if (r + 1 == args.repeats) corrected_map = mapper.map();
  }
  mapper_apply.report("LocalMapper::apply_correction", map,
                      format("the same + covisibility of the merged points' keyframes: %zu keyframes, "
                             "%zu points changed",
                             applied.changed_keyframes.size(), applied.changed_points.size()));

  if (!args.global_ba) return;
  // Global BA on the corrected map; beyond --ba-max-points every k-th point only.
  const std::size_t stride = (corrected_map.points.size() + static_cast<std::size_t>(args.ba_max_points) - 1) /
                             static_cast<std::size_t>(args.ba_max_points);
  if (stride > 1) {
    std::size_t index = 0;
    for (auto& [id, point] : corrected_map.points) point.culled = point.culled || index++ % stride != 0;
  }
  GlobalBundleAdjustmentResult ba;
  const Timings global_ba =
      repeated(args.repeats, [&] { ba = GlobalBundleAdjustment().compute(corrected_map, camera); });
  global_ba.report("GlobalBundleAdjustment", corrected_map,
                   format("%d kf, %d points%s, %d observations, %d iterations, cost %.3g -> %.3g", ba.stats.keyframes,
                          ba.stats.points, stride > 1 ? format(" (1 in %zu)", stride).c_str() : "",
                          ba.stats.observations, ba.stats.iterations, ba.stats.initial_cost, ba.stats.final_cost));
}

int run(int argc, char** argv) {
  const Args args = parse(argc, argv);
  const auto vocabulary = load_vocabulary_setting(args.vocabulary);
  if (vocabulary) {
    std::printf("vocabulary %s: k %d, L %d, %zu words\n", describe_vocabulary_setting(args.vocabulary).c_str(),
                vocabulary->branching(), vocabulary->levels(), vocabulary->word_count());
  } else {
    std::printf("vocabulary none: no BoW detection measured\n");
  }
  const std::vector<Descriptor> pool = real_descriptors(args.dataset);
  if (pool.empty()) std::printf("descriptors: random bytes (--dataset none)\n");
  std::printf("repeats %d (BoW detection: %d query keyframes); times are wall clock, cpu = process CPU\n", args.repeats,
              args.queries);
  for (const int keyframes : args.keyframes) bench_size(args, keyframes, pool, vocabulary);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return heslam::bench::bench_main("heslam-bench-loop", argc, argv, run); }
