// OtherRunWatch over DDS_BUILTIN_TOPIC_DCPSPUBLICATION.
#include "runtime/supervisor/domain_check.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <utility>

#include "runtime/participant.hpp"
#include "runtime/run_id.hpp"
#include "runtime/topics.hpp"

namespace heslam::supervisor {
namespace {

constexpr int kTakeBatch = 32;
constexpr auto kPollPeriod = std::chrono::milliseconds(20);
// Topics named in a description: enough to recognise a pipeline, short enough for one line.
constexpr std::size_t kMaxNamedTopics = 3;
// --domain auto listens this long on each candidate domain.
constexpr auto kAutoListen = std::chrono::milliseconds(1000);

std::optional<std::string> run_of(const dds_builtintopic_endpoint_t& endpoint) {
  void* value = nullptr;
  size_t size = 0;
  if (endpoint.qos == nullptr || !dds_qget_userdata(endpoint.qos, &value, &size) || value == nullptr)
    return std::nullopt;
  const std::string user_data(static_cast<const char*>(value), size);
  dds_free(value);
  if (!user_data.starts_with(runtime::kRunUserDataPrefix)) return std::nullopt;
  return user_data.substr(runtime::kRunUserDataPrefix.size());
}

// Whether run "<pid>:<start time>" is a process alive on this host with that start time.
bool run_alive_here(const std::string& run) {
  const std::size_t colon = run.find(':');
  if (colon == std::string::npos) return false;
  std::ifstream stat("/proc/" + run.substr(0, colon) + "/stat");
  if (!stat) return false;
  const std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');
  std::istringstream fields(close == std::string::npos ? std::string() : text.substr(close + 1));
  std::string field;
  constexpr int kStartTimeField = 22;  // proc(5), counted from 1; fields 1-2 are before the ')'
  for (int index = 3; index <= kStartTimeField && fields >> field; ++index) {
  }
  return field == run.substr(colon + 1);
}

// Cyclone's default port mapping (Discovery/Ports, unchanged by config/cyclonedds.xml): a
// participant of index i on domain d binds Base + DomainGain * d + UnicastMetaOffset +
// ParticipantGain * i for its discovery.
constexpr int kPortBase = 7400;
constexpr int kDomainGain = 250;
constexpr int kParticipantGain = 2;
constexpr int kUnicastMetaOffset = 10;
// Indices looked at: beyond the configured MaxAutoParticipantIndex (50), up to the next domain's ports.
constexpr int kMaxIndexLooked = (kDomainGain - kUnicastMetaOffset) / kParticipantGain - 1;

// The inodes of this process's sockets (/proc/self/fd -> "socket:[N]").
std::set<std::string> own_socket_inodes() {
  std::set<std::string> inodes;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", error)) {
    std::error_code link_error;
    const std::string target = std::filesystem::read_symlink(entry.path(), link_error).string();
    if (!link_error && target.starts_with("socket:[") && target.ends_with("]")) {
      inodes.insert(target.substr(8, target.size() - 9));
    }
  }
  return inodes;
}

}  // namespace

std::optional<bool> other_participant_on_host(const Pipeline& pipeline, int domain_id) {
  // Another configuration may reach other hosts, use multicast or other ports: not told here.
  if (!pipeline.dds_config.empty()) return std::nullopt;
  if (const char* uri = std::getenv("CYCLONEDDS_URI"); uri != nullptr && *uri != '\0') return std::nullopt;
  const int first = kPortBase + kDomainGain * domain_id + kUnicastMetaOffset;
  const std::set<std::string> own = own_socket_inodes();
  bool readable = false;
  for (const char* table : {"/proc/net/udp", "/proc/net/udp6"}) {
    std::ifstream file(table);
    if (!file) continue;
    readable = true;
    std::string line;
    std::getline(file, line);  // the header
    while (std::getline(file, line)) {
      // "  sl  local_address rem_address   st tx_queue:rx_queue tr:tm->when retrnsmt   uid  timeout inode ..."
      std::istringstream fields(line);
      std::string slot, local, remote, state, queues, timer, retransmits, uid, timeout, inode;
      if (!(fields >> slot >> local >> remote >> state >> queues >> timer >> retransmits >> uid >> timeout >> inode)) {
        continue;
      }
      const std::size_t colon = local.rfind(':');
      if (colon == std::string::npos) continue;
      // Cyclone binds its receiving sockets to every address (0.0.0.0 or ::); a socket bound to one
      // address (its sending socket, 127.0.0.1 and an ephemeral port that may fall in the range) is not one.
      if (local.find_first_not_of('0') != colon) continue;
      const int port = static_cast<int>(std::strtol(local.c_str() + colon + 1, nullptr, 16));
      const int offset = port - first;
      if (offset < 0 || offset % kParticipantGain != 0 || offset / kParticipantGain > kMaxIndexLooked) continue;
      if (!own.contains(inode)) return true;
    }
  }
  if (!readable) return std::nullopt;
  return false;
}

std::optional<DomainClaim> DomainClaim::try_claim(int domain_id, const std::string& ns, std::string* holder) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "heslam-domains";
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  // Shared by every user's runs, like /tmp itself.
  std::filesystem::permissions(folder, std::filesystem::perms::all | std::filesystem::perms::sticky_bit, error);
  std::string name = std::to_string(domain_id) + "-" + ns;
  std::replace(name.begin(), name.end(), '/', '%');
  const std::filesystem::path file = folder / (name + ".lock");
  const int fd = ::open(file.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
  if (fd < 0) return DomainClaim(-1);  // no claim possible (read-only /tmp): the DDS check still runs
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (holder != nullptr) {
      char text[32] = {};
      const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
      *holder = n > 0 ? std::string(text, static_cast<std::size_t>(n)) : std::string();
    }
    ::close(fd);
    return std::nullopt;
  }
  const std::string pid = std::to_string(getpid());
  if (::ftruncate(fd, 0) == 0) [[maybe_unused]]
    const ssize_t written = ::pwrite(fd, pid.data(), pid.size(), 0);
  return DomainClaim(fd);
}

