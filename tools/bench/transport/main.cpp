// heslam-bench-transport: one-way transport latency of stereo frames from a real heslam-replay
// process to a subscriber (this process), for an EuRoC 752x480 pair and a KITTI 1241x376 pair.
//
// Latency of a frame = this process's CLOCK_REALTIME when take() returned the deserialised sample
// minus the sample's source timestamp (CLOCK_REALTIME at dds_write in the replay; same machine, same
// clock). It therefore includes serialisation, loopback UDP, reassembly, the waitset wake-up and the
// copy into the C++ sample: what a frontend sees. The replay runs with --rate 1 at 20 Hz.
// wake_p50 is the median to the waitset wake-up, before take(): the difference is the take
// (allocation + deserialisation into the owned sample). The replay runs with --loop and caches the
// decoded pairs, so the frames of the first pass (decoded while the replay runs, as in every run
// without --loop) are also summarised on their own.
//
//   heslam-bench-transport [--frames N] [--domain D] [--bin DIR] [--euroc DIR] [--ddsperf-seconds S]
//                          [--take reuse|fresh]   (reuse, the default: take_into one sample, as the frontend)
//                          [--no-plain-c]         (skip the plain C API reference rows)
//                          [--image-transport shm --image-domain N]  (replay -> subscriber over iceoryx
//                           shared memory, docs/topics.md; needs iox-roudi running; the plain C and
//                           ddsperf rows stay UDP)
//                          [--replay-via "ip netns exec NS"]  (start the replay through this command, e.g.
//                           in another network namespace: the latency over a real link; docs/deployment.md)
//
// Also for reference, the same type, QoS and Cyclone configuration through the plain C API
// (dds_write / dds_take, no heslam runtime and no replay): a child process (this executable with the
// hidden --plain-c-publisher mode) writes synthetic pairs at 20 Hz from as many distinct buffers as the
// EuRoC recording has pairs, so its serialisation reads memory that is not in cache, as the replay's.
// The difference to the heslam rows is what heslam's replay and runtime add.
//
// For reference it then runs Cyclone's `ddsperf` ping/pong (when on PATH) with the same sample sizes,
// 20 Hz and the same (project) Cyclone configuration; ddsperf reports half the round trip per second,
// summarised here as the median over those seconds of its per-second median and p99.
//
// The KITTI-sized sequence is synthesised in a temporary folder (EuRoC images resized to 1241x376,
// 20 Hz like the EuRoC run) because no KITTI images ship with the shared data.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "runtime/args.hpp"
#include "runtime/flags.hpp"
#include "runtime/image_transport.hpp"
#include "runtime/participant.hpp"
#include "runtime/qos.hpp"
#include "runtime/reader.hpp"
#include "runtime/shutdown.hpp"
#include "runtime/topic.hpp"
#include "runtime/topics.hpp"
#include "runtime/waitset.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/dataset/stereo_images.hpp"

extern char** environ;

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kKittiWidth = 1241;
constexpr int kKittiHeight = 376;
constexpr double kFramePeriodS = 0.05;  // 20 Hz, as the EuRoC cameras
// Frames received before measuring: discovery, first-fragment socket buffer growth, page faults.
constexpr std::size_t kWarmupFrames = 10;
constexpr std::chrono::seconds kNoFrameTimeout{15};

std::int64_t realtime_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

// A KITTI sequence of `frames` pairs: EuRoC images resized, times at 20 Hz, a plausible calib.txt.
fs::path make_kitti_sequence(const StereoDataset& euroc, std::size_t frames) {
  const fs::path dir = fs::temp_directory_path() / ("heslam_bench_kitti_" + std::to_string(getpid()));
  fs::create_directories(dir / "image_0");
  fs::create_directories(dir / "image_1");
  std::ofstream times(dir / "times.txt");
  for (std::size_t i = 0; i < frames; ++i) {
    const StereoImages images = load_stereo_images(euroc.frames[i % euroc.frames.size()]);
    char name[32];
    std::snprintf(name, sizeof(name), "%06zu.png", i);
    cv::Mat left, right;
    cv::resize(images.left, left, cv::Size(kKittiWidth, kKittiHeight));
    cv::resize(images.right, right, cv::Size(kKittiWidth, kKittiHeight));
    cv::imwrite((dir / "image_0" / name).string(), left);
    cv::imwrite((dir / "image_1" / name).string(), right);
    times << static_cast<double>(i) * kFramePeriodS << "\n";
  }
  // KITTI 00's P0/P1 (718.856 px focal length, 0.537 m baseline).
  std::ofstream(dir / "calib.txt") << "P0: 718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1 0\n"
                                      "P1: 718.856 0 607.1928 -386.1448 0 718.856 185.2157 0 0 0 1 0\n";
  return dir;
}

