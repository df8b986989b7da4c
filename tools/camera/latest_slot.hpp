// A one-frame handoff between a capture thread and a publishing thread, as a camera driver's
// buffer behaves: a value put while the previous one was not taken yet replaces it, and the
// replaced one is counted as dropped (never hidden).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <optional>
#include <utility>

namespace heslam {

template <typename T>
class LatestSlot {
 public:
  // Returns true when an untaken value was replaced (a dropped frame).
  bool put(T value) {
    bool dropped = false;
    {
      const std::lock_guard lock(mutex_);
      dropped = value_.has_value();
      if (dropped) ++dropped_;
      value_ = std::move(value);
    }
    ready_.notify_one();
    return dropped;
  }

  // The value, or nothing after `timeout` or once closed and empty.
  std::optional<T> take(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    ready_.wait_for(lock, timeout, [this] { return value_.has_value() || closed_; });
    std::optional<T> value = std::move(value_);
    value_.reset();
    return value;
  }

  // No more values come (the source ended); take() returns what is left, then nothing at once.
  void close() {
    {
      const std::lock_guard lock(mutex_);
      closed_ = true;
    }
    ready_.notify_all();
  }

  bool finished() const {
    const std::lock_guard lock(mutex_);
    return closed_ && !value_.has_value();
  }

  std::size_t dropped() const {
    const std::lock_guard lock(mutex_);
    return dropped_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::optional<T> value_;
  std::size_t dropped_ = 0;
  bool closed_ = false;
};

}  // namespace heslam
