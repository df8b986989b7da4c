// heslam-spy list / echo / hz / bw / info.
#include "tools/spy/spy_commands.hpp"

#include <dds/ddsi/ddsi_serdata.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <set>

#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/security.hpp"
#include "runtime/shutdown.hpp"
#include "runtime/waitset.hpp"
#include "tools/spy/arrival_window.hpp"
#include "tools/spy/message_format.hpp"
#include "tools/spy/spy_topic.hpp"
#include "tools/spy/topic_discovery.hpp"

namespace heslam {

namespace {

using Clock = std::chrono::steady_clock;

// hz / bw print a report this often, as `ros2 topic hz`.
constexpr std::chrono::seconds kReportPeriod{1};
// Waits are sliced so SIGINT and --timeout are noticed promptly.
constexpr std::chrono::milliseconds kWaitSlice{100};
// echo --once on a keyed topic prints one sample per instance and stops once no new instance has
// appeared for this long: status is published every second, so every living component is heard.
constexpr std::chrono::milliseconds kInstanceSettle{1500};

std::chrono::milliseconds to_ms(double seconds) {
  return std::chrono::milliseconds(static_cast<std::int64_t>(seconds * 1e3));
}

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

// The spy's reader QoS: best effort, KEEP_LAST(1), volatile, so it never slows a writer. State
// topics (calibration, keyframes, map, corrections) are transient-local: a volatile best-effort
// tap would never see state published before it started, so echo asks for the history; a
// keep-last reader acknowledges on receipt and still cannot throttle the writer.
runtime::Qos spy_qos(runtime::QosRole role, bool want_history) {
  runtime::Qos qos(runtime::QosRole::kSpy);
  const bool state_topic = role == runtime::QosRole::kCalibration || role == runtime::QosRole::kKeyframes ||
                           role == runtime::QosRole::kMapState || role == runtime::QosRole::kCorrections;
  if (want_history && state_topic) qos.reliable(std::chrono::milliseconds(0)).transient_local(1);
  return qos;
}

class TimeoutGuard {
 public:
  TimeoutGuard(double timeout_s, std::string topic) : timeout_s_(timeout_s), topic_(std::move(topic)) { reset(); }
  void reset() { last_ = Clock::now(); }
  // `matched_writers`: writers the spy's reader is matched with now. A matched writer that sends
  // nothing (a paused replay) is a different problem from no writer at all.
  void check(int domain, int matched_writers) const {
    if (timeout_s_ > 0.0 && Clock::now() - last_ >= to_ms(timeout_s_)) {
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%g", timeout_s_);
      if (matched_writers > 0) {
        throw std::runtime_error("no sample on '" + topic_ + "' within " + seconds + " s, although " +
                                 std::to_string(matched_writers) +
                                 (matched_writers == 1 ? " writer is" : " writers are") +
                                 " matched: the writer is silent (paused, waiting for its input, or publishing "
                                 "only on change)");
      }
      throw std::runtime_error("no sample on '" + topic_ + "' within " + seconds +
                               " s and no writer matched (is a "
                               "writer running on domain " +
                               std::to_string(domain) + " with the same --namespace?)");
    }
  }