struct Result {
  std::string name;
  std::size_t bytes = 0;
  std::vector<double> latencies_us;       // source timestamp -> sample taken (deserialised)
  std::vector<double> wake_latencies_us;  // source timestamp -> waitset woke (before take)
  // The frames of the first pass over the recording, decoded by the replay while it ran (as in any
  // run without --loop); later passes come from its decoded-pair cache.
  std::vector<double> first_pass_latencies_us;
  std::uint64_t first_seq = 0;
  std::uint64_t last_seq = 0;

  // One measured frame: taken at now_ns, written at source_ns; the first of a wake-up also gives the
  // latency to that wake-up.
  void record(const msg::StereoFrame& frame, std::int64_t source_ns, std::int64_t now_ns, std::int64_t wake_ns,
              bool first_of_wake) {
    if (latencies_us.empty()) first_seq = frame.seq;
    last_seq = frame.seq;
    bytes = frame.left._length + frame.right._length;
    latencies_us.push_back(static_cast<double>(now_ns - source_ns) * 1e-3);
    if (first_of_wake) wake_latencies_us.push_back(static_cast<double>(wake_ns - source_ns) * 1e-3);
  }
};

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(p * static_cast<double>(values.size() - 1) + 0.5);
  return values[std::min(index, values.size() - 1)];
}

Result measure(const std::string& name, const fs::path& dataset, const fs::path& bin_dir, int domain,
               std::size_t frames, std::size_t recording_frames, bool reuse_buffers,
               const std::vector<std::string>& replay_via, runtime::ImageTransport transport, int image_domain) {
  runtime::Participant participant({.domain_id = domain, .dds_config = ""});
  // --image-transport shm: the frames on their shared-memory domain, as the frontend reads them.
  runtime::ImageParticipant images(participant, transport, image_domain, "");
  const runtime::Topics topics;
  runtime::Reader<msg::StereoFrame> reader(images.get(), topics.stereo());
  runtime::WaitSet waitset(images.get());
  waitset.attach(reader);

  std::vector<std::string> args{(bin_dir / "heslam-replay").string(),
                                dataset.string(),
                                "--rate",
                                "1",
                                "--loop",
                                "--domain",
                                std::to_string(domain),
                                "--no-progress",
                                "--no-keyboard",
                                "--log-level",
                                "error"};
  if (images.separate_domain()) {
    args.insert(args.end(), {"--image-transport", "shm", "--image-domain", std::to_string(image_domain)});
  }
  args.insert(args.begin(), replay_via.begin(), replay_via.end());
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  pid_t replay = 0;
  if (posix_spawnp(&replay, argv[0], nullptr, nullptr, argv.data(), environ) != 0) {
    throw std::runtime_error(args[0] + ": cannot start (build heslam-replay, or pass --bin DIR)");
  }

  Result result;
  result.name = name;
  std::size_t received = 0;
  runtime::Received<msg::StereoFrame> reused;
  auto last_frame = std::chrono::steady_clock::now();
  while (result.latencies_us.size() < frames && !runtime::shutdown_requested()) {
    if (std::chrono::steady_clock::now() - last_frame > kNoFrameTimeout) {
      kill(replay, SIGKILL);
      waitpid(replay, nullptr, 0);
      throw std::runtime_error(name + ": no frame from heslam-replay for 15 s");
    }
    if (waitset.wait(std::chrono::milliseconds(100)) != runtime::Wake::kData) continue;
    const std::int64_t wake_ns = realtime_ns();
    bool first_of_wake = true;
    // reuse: take_into one Received, as the frontend does; fresh: a new sample (and allocation) per take.
    runtime::Received<msg::StereoFrame> fresh;
    runtime::Received<msg::StereoFrame>& frame = reuse_buffers ? reused : fresh;
    while (reader.take_into(frame)) {
      const std::int64_t now_ns = realtime_ns();
      if (!frame.info.valid_data) continue;
      last_frame = std::chrono::steady_clock::now();
      if (++received <= kWarmupFrames) continue;
      result.record(*frame.sample, frame.info.source_stamp_ns, now_ns, wake_ns, first_of_wake);
      if (frame.sample->seq < recording_frames) result.first_pass_latencies_us.push_back(result.latencies_us.back());
      first_of_wake = false;
      if (!reuse_buffers) fresh = runtime::Received<msg::StereoFrame>{};
    }
  }
  kill(replay, SIGINT);
  waitpid(replay, nullptr, 0);
  return result;
}