DomainClaim::DomainClaim(DomainClaim&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}

DomainClaim& DomainClaim::operator=(DomainClaim&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

DomainClaim::~DomainClaim() {
  if (fd_ >= 0) ::close(fd_);
}

OtherRunWatch::OtherRunWatch(dds_entity_t participant, std::string ns, std::string own_run)
    : prefix_(std::move(ns) + "/"), own_run_(std::move(own_run)) {
  reader_ = dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  if (reader_ < 0)
    throw std::runtime_error(std::string("cannot watch the domain's writers: ") + dds_strretcode(reader_));
  if (dds_get_guid(participant, &own_participant_) != DDS_RETCODE_OK) {
    throw std::runtime_error("cannot watch the domain's writers: no participant GUID");
  }
}

OtherRunWatch::~OtherRunWatch() {
  if (reader_ > 0) dds_delete(reader_);
}

bool OtherRunWatch::poll() {
  bool found = false;
  void* samples[kTakeBatch] = {};
  dds_sample_info_t infos[kTakeBatch];
  for (;;) {
    const dds_return_t n = dds_take(reader_, samples, infos, kTakeBatch, kTakeBatch);
    if (n <= 0) break;
    for (dds_return_t i = 0; i < n; ++i) {
      const auto& endpoint = *static_cast<const dds_builtintopic_endpoint_t*>(samples[i]);
      const std::vector<unsigned char> guid(endpoint.key.v, endpoint.key.v + sizeof endpoint.key.v);
      if (infos[i].instance_state != DDS_IST_ALIVE) {
        alive_.erase(guid);
        continue;
      }
      if (!infos[i].valid_data) continue;
      if (std::memcmp(endpoint.participant_key.v, own_participant_.v, sizeof own_participant_.v) == 0) continue;
      if (endpoint.topic_name == nullptr || !std::string(endpoint.topic_name).starts_with(prefix_)) continue;
      // Every heslam process reports on the status topic, observers too (a viewer or a loop closer
      // started by hand before the run): only a writer of the pipeline's data makes another run.
      if (std::string_view(endpoint.topic_name).substr(prefix_.size()) == runtime::topic_names::kStatus) continue;
      const std::optional<std::string> run = run_of(endpoint);
      if (run && *run == own_run_) continue;
      std::set<std::string>& topics = runs_[run.value_or("unknown (a writer that is not heslam's)")];
      topics.insert(endpoint.topic_name);
      alive_.insert(guid);
      found = true;
    }
    dds_return_loan(reader_, samples, n);
  }
  return found;
}

std::string OtherRunWatch::describe() const {
  std::string text;
  for (const auto& [run, topics] : runs_) {
    std::string named;
    std::size_t count = 0;
    for (const std::string& topic : topics) {
      if (count++ == kMaxNamedTopics) {
        named += ", ...";
        break;
      }
      named += (named.empty() ? "" : ", ") + topic;
    }
    text += (text.empty() ? "run " : "; run ") + run + " (writers of " + named + ")";
  }
  return text;
}

bool OtherRunWatch::all_runs_ended_here() const {
  for (const auto& [run, topics] : runs_) {
    if (run_alive_here(run) || run.find(':') == std::string::npos) return false;
  }
  return true;
}

std::optional<std::string> other_run_alive(OtherRunWatch& watch, std::chrono::milliseconds window,
                                           std::chrono::milliseconds stale_window) {
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    watch.poll();
    const auto elapsed = std::chrono::steady_clock::now() - start;
    if (watch.seen()) {
      // A killed run's writers outlive it by their lease: wait for them to go before calling the
      // domain busy, unless the run is alive (here) or may be (another host).
      if (watch.alive() == 0) return std::nullopt;
      if (!watch.all_runs_ended_here() || elapsed >= stale_window) return watch.describe();
    } else if (elapsed >= window) {
      return std::nullopt;
    }
    std::this_thread::sleep_for(kPollPeriod);
  }
}

int free_domain(const Pipeline& pipeline, std::optional<DomainClaim>& claim) {
  std::vector<int> candidates{pipeline.domain_id};
  for (int domain = 1; domain <= runtime::kMaxDomainId; ++domain) {
    if (domain != pipeline.domain_id) candidates.push_back(domain);
  }
  if (pipeline.domain_id != 0) candidates.push_back(0);
  for (const int domain : candidates) {
    std::optional<DomainClaim> candidate = DomainClaim::try_claim(domain, pipeline.ns);
    if (!candidate) continue;
    if (other_participant_on_host(pipeline, domain) == false) {
      claim = std::move(candidate);  // no one else there to listen for
      return domain;
    }
    try {
      const runtime::Participant participant(runtime::ParticipantOptions{domain, pipeline.dds_config});
      OtherRunWatch watch(participant.handle(), pipeline.ns, runtime::own_run_id());
      // A killed run's writers count as busy here: another domain is as good and needs no waiting.
      if (other_run_alive(watch, kAutoListen, std::chrono::milliseconds(0))) continue;
    } catch (const std::runtime_error&) {
      continue;  // no participant there (e.g. its process slots are all taken): not free
    }
    claim = std::move(candidate);
    return domain;
  }
  throw std::runtime_error("--domain auto: every domain 0-" + std::to_string(runtime::kMaxDomainId) +
                           " is in use by another heslam run (namespace '" + pipeline.ns + "')");
}

}  // namespace heslam::supervisor
