// heslam-bench-shm: one-way latency of the EuRoC-size stereo pair (752x480x2, 722 KB) over loopback
// UDP with the project's tuned Cyclone XML vs Cyclone's shared-memory (iceoryx) path, and whether
// keyed status-like types survive SHM (findings pitfall 10).
//
// Every case runs in two child processes of this executable (a subscriber, then a publisher), so a
// crash or a hang (participant creation hangs without iox-roudi) is recorded as a result instead of
// ending the run. Cases:
//   udp-seq            StereoFrame (sequence<octet>), images QoS, project XML: the default transport
//   shm-seq            the same with <SharedMemory><Enable>: the sample is serialised into the chunk
//   shm-loan           FixedStereoFrame (octet arrays), dds_loan_sample + dds_write, dds_take on loan
//   shm-status-int     IntKeyStatus (uint32 key), status QoS (liveliness 2 s) on the SHM domain
//   shm-status-string  msg::ComponentStatus (string key), status QoS on the SHM domain
//   shm-status-int-nolive / shm-status-string-nolive   the same without the liveliness lease
// Latency of a frame = CLOCK_REALTIME when dds_take returned it minus its source timestamp (stamped by
// dds_write in the publisher; same machine, same clock); "from ready" starts at the frame's stamp_ns,
// taken before the pixels are copied into a loan or serialised, so it charges the loan case its copy.
// The publisher writes at 20 Hz from a pool of
// distinct buffers (cold in cache, as a replay's decoded pairs); the subscriber checks two marker bytes
// per frame so a torn or stale chunk is counted, not timed.
// Per process it also prints dds_is_shared_memory_available() of its writer/reader: Cyclone falls
// back to UDP silently when a QoS or type does not qualify, so "shm" in a case name proves nothing.
//
//   heslam-bench-shm [--frames N] [--domain D] [--cases a,b,...] [--roudi start|external]
//                    [--roudi-config FILE] [--case-timeout-s S]
// --roudi start (default): start iox-roudi with config/iceoryx/roudi.toml for the SHM cases and stop
// it at the end (if one is already running, it is used as it is); external: use a running one.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <dds/dds.h>
#include <dds/ddsc/dds_loan_api.h>

#include "runtime/flags.hpp"
#include "runtime/messages.hpp"
#include "runtime/participant.hpp"
#include "runtime/qos.hpp"
#include "shm_probe.h"
#include "tools/bench/bench_util.hpp"

extern char** environ;

namespace heslam {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr std::uint32_t kWidthPx = 752;  // EuRoC cam0/cam1
constexpr std::uint32_t kHeightPx = 480;
constexpr std::size_t kImageBytes = std::size_t{kWidthPx} * kHeightPx;
static_assert(kImageBytes == heslam_probe_kEurocImageBytes, "shm_probe.idl and the bench disagree on the size");
constexpr std::chrono::milliseconds kFramePeriod{50};  // 20 Hz, as the EuRoC cameras
// Distinct source buffers the publisher cycles through: more than the 2 MB L2, as a replay's pairs.
constexpr std::size_t kSourceBuffers = 16;
// Frames before measuring: discovery, first-use page faults of sockets and chunks.
constexpr std::size_t kWarmupFrames = 10;
// Status samples per status case, and their rate (fast: only delivery and crashes matter here).
constexpr int kStatusSamples = 50;
constexpr std::chrono::milliseconds kStatusPeriod{20};
// Publisher: wait this long for the subscriber to match before giving up.
constexpr std::chrono::seconds kMatchTimeout{10};
// Subscriber: stop after this long without a sample (the publisher is done or dead).
constexpr std::chrono::seconds kIdleTimeout{4};
// Let late acks / SHM deliveries drain before the publisher deletes its writer.
constexpr std::chrono::milliseconds kLinger{500};
// iox-roudi needs a moment to create its shared memory before a participant can register.
constexpr std::chrono::milliseconds kRoudiStartup{1500};
constexpr int kStatusNodeId = 7;
constexpr const char* kStatusName = "frontend";

std::string shm_xml() {
  return "<CycloneDDS><Domain id=\"any\"><SharedMemory><Enable>true</Enable><LogLevel>warn</LogLevel>"
         "</SharedMemory></Domain></CycloneDDS>";
}

bool case_uses_shm(const std::string& name) { return name.rfind("shm-", 0) == 0; }

std::int64_t realtime_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

// The marker bytes a frame carries so the subscriber can check it got this frame's pixels.
std::uint8_t left_marker(std::uint64_t seq) { return static_cast<std::uint8_t>(seq & 0xff); }
std::uint8_t right_marker(std::uint64_t seq) { return static_cast<std::uint8_t>((seq * 7 + 3) & 0xff); }

// One participant on its own domain (created from `xml`), deleted with it.
class Domain {
 public:
  Domain(int domain_id, const std::string& xml) {
    domain_ =
        runtime::check_dds(dds_create_domain(static_cast<dds_domainid_t>(domain_id), xml.c_str()), "create domain");
    participant_ = runtime::check_dds(dds_create_participant(static_cast<dds_domainid_t>(domain_id), nullptr, nullptr),
                                      "create participant");
  }
  ~Domain() { dds_delete(domain_); }
  Domain(const Domain&) = delete;
  Domain& operator=(const Domain&) = delete;
  dds_entity_t participant() const { return participant_; }