void print(const Result& result) {
  const std::size_t expected = result.last_seq - result.first_seq + 1;
  std::printf("%-18s %8.0f KB %7zu %6zu %9.0f %9.0f %9.0f %9.0f %9.0f\n", result.name.c_str(),
              static_cast<double>(result.bytes) / 1e3, result.latencies_us.size(),
              expected - result.latencies_us.size(), percentile(result.latencies_us, 0.5),
              percentile(result.latencies_us, 0.9), percentile(result.latencies_us, 0.99),
              percentile(result.latencies_us, 1.0), percentile(result.wake_latencies_us, 0.5));
  const std::vector<double>& first = result.first_pass_latencies_us;
  if (!first.empty()) {
    std::printf("  first pass (decoding) %7zu %6s %9.0f %9.0f %9.0f %9.0f\n", first.size(), "", percentile(first, 0.5),
                percentile(first, 0.9), percentile(first, 0.99), percentile(first, 1.0));
  }
}

pid_t spawn(std::vector<std::string> args, const fs::path& output, const std::string& dds_config) {
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  std::vector<std::string> environment_text{"CYCLONEDDS_URI=" + dds_config};
  for (char** variable = environ; *variable != nullptr; ++variable) {
    if (std::string(*variable).rfind("CYCLONEDDS_URI=", 0) != 0) environment_text.emplace_back(*variable);
  }
  std::vector<char*> environment;
  for (std::string& variable : environment_text) environment.push_back(variable.data());
  environment.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = 0;
  const int error = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environment.data());
  posix_spawn_file_actions_destroy(&actions);
  return error == 0 ? pid : 0;
}

// --plain-c-publisher mode: `frames` stereo pairs of width x height at 20 Hz with dds_write, each
// from the next of `buffers` distinct buffers, after waiting for a reader.
int plain_c_publish(int domain, int width, int height, std::size_t frames, std::size_t buffers) {
  const runtime::Participant participant({.domain_id = domain, .dds_config = ""});
  const runtime::Topic<msg::StereoFrame> topic(participant, runtime::Topics().stereo());
  const runtime::Qos qos(runtime::QosRole::kImages);
  const dds_entity_t writer = dds_create_writer(participant.handle(), topic.handle(), qos.get(), nullptr);
  if (writer < 0) throw std::runtime_error(std::string("plain C publisher: ") + dds_strretcode(writer));
  const std::size_t image_bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<std::uint8_t> pixels(buffers * 2 * image_bytes);
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<std::uint8_t>(i * 131 + (i >> 12));
  dds_publication_matched_status_t matched{};
  for (int tries = 0; tries < 1000 && matched.current_count == 0; ++tries) {
    dds_get_publication_matched_status(writer, &matched);
    if (matched.current_count == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  msg::StereoFrame frame{};
  frame.width_px = static_cast<std::uint32_t>(width);
  frame.height_px = static_cast<std::uint32_t>(height);
  frame.encoding = heslam_msg_ENCODING_MONO8;
  frame.left._length = frame.left._maximum = frame.right._length = frame.right._maximum =
      static_cast<std::uint32_t>(image_bytes);
  auto due = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < frames && !runtime::shutdown_requested(); ++i) {
    due +=
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(kFramePeriodS));
    std::this_thread::sleep_until(due);
    std::uint8_t* pair = pixels.data() + (i % buffers) * 2 * image_bytes;
    frame.left._buffer = pair;
    frame.right._buffer = pair + image_bytes;
    frame.seq = i;
    if (const dds_return_t rc = dds_write(writer, &frame); rc < 0 && rc != DDS_RETCODE_TIMEOUT) {
      throw std::runtime_error(std::string("plain C publisher: write failed: ") + dds_strretcode(rc));
    }
  }
  return 0;
}

