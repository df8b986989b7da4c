// heslam-test-talker: the smallest real component, for supervisor tests. Publishes its status and a
// "ticks" counter; optionally exits after a while with a chosen code, or ignores SIGTERM (to test
// the supervisor's SIGKILL escalation), or holds an odometry writer (`data_writer: true`: what makes
// it a run's writer to the supervisor's domain check, which ignores status-only observers).
#include <signal.h>

#include <chrono>
#include <optional>

#include "runtime/component.hpp"
#include "runtime/messages.hpp"
#include "runtime/writer.hpp"

namespace heslam::test {

class Talker : public runtime::Component {
 public:
  explicit Talker(const runtime::CommonArgs& args) : Component("talker", args) {}

 private:
  void configure(const runtime::Config& config) override {
    exit_after_s_ = config.get_double("exit_after_s", 0.0, 0.0, 3600.0);  // 0: run until told to stop
    exit_code_ = config.get_int("exit_code", 0, 0, 255);
    if (config.get_bool("ignore_sigterm", false)) signal(SIGTERM, SIG_IGN);
    if (config.get_bool("data_writer", false)) odometry_writer_.emplace(participant(), topics().odometry());
  }

  void run() override {
    const auto start = std::chrono::steady_clock::now();
    while (spin_once(std::chrono::milliseconds(kTickMs))) {
      stats().count("ticks");
      const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (exit_after_s_ > 0 && elapsed_s >= exit_after_s_) {
        log().info("exiting with code ", exit_code_, " as configured");
        std::exit(exit_code_);
      }
    }
    log().info("shutting down");
  }

  static constexpr int kTickMs = 50;
  double exit_after_s_ = 0;
  int exit_code_ = 0;
  std::optional<runtime::Writer<msg::Odometry>> odometry_writer_;
};

}  // namespace heslam::test

int main(int argc, char** argv) { return heslam::runtime::component_main<heslam::test::Talker>(argc, argv, "talker"); }
