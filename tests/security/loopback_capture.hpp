// A capture of the UDP datagrams one DDS domain receives (all of its ports), through a raw socket, as
// tcpdump would see them: counts datagrams and bytes and those whose payload holds the test pattern.
// Needs CAP_NET_RAW (root); error() says why not otherwise, for a GTEST_SKIP.
#pragma once

#include <netinet/in.h>
#include <netinet/ip.h>
#include <netinet/udp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "secure_pattern.hpp"
#include "test_support.hpp"

namespace heslam::test {

// Cyclone's default port mapping: domain d owns ports 7400 + 250 d ... + 249 (PB 7400, DG 250).
inline constexpr int kCyclonePortBase = 7400;
inline constexpr int kCyclonePortsPerDomain = 250;

// A test domain for a capture (reserve_test_domain, tests/support/test_support.hpp), among the ids whose
// ports lie below the kernel's ephemeral ports (32768 on: domain 101's 7400 + 250 * 101 = 32650 reaches
// them): there, a socket another process (a parallel test) binds to a kernel-chosen port may land in the
// captured range, and its plain image datagrams looked like this domain's (SecureDds's positive control
// failed once in a full suite, 1 in 935).
inline constexpr int kLastCaptureDomain = (32768 - kCyclonePortBase) / kCyclonePortsPerDomain - 1;  // 100
inline int capture_domain_id() {
  static const int domain_id = reserve_test_domain(static_cast<int>(getpid() % kLastCaptureDomain), kLastCaptureDomain);
  return domain_id;
}

class LoopbackCapture {
 public:
  explicit LoopbackCapture(int domain_id)
      : first_port_(kCyclonePortBase + kCyclonePortsPerDomain * domain_id),
        last_port_(first_port_ + kCyclonePortsPerDomain - 1) {
    fd_ = ::socket(AF_INET, SOCK_RAW | SOCK_CLOEXEC, IPPROTO_UDP);
    if (fd_ < 0) {
      error_ = std::string("cannot open a raw UDP socket (needs root / CAP_NET_RAW): ") + std::strerror(errno);
      return;
    }
    // 8 MB: image fragments arrive in bursts, and a raw socket also receives every other domain's
    // datagrams (a parallel suite). SO_RCVBUF is capped at net.core.rmem_max (often 208 KB), which lost
    // image datagrams under load; SO_RCVBUFFORCE (root, as the raw socket itself) is not.
    const int buffer_bytes = 8 << 20;
    if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &buffer_bytes, sizeof buffer_bytes) != 0) {
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &buffer_bytes, sizeof buffer_bytes);
    }
    thread_ = std::thread([this] { loop(); });
  }
  ~LoopbackCapture() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) ::close(fd_);
  }
  LoopbackCapture(const LoopbackCapture&) = delete;
  LoopbackCapture& operator=(const LoopbackCapture&) = delete;

  const std::string& error() const { return error_; }
  long datagrams() const { return datagrams_; }
  long payload_bytes() const { return payload_bytes_; }
  long datagrams_with_pattern() const { return with_pattern_; }

 private:
  void loop() {
    std::vector<uint8_t> packet(70000);
    while (!stop_) {
      pollfd fds{fd_, POLLIN, 0};
      if (::poll(&fds, 1, 50) <= 0) continue;
      const ssize_t n = ::recv(fd_, packet.data(), packet.size(), 0);
      if (n < static_cast<ssize_t>(sizeof(iphdr))) continue;
      const auto* ip = reinterpret_cast<const iphdr*>(packet.data());
      const std::size_t ip_bytes = static_cast<std::size_t>(ip->ihl) * 4;
      if (static_cast<std::size_t>(n) < ip_bytes + sizeof(udphdr)) continue;
      const auto* udp = reinterpret_cast<const udphdr*>(packet.data() + ip_bytes);
      const int port = ntohs(udp->dest);
      if (port < first_port_ || port > last_port_) continue;
      const std::span<const uint8_t> payload(packet.data() + ip_bytes + sizeof(udphdr),
                                             static_cast<std::size_t>(n) - ip_bytes - sizeof(udphdr));
      ++datagrams_;
      payload_bytes_ += static_cast<long>(payload.size());
      if (has_pattern(payload)) ++with_pattern_;
    }
  }

  int first_port_;
  int last_port_;
  int fd_ = -1;
  std::string error_;
  std::atomic<bool> stop_{false};
  std::atomic<long> datagrams_{0};
  std::atomic<long> payload_bytes_{0};
  std::atomic<long> with_pattern_{0};
  std::thread thread_;
};

}  // namespace heslam::test