// The plain C API reference: spawns the --plain-c-publisher child and takes its frames with dds_take
// into one reused sample, through a waitset on a read condition (what runtime::Reader does, unwrapped).
Result measure_plain_c(const std::string& name, int width, int height, int domain, std::size_t frames,
                       std::size_t buffers) {
  const runtime::Participant participant({.domain_id = domain, .dds_config = ""});
  const runtime::Topic<msg::StereoFrame> topic(participant, runtime::Topics().stereo());
  const runtime::Qos qos(runtime::QosRole::kImages);
  const dds_entity_t reader = dds_create_reader(participant.handle(), topic.handle(), qos.get(), nullptr);
  const dds_entity_t waitset = dds_create_waitset(participant.handle());
  const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
  if (reader < 0 || waitset < 0 || condition < 0 || dds_waitset_attach(waitset, condition, 0) < 0) {
    throw std::runtime_error(name + ": cannot create the plain C reader");
  }
  std::vector<std::string> args{fs::canonical("/proc/self/exe").string(), "--plain-c-publisher",
                                std::to_string(width) + "," + std::to_string(height) + "," +
                                    std::to_string(frames + kWarmupFrames) + "," + std::to_string(buffers),
                                "--domain", std::to_string(domain)};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  pid_t publisher = 0;
  if (posix_spawn(&publisher, argv[0], nullptr, nullptr, argv.data(), environ) != 0) {
    throw std::runtime_error(name + ": cannot start the plain C publisher");
  }
  Result result;
  result.name = name;
  msg::StereoFrame sample{};
  void* buffer = &sample;
  dds_sample_info_t info{};
  std::size_t received = 0;
  auto last_frame = std::chrono::steady_clock::now();
  while (result.latencies_us.size() < frames && !runtime::shutdown_requested()) {
    if (std::chrono::steady_clock::now() - last_frame > kNoFrameTimeout) break;
    if (dds_waitset_wait(waitset, nullptr, 0, DDS_MSECS(100)) <= 0) continue;
    const std::int64_t wake_ns = realtime_ns();
    bool first_of_wake = true;
    while (dds_take(reader, &buffer, &info, 1, 1) == 1) {
      const std::int64_t now_ns = realtime_ns();
      if (!info.valid_data) continue;
      last_frame = std::chrono::steady_clock::now();
      if (++received <= kWarmupFrames) continue;
      result.record(sample, info.source_timestamp, now_ns, wake_ns, first_of_wake);
      first_of_wake = false;
    }
  }
  dds_sample_free(&sample, &heslam_msg_StereoFrame_desc, DDS_FREE_CONTENTS);
  kill(publisher, SIGINT);
  waitpid(publisher, nullptr, 0);
  if (result.latencies_us.empty()) throw std::runtime_error(name + ": no frame from the plain C publisher");
  return result;
}

// ddsperf ping/pong at 20 Hz with `bytes` per sample; prints median-of-seconds of its 50% and 99%.
void run_ddsperf(const std::string& name, std::size_t bytes, int domain, int seconds) {
  const fs::path pong_out = fs::temp_directory_path() / ("heslam_bench_pong_" + std::to_string(getpid()));
  const fs::path ping_out = fs::temp_directory_path() / ("heslam_bench_ping_" + std::to_string(getpid()));
  const std::string& config = runtime::default_dds_config();
  const pid_t pong =
      spawn({"ddsperf", "-i", std::to_string(domain), "-D", std::to_string(seconds + 3), "pong"}, pong_out, config);
  const pid_t ping = spawn({"ddsperf", "-i", std::to_string(domain), "-D", std::to_string(seconds), "ping", "20Hz",
                            "size", std::to_string(bytes)},
                           ping_out, config);
  if (ping == 0 || pong == 0) {
    std::printf("%-18s ddsperf not found on PATH (apt install cyclonedds-tools)\n", name.c_str());
    for (const pid_t pid : {ping, pong}) {
      if (pid == 0) continue;
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    return;
  }
  waitpid(ping, nullptr, 0);
  kill(pong, SIGINT);
  waitpid(pong, nullptr, 0);
  std::ifstream in(ping_out);
  std::stringstream text;
  text << in.rdbuf();
  const std::string output = text.str();
  std::vector<double> medians_us, p99s_us;
  const std::regex line("size [0-9]+ mean [0-9.]+us min [0-9.]+us 50% ([0-9.]+)us 90% [0-9.]+us 99% ([0-9.]+)us");
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line); it != std::sregex_iterator(); ++it) {
    medians_us.push_back(std::stod((*it)[1]));
    p99s_us.push_back(std::stod((*it)[2]));
  }
  fs::remove(pong_out);
  fs::remove(ping_out);
  std::printf("%-18s %8.0f KB %7zu s %4s %9.0f %9s %9.0f   (ddsperf ping/pong, RTT/2, tuned config)\n", name.c_str(),
              static_cast<double>(bytes) / 1e3, medians_us.size(), "", percentile(medians_us, 0.5), "-",
              percentile(p99s_us, 0.5));
}