 private:
  double timeout_s_;
  std::string topic_;
  Clock::time_point last_;
};

// Why a list may be empty although a run is up: DDS Security hides a secure run from a plain
// participant entirely, and a plain run from a secure one (docs/security.md).
std::string empty_domain_hint() {
  const std::filesystem::path identity = runtime::security_identity_from_env();
  if (identity.empty()) {
    return "hint: a secure run (DDS Security) is invisible to a plain spy; give the spy the run's identity: " +
           std::string(runtime::kSecurityEnv) + "=DIR/identities/spy heslam-spy list (docs/security.md)";
  }
  return "hint: this spy is secure (" + std::string(runtime::kSecurityEnv) + "=" + identity.string() +
         "): it sees only runs made with that folder's certificates, never a plain run; unset " +
         runtime::kSecurityEnv + " to look for one (docs/security.md)";
}

int run_list(const runtime::Participant& participant, const SpyOptions& options) {
  struct Row {
    std::set<std::string> types;
    int writers = 0;
    int readers = 0;
  };
  std::map<std::string, Row> rows;
  for (const DiscoveredEndpoint& endpoint : discover_endpoints(participant, to_ms(options.wait_s))) {
    Row& row = rows[endpoint.topic];
    row.types.insert(endpoint.type);
    (endpoint.is_writer ? row.writers : row.readers) += 1;
  }
  if (rows.empty()) {
    std::cout << "no topics on domain " << participant.domain_id() << " (listened " << options.wait_s << " s)\n"
              << empty_domain_hint() << "\n";
    return 0;
  }
  std::size_t width = 5;
  std::size_t type_width = 32;  // heslam's own type names fit; ROS 2 ones (via the bridge) are longer
  std::map<std::string, std::string> types_of;
  for (const auto& [topic, row] : rows) {
    width = std::max(width, topic.size());
    std::string types;
    for (const std::string& type : row.types) types += (types.empty() ? "" : " | ") + type;
    type_width = std::max(type_width, types.size());
    types_of[topic] = types;
  }
  std::printf("%-*s  %-*s %7s %7s\n", static_cast<int>(width), "TOPIC", static_cast<int>(type_width), "TYPE", "WRITERS",
              "READERS");
  for (const auto& [topic, row] : rows) {
    std::printf("%-*s  %-*s %7d %7d\n", static_cast<int>(width), topic.c_str(), static_cast<int>(type_width),
                types_of[topic].c_str(), row.writers, row.readers);
  }
  return 0;
}

int run_info(const runtime::Participant& participant, const ResolvedTopic& topic, const SpyOptions& options) {
  std::vector<DiscoveredEndpoint> writers;
  std::vector<DiscoveredEndpoint> readers;
  std::set<std::string> types;
  for (DiscoveredEndpoint& endpoint : discover_endpoints(participant, to_ms(options.wait_s))) {
    if (endpoint.topic != topic.full_name) continue;
    types.insert(endpoint.type);
    (endpoint.is_writer ? writers : readers).push_back(std::move(endpoint));
  }
  std::cout << "topic: " << topic.full_name << "\n";
  std::cout << "type: " << topic.type_name << " (role " << runtime::to_string(topic.role) << ")\n";
  auto print = [](const char* title, const std::vector<DiscoveredEndpoint>& endpoints, bool is_writer) {
    std::cout << title << ": " << endpoints.size() << "\n";
    for (const DiscoveredEndpoint& endpoint : endpoints) {
      std::cout << "  - " << endpoint.participant << "  " << describe(endpoint.qos, is_writer) << "\n";
    }
  };
  print("writers", writers, true);
  print("readers", readers, false);
  std::size_t problems = 0;
  if (types.size() > 1) {
    std::string list;
    for (const std::string& type : types) list += (list.empty() ? "" : ", ") + type;
    std::cout << "incompatible: endpoints disagree on the type: " << list << "\n";
    ++problems;
  }
  for (const DiscoveredEndpoint& writer : writers) {
    for (const DiscoveredEndpoint& reader : readers) {
      for (const std::string& reason : incompatibilities(writer.qos, reader.qos)) {
        std::cout << "incompatible: writer (" << writer.participant << ") -> reader (" << reader.participant
                  << "): " << reason << "\n";
        ++problems;
      }
    }
  }
  if (problems == 0) std::cout << "all writer/reader pairs are QoS-compatible\n";
  return 0;
}

template <runtime::Message T>
int echo_each_instance(const runtime::Participant& participant, runtime::Reader<T>& reader, runtime::WaitSet& waitset,
                       TimeoutGuard& timeout, const FormatOptions& format) {
  std::set<dds_instance_handle_t> seen;
  auto last_new_instance = Clock::now();
  while (seen.empty() || Clock::now() - last_new_instance < kInstanceSettle) {
    const runtime::Wake wake = waitset.wait(kWaitSlice);
    if (wake == runtime::Wake::kShutdown) break;
    if (wake != runtime::Wake::kData) {
      if (seen.empty()) timeout.check(participant.domain_id(), reader.matched_writers());
      continue;
    }
    for (auto& received : reader.take()) {
      if (!received.info.valid_data || !seen.insert(received.info.instance_handle).second) continue;
      timeout.reset();
      last_new_instance = Clock::now();
      std::cout << format_message(*received.sample, format) << "---\n" << std::flush;
    }
  }
  if (!seen.empty())
    std::cout << "# " << seen.size() << (seen.size() == 1 ? " instance" : " instances") << ", one sample each\n";
  return 0;
}

template <runtime::Message T>
int run_echo(const runtime::Participant& participant, const ResolvedTopic& topic, const SpyOptions& options) {
  runtime::Reader<T> reader(participant, runtime::TopicSpec<T>{topic.full_name, topic.role}, spy_qos(topic.role, true));
  runtime::WaitSet waitset(participant);
  waitset.attach(reader);
  TimeoutGuard timeout(options.timeout_s, topic.full_name);
  FormatOptions format;
  format.full = options.full;
  // --once on a keyed topic (status of every component, every keyframe): one sample per instance.
  if (options.once && runtime::MessageTraits<T>::descriptor()->m_nkeys > 0) {
    return echo_each_instance(participant, reader, waitset, timeout, format);
  }
  std::size_t printed = 0;
  while (options.count == 0 || printed < options.count) {
    const runtime::Wake wake = waitset.wait(kWaitSlice);
    if (wake == runtime::Wake::kShutdown) break;
    if (wake != runtime::Wake::kData) {
      timeout.check(participant.domain_id(), reader.matched_writers());
      continue;
    }
    for (auto& received : reader.take()) {
      timeout.reset();
      if (received.info.valid_data) {
        std::cout << format_message(*received.sample, format);
      } else {
        std::cout << format_instance_end(*received.sample, received.info.disposed);
      }
      std::cout << "---\n" << std::flush;
      if (options.count != 0 && ++printed >= options.count) break;
    }
  }
  return 0;
}

void print_rate(const RateStats& stats) {
  std::printf("average rate: %.3f\n\tmin: %.3fs max: %.3fs std dev: %.5fs window: %zu\n", stats.rate_hz,
              stats.min_period_s, stats.max_period_s, stats.std_period_s, stats.periods + 1);
  std::fflush(stdout);
}

std::string megabytes(double bytes) {
  char text[32];
  if (bytes >= 1e6) {
    std::snprintf(text, sizeof(text), "%.2f MB", bytes / 1e6);
  } else if (bytes >= 1e3) {
    std::snprintf(text, sizeof(text), "%.2f KB", bytes / 1e3);
  } else {
    std::snprintf(text, sizeof(text), "%.0f B", bytes);
  }
  return text;
}

void print_bandwidth(const BandwidthStats& stats) {
  std::printf("%s/s from %zu messages\n\tmessage size mean: %s min: %s max: %s\n", megabytes(stats.bytes_per_s).c_str(),
              stats.samples, megabytes(stats.mean_bytes).c_str(),
              megabytes(static_cast<double>(stats.min_bytes)).c_str(),
              megabytes(static_cast<double>(stats.max_bytes)).c_str());
  std::fflush(stdout);
}

// hz and bw: serialized samples (dds_takecdr) are counted, never deserialized.
template <runtime::Message T>
int run_rate(const runtime::Participant& participant, const ResolvedTopic& topic, const SpyOptions& options) {
  runtime::Reader<T> reader(participant, runtime::TopicSpec<T>{topic.full_name, topic.role},
                            spy_qos(topic.role, false));
  runtime::WaitSet waitset(participant);
  waitset.attach(reader);
  TimeoutGuard timeout(options.timeout_s, topic.full_name);
  ArrivalWindow window(options.window);
  const bool hz = options.command == SpyCommand::kHz;
  auto report = [&] {
    if (hz && window.size() >= 2) print_rate(window.rate());
    if (!hz && window.size() >= 1) print_bandwidth(window.bandwidth());
  };
  std::size_t received = 0;
  bool seen_first = false;
  auto next_report = Clock::now() + kReportPeriod;
  for (;;) {
    const runtime::Wake wake = waitset.wait(kWaitSlice);
    if (wake == runtime::Wake::kShutdown) break;
    if (wake == runtime::Wake::kData) {
      ddsi_serdata* serdata = nullptr;
      dds_sample_info_t info{};
      while (dds_takecdr(reader.handle(), &serdata, 1, &info, DDS_ANY_STATE) > 0) {
        const std::int64_t arrival_ns = now_ns();
        // The first sample after matching may wait in the reader cache while the spy finishes
        // starting: its take time is not its arrival time, so it is left out of the statistics.
        if (info.valid_data && !seen_first) {
          seen_first = true;
        } else if (info.valid_data) {
          window.add(arrival_ns, ddsi_serdata_size(serdata));
          ++received;
          timeout.reset();
        }
        ddsi_serdata_unref(serdata);
        serdata = nullptr;
      }
    } else {
      timeout.check(participant.domain_id(), reader.matched_writers());
    }
    if (options.count != 0 && received >= options.count) break;
    if (Clock::now() >= next_report) {
      next_report += kReportPeriod;
      report();
      if (options.once && window.size() >= 2) return 0;
    }
  }
  report();
  return 0;
}

}  // namespace

int run_spy(const runtime::CommonArgs& common, const SpyOptions& options) {
  const runtime::Participant participant({.domain_id = common.domain_id, .dds_config = common.dds_config});
  if (options.command == SpyCommand::kList) return run_list(participant, options);
  const ResolvedTopic topic = resolve_topic(options.topic, common.ns);
  if (options.command == SpyCommand::kInfo) return run_info(participant, topic, options);
  int code = 0;
  with_message_type(topic.type_name, [&]<typename T>(std::type_identity<T>) {
    code = options.command == SpyCommand::kEcho ? run_echo<T>(participant, topic, options)
                                                : run_rate<T>(participant, topic, options);
  });
  return code;
}

}  // namespace heslam
