// The loop closer's global bundle adjustment thread (see background_global_ba.hpp).
#include "components/loop_closer/background_global_ba.hpp"

#include <utility>

namespace heslam::loop_closer {

void BackgroundGlobalBa::start(const LoopClosing& closing, Map map, KeyframeId loop_kf) {
  abort();
  stop_ = false;
  done_ = false;
  result_.reset();
  started_ = std::chrono::steady_clock::now();
  thread_ = std::thread([this, &closing, map = std::move(map), loop_kf] {
    result_ = closing.global_bundle_adjustment(map, &stop_);
    if (result_) result_->loop_kf = loop_kf;
    done_ = true;
  });
}

bool BackgroundGlobalBa::abort() {
  if (!thread_.joinable()) return false;
  stop_ = true;
  thread_.join();
  result_.reset();
  return true;
}

BackgroundGlobalBa::Outcome BackgroundGlobalBa::collect() {
  Outcome outcome;
  if (!thread_.joinable()) return outcome;
  thread_.join();
  outcome.correction = std::move(result_);
  result_.reset();
  outcome.elapsed_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started_).count();
  return outcome;
}

}  // namespace heslam::loop_closer