int run(int argc, char** argv) {
  runtime::install_shutdown_handlers();
  runtime::CommonArgs common = runtime::parse_common_args(argc, argv, "bench-transport");
  std::size_t frames = 200;
  int ddsperf_seconds = 10;
  bool reuse_buffers = true;
  bool plain_c = true;
  std::vector<std::string> replay_via;
  fs::path bin_dir = fs::canonical("/proc/self/exe").parent_path();
  fs::path euroc_dir = fs::path(HESLAM_SHARED_DATA) / "euroc_v101_head";
  std::vector<int> plain_c_child;  // the hidden child mode: W,H,FRAMES,BUFFERS
  runtime::Flags flags("heslam-bench-transport [options] [common options]");
  flags
      .integer("--frames", "N", &frames, std::size_t{1}, std::numeric_limits<std::size_t>::max(),
               "timed frames per row (200)")
      .path("--bin", "DIR", &bin_dir, "where heslam-replay is (default: beside this executable)")
      .path("--euroc", "DIR", &euroc_dir, "the EuRoC recording replayed (euroc_v101_head)")
      .integer("--ddsperf-seconds", "S", &ddsperf_seconds, "length of the ddsperf reference run (10)")
      .choice("--take", &reuse_buffers, {{"reuse", true}, {"fresh", false}},
              "reuse: take_into one sample (default); fresh: a new sample per frame")
      .toggle("--no-plain-c", &plain_c, "no plain C API reference rows", false)
      .custom("--replay-via", "CMD", "run the replay through CMD (words split at spaces, e.g. 'taskset -c 1')",
              [&replay_via](const std::string& value) {
                std::istringstream words(value);
                for (std::string word; words >> word;) replay_via.push_back(word);
              })
      .integer_list("--plain-c-publisher", "W,H,N,B", &plain_c_child, 1, std::numeric_limits<int>::max(),
                    "internal: be the plain C publisher child (N pairs of W x H from B buffers)");
  if (common.help) {
    std::cout << flags.usage() << runtime::common_args_usage();
    return 0;
  }
  flags.parse(common.rest);
  if (flags.given("--plain-c-publisher")) {
    if (plain_c_child.size() != 4) throw std::runtime_error("--plain-c-publisher: expected W,H,N,B");
    return plain_c_publish(common.domain_id, plain_c_child[0], plain_c_child[1],
                           static_cast<std::size_t>(plain_c_child[2]), static_cast<std::size_t>(plain_c_child[3]));
  }
  const StereoDataset euroc = open_dataset(euroc_dir);
  const fs::path kitti = make_kitti_sequence(euroc, euroc.frames.size());
  std::printf(
      "one-way latency heslam-replay -> subscriber, %zu frames each after %zu warm-up, 20 Hz, domain %d, "
      "take %s\n",
      frames, kWarmupFrames, common.domain_id, reuse_buffers ? "reuse (take_into)" : "fresh sample per frame");
  std::printf("%-18s %11s %7s %6s %9s %9s %9s %9s %9s\n", "stereo pair", "size", "frames", "lost", "median_us",
              "p90_us", "p99_us", "max_us", "wake_p50");
  std::fflush(stdout);
  try {
    print(measure("EuRoC 752x480", euroc_dir, bin_dir, common.domain_id, frames, euroc.frames.size(), reuse_buffers,
                  replay_via, common.image_transport, common.image_domain_id));
    std::fflush(stdout);
    print(measure("KITTI 1241x376", kitti, bin_dir, common.domain_id, frames, euroc.frames.size(), reuse_buffers,
                  replay_via, common.image_transport, common.image_domain_id));
  } catch (...) {
    fs::remove_all(kitti);
    throw;
  }
  fs::remove_all(kitti);
  if (plain_c) {
    std::fflush(stdout);
    print(measure_plain_c("plain C 752x480", 752, 480, common.domain_id, frames, euroc.frames.size()));
    std::fflush(stdout);
    print(
        measure_plain_c("plain C 1241x376", kKittiWidth, kKittiHeight, common.domain_id, frames, euroc.frames.size()));
  }
  if (ddsperf_seconds > 0) {
    std::fflush(stdout);
    run_ddsperf("ddsperf 722 KB", 752 * 480 * 2, common.domain_id, ddsperf_seconds);
    std::fflush(stdout);
    run_ddsperf("ddsperf 933 KB", 1241 * 376 * 2, common.domain_id, ddsperf_seconds);
  }
  return 0;
}

}  // namespace
}  // namespace heslam

int main(int argc, char** argv) {
  try {
    return heslam::run(argc, argv);
  } catch (const std::exception& error) {
    std::cerr << "heslam-bench-transport: " << error.what() << "\n";
    return 1;
  }
}