 private:
  dds_entity_t domain_ = 0;
  dds_entity_t participant_ = 0;
};

struct CaseSpec {
  const dds_topic_descriptor_t* descriptor = nullptr;
  const char* topic = nullptr;
  runtime::Qos qos{runtime::QosRole::kImages};
  bool frames = true;  // an image case (else a status case)
  bool loan = false;
};

CaseSpec spec_of(const std::string& name) {
  CaseSpec spec;
  if (name == "udp-seq" || name == "shm-seq") {
    spec.descriptor = &heslam_msg_StereoFrame_desc;
    spec.topic = "bench_shm/stereo";
  } else if (name == "shm-loan") {
    spec.descriptor = &heslam_probe_FixedStereoFrame_desc;
    spec.topic = "bench_shm/stereo_fixed";
    spec.loan = true;
  } else if (name.rfind("shm-status-", 0) == 0) {
    const bool int_key = name.rfind("shm-status-int", 0) == 0;
    spec.descriptor = int_key ? &heslam_probe_IntKeyStatus_desc : &heslam_msg_ComponentStatus_desc;
    spec.topic = int_key ? "bench_shm/status_int" : "bench_shm/status_string";
    spec.qos = runtime::Qos(runtime::QosRole::kStatus);
    if (name.find("-nolive") != std::string::npos) {
      // runtime::Qos has no liveliness setter; its dds_qos_t is its own (non-const) allocation.
      dds_qset_liveliness(const_cast<dds_qos_t*>(spec.qos.get()), DDS_LIVELINESS_AUTOMATIC, DDS_INFINITY);
    }
    spec.frames = false;
  } else {
    throw std::runtime_error("unknown case '" + name + "'");
  }
  return spec;
}

std::string xml_of(const std::string& name) {
  return case_uses_shm(name) ? runtime::default_dds_config() + "," + shm_xml() : runtime::default_dds_config();
}

// ---- publisher process -------------------------------------------------------------------------

void wait_matched(dds_entity_t writer) {
  const auto deadline = Clock::now() + kMatchTimeout;
  dds_publication_matched_status_t status{};
  while (Clock::now() < deadline) {
    dds_get_publication_matched_status(writer, &status);
    if (status.current_count > 0) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  throw std::runtime_error("no subscriber matched within 10 s");
}

void publish_frames(dds_entity_t writer, bool loan, std::size_t count, std::vector<double>& write_us) {
  std::vector<std::vector<std::uint8_t>> sources(kSourceBuffers, std::vector<std::uint8_t>(2 * kImageBytes));
  for (std::size_t b = 0; b < sources.size(); ++b) {
    for (std::size_t i = 0; i < sources[b].size(); ++i) sources[b][i] = static_cast<std::uint8_t>((i * 31 + b) & 0xff);
  }
  auto next = Clock::now();
  for (std::uint64_t seq = 0; seq < count; ++seq) {
    std::this_thread::sleep_until(next);
    next += kFramePeriod;
    std::vector<std::uint8_t>& source = sources[seq % sources.size()];
    source[0] = left_marker(seq);
    source[2 * kImageBytes - 1] = right_marker(seq);
    const auto start = Clock::now();
    dds_return_t ret = 0;
    if (loan) {
      void* chunk = nullptr;
      runtime::check_dds(dds_loan_sample(writer, &chunk), "dds_loan_sample");
      auto* frame = static_cast<heslam_probe_FixedStereoFrame*>(chunk);
      frame->seq = seq;
      frame->stamp_ns = realtime_ns();
      frame->width_px = kWidthPx;
      frame->height_px = kHeightPx;
      // The replay would decode into its own buffer, then copy into the loan: one copy, as here.
      std::memcpy(frame->left, source.data(), kImageBytes);
      std::memcpy(frame->right, source.data() + kImageBytes, kImageBytes);
      ret = dds_write(writer, frame);
    } else {
      msg::StereoFrame frame{};
      frame.seq = seq;
      frame.stamp_ns = realtime_ns();
      frame.stamp_right_ns = frame.stamp_ns;
      frame.width_px = kWidthPx;
      frame.height_px = kHeightPx;
      frame.encoding = heslam_msg_ENCODING_MONO8;
      frame.left = {static_cast<std::uint32_t>(kImageBytes), static_cast<std::uint32_t>(kImageBytes), source.data(),
                    false};
      frame.right = {static_cast<std::uint32_t>(kImageBytes), static_cast<std::uint32_t>(kImageBytes),
                     source.data() + kImageBytes, false};
      ret = dds_write(writer, &frame);
    }
    write_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
    runtime::check_dds(ret, "dds_write frame " + std::to_string(seq));
  }
}

void publish_status(dds_entity_t writer, bool int_key) {
  std::string counter_name = "frames";
  for (int i = 0; i < kStatusSamples; ++i) {
    dds_return_t ret = 0;
    if (int_key) {
      heslam_probe_ProbeCounter counter{counter_name.data(), static_cast<std::uint64_t>(i)};
      heslam_probe_IntKeyStatus status{};
      status.node_id = kStatusNodeId;
      status.name = const_cast<char*>(kStatusName);
      status.pid = getpid();
      status.stamp_ns = realtime_ns();
      status.counters = {1, 1, &counter, false};
      status.message = const_cast<char*>("");
      ret = dds_write(writer, &status);
    } else {
      heslam_msg_Counter counter{counter_name.data(), static_cast<std::uint64_t>(i)};
      msg::ComponentStatus status{};
      status.name = const_cast<char*>(kStatusName);
      status.pid = getpid();
      status.executable = const_cast<char*>("heslam-bench-shm");
      status.stamp_ns = realtime_ns();
      status.counters = {1, 1, &counter, false};
      status.message = const_cast<char*>("");
      ret = dds_write(writer, &status);
    }
    runtime::check_dds(ret, "dds_write status " + std::to_string(i));
    std::this_thread::sleep_for(kStatusPeriod);
  }
}

int run_publisher(const std::string& name, int domain_id, std::size_t frames) {
  const CaseSpec spec = spec_of(name);
  Domain domain(domain_id, xml_of(name));
  const dds_entity_t topic = runtime::check_dds(
      dds_create_topic(domain.participant(), spec.descriptor, spec.topic, nullptr, nullptr), "topic");
  const dds_entity_t writer =
      runtime::check_dds(dds_create_writer(domain.participant(), topic, spec.qos.get(), nullptr), "writer");
  std::cout << "PUB shm_available=" << dds_is_shared_memory_available(writer)
            << " loan_available=" << dds_is_loan_available(writer) << std::endl;
  wait_matched(writer);
  std::vector<double> write_us;
  if (spec.frames) {
    publish_frames(writer, spec.loan, frames + kWarmupFrames, write_us);
  } else {
    publish_status(writer, spec.descriptor == &heslam_probe_IntKeyStatus_desc);
  }
  std::this_thread::sleep_for(kLinger);
  if (!write_us.empty()) {
    std::printf("PUB write_median_us=%.0f write_p99_us=%.0f\n", bench::percentile(write_us, 0.5),
                bench::percentile(write_us, 0.99));
  }
  std::cout << "PUB done" << std::endl;
  return 0;
}

// ---- subscriber process ------------------------------------------------------------------------

struct Received {
  std::vector<double> latency_us;        // source timestamp (stamped inside dds_write) -> taken
  std::vector<double> ready_latency_us;  // frame ready (stamp_ns, before the copy into a loan) -> taken
  std::size_t samples = 0;
  std::size_t bad = 0;  // marker bytes or key not what the publisher wrote
};

// Takes one sample at a time (as the frontend) until `expected` arrived or the publisher went idle.
template <typename Take>
void receive(dds_entity_t participant, dds_entity_t reader, std::size_t expected, Take take) {
  const dds_entity_t waitset = dds_create_waitset(participant);
  const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
  dds_waitset_attach(waitset, condition, 0);
  auto last_sample = Clock::now();
  std::size_t got = 0;
  std::cout << "SUB ready" << std::endl;
  while (got < expected) {
    const dds_return_t woke = dds_waitset_wait(waitset, nullptr, 0, DDS_MSECS(200));
    runtime::check_dds(woke, "dds_waitset_wait");
    if (woke == 0) {
      // Before the first sample the publisher may still be starting; afterwards silence means it ended.
      if (got > 0 && Clock::now() - last_sample > kIdleTimeout) break;
      if (got == 0 && Clock::now() - last_sample > 4 * kMatchTimeout) break;
      continue;
    }
    std::size_t n = 0;
    while ((n = take()) > 0) got += n;
    last_sample = Clock::now();
  }
  dds_delete(waitset);
}

int run_subscriber(const std::string& name, int domain_id, std::size_t frames) {
  const CaseSpec spec = spec_of(name);
  Domain domain(domain_id, xml_of(name));
  const dds_entity_t topic = runtime::check_dds(
      dds_create_topic(domain.participant(), spec.descriptor, spec.topic, nullptr, nullptr), "topic");
  const dds_entity_t reader =
      runtime::check_dds(dds_create_reader(domain.participant(), topic, spec.qos.get(), nullptr), "reader");
  std::cout << "SUB shm_available=" << dds_is_shared_memory_available(reader) << std::endl;
  Received result;
  const std::size_t expected = spec.frames ? frames + kWarmupFrames : static_cast<std::size_t>(kStatusSamples);
  auto record = [&](const dds_sample_info_t& info, std::uint64_t seq, std::int64_t ready_ns, bool ok) {
    ++result.samples;
    if (!ok) ++result.bad;
    if (spec.frames && seq >= kWarmupFrames) {
      const std::int64_t now_ns = realtime_ns();
      result.latency_us.push_back(static_cast<double>(now_ns - info.source_timestamp) * 1e-3);
      result.ready_latency_us.push_back(static_cast<double>(now_ns - ready_ns) * 1e-3);
    }
  };
  if (name == "shm-loan") {
    receive(domain.participant(), reader, expected, [&]() -> std::size_t {
      void* samples[1] = {nullptr};
      dds_sample_info_t info[1];
      const dds_return_t n = runtime::check_dds(dds_take(reader, samples, info, 1, 1), "dds_take (loan)");
      if (n == 0) return 0;
      if (info[0].valid_data) {
        const auto* frame = static_cast<const heslam_probe_FixedStereoFrame*>(samples[0]);
        record(info[0], frame->seq, frame->stamp_ns,
               frame->left[0] == left_marker(frame->seq) && frame->right[kImageBytes - 1] == right_marker(frame->seq));
      }
      dds_return_loan(reader, samples, n);
      return static_cast<std::size_t>(n);
    });
  } else if (spec.frames) {
    msg::StereoFrame frame{};  // buffers malloc'ed by the first take, reused by later ones (pitfall 4)
    receive(domain.participant(), reader, expected, [&]() -> std::size_t {
      void* samples[1] = {&frame};
      dds_sample_info_t info[1];
      const dds_return_t n = runtime::check_dds(dds_take(reader, samples, info, 1, 1), "dds_take");
      if (n > 0 && info[0].valid_data) {
        const bool ok = frame.left._length == kImageBytes && frame.right._length == kImageBytes &&
                        frame.left._buffer[0] == left_marker(frame.seq) &&
                        frame.right._buffer[kImageBytes - 1] == right_marker(frame.seq);
        record(info[0], frame.seq, frame.stamp_ns, ok);
      }
      return static_cast<std::size_t>(n);
    });
    heslam_msg_StereoFrame_free(&frame, DDS_FREE_CONTENTS);
  } else {
    const bool int_key = spec.descriptor == &heslam_probe_IntKeyStatus_desc;
    receive(domain.participant(), reader, expected, [&]() -> std::size_t {
      void* samples[1] = {nullptr};
      dds_sample_info_t info[1];
      const dds_return_t n = runtime::check_dds(dds_take(reader, samples, info, 1, 1), "dds_take (status)");
      if (n == 0) return 0;
      if (info[0].valid_data) {
        bool ok = false;
        if (int_key) {
          const auto* status = static_cast<const heslam_probe_IntKeyStatus*>(samples[0]);
          ok = status->node_id == kStatusNodeId && std::strcmp(status->name, kStatusName) == 0;
        } else {
          const auto* status = static_cast<const msg::ComponentStatus*>(samples[0]);
          ok = std::strcmp(status->name, kStatusName) == 0;
        }
        record(info[0], 0, 0, ok);
      }
      dds_return_loan(reader, samples, n);
      return static_cast<std::size_t>(n);
    });
  }
  std::printf("SUB received=%zu expected=%zu bad=%zu", result.samples, expected, result.bad);
  if (!result.latency_us.empty()) {
    std::printf(" timed=%zu median_us=%.0f p90_us=%.0f p99_us=%.0f max_us=%.0f", result.latency_us.size(),
                bench::percentile(result.latency_us, 0.5), bench::percentile(result.latency_us, 0.9),
                bench::percentile(result.latency_us, 0.99), bench::percentile(result.latency_us, 1.0));
    std::printf(" from_ready_median_us=%.0f from_ready_p99_us=%.0f", bench::percentile(result.ready_latency_us, 0.5),
                bench::percentile(result.ready_latency_us, 0.99));
  }
  std::printf("\n");
  return result.samples == expected && result.bad == 0 ? 0 : 2;
}

// ---- orchestration -----------------------------------------------------------------------------

struct Child {
  pid_t pid = -1;
  fs::path output;
};

Child spawn(const std::vector<std::string>& args, const fs::path& output) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> argv;
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  Child child{-1, output};
  const int error = posix_spawnp(&child.pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw std::runtime_error("cannot start " + args[0] + ": " + std::strerror(error));
  return child;
}

// "exit 0", "exit 2", "killed by signal 11 (Segmentation fault)", "timeout (killed)".
std::string wait_for(const Child& child, Clock::time_point deadline) {
  int status = 0;
  while (true) {
    const pid_t done = waitpid(child.pid, &status, WNOHANG);
    if (done == child.pid) break;
    if (Clock::now() > deadline) {
      kill(child.pid, SIGKILL);
      waitpid(child.pid, &status, 0);
      return "timeout (killed)";
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (WIFEXITED(status)) return "exit " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
  }
  return "unknown end";
}

std::string read_all(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The lines of a child's output worth showing: its results, and its first error lines.
std::string summary_lines(const std::string& text, const std::string& prefix) {
  std::istringstream lines(text);
  std::string line;
  std::string out;
  int other = 0;
  while (std::getline(lines, line)) {
    if (line.rfind(prefix, 0) == 0) {
      if (line != prefix + " ready" && line != prefix + " done") out += "  " + line + "\n";
    } else if (other++ < 3 && !line.empty()) {
      out += "  " + prefix + " said: " + line + "\n";
    }
  }
  return out;
}

bool wait_for_line(const fs::path& path, const std::string& needle, std::chrono::seconds timeout) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    if (read_all(path).find(needle) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

void run_case(const std::string& self, const std::string& name, int domain_id, std::size_t frames,
              std::chrono::seconds timeout) {
  const fs::path dir = fs::temp_directory_path();
  const std::string tag = std::to_string(getpid()) + "_" + name;
  const std::vector<std::string> common = {
      "--case", name, "--domain", std::to_string(domain_id), "--frames", std::to_string(frames)};
  std::vector<std::string> sub_args = {self, "--role", "sub"};
  sub_args.insert(sub_args.end(), common.begin(), common.end());
  std::vector<std::string> pub_args = {self, "--role", "pub"};
  pub_args.insert(pub_args.end(), common.begin(), common.end());
  const auto deadline = Clock::now() + timeout;
  const Child sub = spawn(sub_args, dir / ("heslam_bench_shm_sub_" + tag + ".txt"));
  // A subscriber that never gets ready (e.g. no RouDi: participant creation hangs) ends the case.
  const bool ready = wait_for_line(sub.output, "SUB ready", std::chrono::seconds(15));
  std::string pub_end = "not started (subscriber not ready)";
  std::string pub_text;
  if (ready) {
    const Child pub = spawn(pub_args, dir / ("heslam_bench_shm_pub_" + tag + ".txt"));
    pub_end = wait_for(pub, deadline);
    pub_text = read_all(pub.output);
    fs::remove(pub.output);
  }
  const std::string sub_end = wait_for(sub, ready ? deadline : Clock::now());
  const std::string sub_text = read_all(sub.output);
  fs::remove(sub.output);
  std::cout << name << ": publisher " << pub_end << ", subscriber " << sub_end << "\n"
            << summary_lines(pub_text, "PUB") << summary_lines(sub_text, "SUB") << std::flush;
}

// iox-roudi, started for the SHM cases unless one runs already; stopped (SIGTERM) at the end.
class Roudi {
 public:
  explicit Roudi(const fs::path& config) {
    const fs::path log = fs::temp_directory_path() / ("heslam_bench_shm_roudi_" + std::to_string(getpid()) + ".txt");
    child_ = spawn({"iox-roudi", "-c", config.string(), "-l", "warning"}, log);
    std::this_thread::sleep_for(kRoudiStartup);
    int status = 0;
    if (waitpid(child_.pid, &status, WNOHANG) == child_.pid) {
      std::cout << "iox-roudi exited at once (another RouDi running? using it): "
                << summary_lines(read_all(log), "roudi") << std::flush;
      child_.pid = -1;
    }
  }
  ~Roudi() {
    if (child_.pid > 0) {
      kill(child_.pid, SIGTERM);
      waitpid(child_.pid, nullptr, 0);
    }
    fs::remove(child_.output);
  }
  Roudi(const Roudi&) = delete;
  Roudi& operator=(const Roudi&) = delete;

 private:
  Child child_;
};

std::vector<std::string> split(const std::string& list) {
  std::vector<std::string> items;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

int run(int argc, char** argv) {
  std::size_t frames = 300;
  int domain_id = 78;
  std::string cases =
      "udp-seq,shm-seq,shm-loan,shm-status-int,shm-status-int-nolive,shm-status-string,shm-status-string-nolive";
  std::string roudi = "start";
  fs::path roudi_config = fs::path(HESLAM_SOURCE_DIR) / "config" / "iceoryx" / "roudi.toml";
  int case_timeout_s = 0;
  std::string role;
  std::string case_name;
  bool help = false;
  runtime::Flags flags("heslam-bench-shm [options]");
  flags
      .integer("--frames", "N", &frames, std::size_t{1}, std::numeric_limits<std::size_t>::max(),
               "frames per case (300)")
      .integer("--domain", "D", &domain_id, 0, runtime::kMaxDomainId, "DDS domain (78)")
      .text("--cases", "a,b", &cases, "the cases to run (default: all)")
      .choice("--roudi", &roudi, {{"start", std::string("start")}, {"external", std::string("external")}},
              "start a RouDi for the shm cases, or use a running one (start)")
      .path("--roudi-config", "FILE", &roudi_config, "the RouDi config (config/iceoryx/roudi.toml)")
      .integer("--case-timeout-s", "S", &case_timeout_s, 0, std::numeric_limits<int>::max(),
               "give a case up after S s (0: from the frame count)")
      .choice("--role", &role, {{"pub", std::string("pub")}, {"sub", std::string("sub")}},
              "internal: be a case's publisher or subscriber child")
      .text("--case", "NAME", &case_name, "internal: the child's case")
      .toggle("--help", &help, "this help")
      .alias("-h");
  flags.parse(argc, argv);
  if (help) {
    std::cout << flags.usage();
    return 0;
  }
  if (role == "pub") return run_publisher(case_name, domain_id, frames);
  if (role == "sub") return run_subscriber(case_name, domain_id, frames);

  const std::vector<std::string> names = split(cases);
  for (const std::string& name : names) spec_of(name);  // unknown names fail before anything runs
  // Frames at 20 Hz, plus discovery and the subscriber's idle timeout.
  const auto timeout = case_timeout_s > 0 ? std::chrono::seconds(case_timeout_s)
                                          : std::chrono::seconds(30 + (frames + kWarmupFrames) / 20);
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  std::unique_ptr<Roudi> roudi_process;
  bool any_shm = false;
  for (const std::string& name : names) any_shm = any_shm || case_uses_shm(name);
  if (any_shm && roudi == "start") roudi_process = std::make_unique<Roudi>(roudi_config);
  std::cout << "heslam-bench-shm: " << frames << " frames of " << kWidthPx << "x" << kHeightPx
            << "x2 mono8 at 20 Hz per image case (+" << kWarmupFrames << " warm-up), domain " << domain_id << "\n";
  for (const std::string& name : names) run_case(self, name, domain_id, frames, timeout);
  return 0;
}

}  // namespace
}  // namespace heslam

int main(int argc, char** argv) { return heslam::bench::bench_main("heslam-bench-shm", argc, argv, heslam::run); }
