// Giving the heap's free memory back to the system after a burst of allocations (a global BA, a loop
// correction): glibc keeps what a thread freed in that thread's arena for reuse, so the resident set of
// a process that once ran a large solver on a worker thread stayed at its peak for the rest of the run
// (the loop closer's +40-100 MiB after the first loop, issue 41, docs/benchmarks.md "Long runs").
#pragma once

#include <cstdint>

namespace heslam::runtime {

class Stats;

struct HeapRelease {
  std::uint64_t rss_before_bytes = 0;  // resident_bytes() before and after (0 if unknown)
  std::uint64_t rss_after_bytes = 0;
  double elapsed_ms = 0.0;  // the call's wall time
  std::uint64_t released_bytes() const {
    return rss_before_bytes > rss_after_bytes ? rss_before_bytes - rss_after_bytes : 0;
  }
};

// Returns the free pages of every malloc arena to the system (malloc_trim(0); a no-op without glibc).
// Cost: a walk over the arenas, a few ms for a heap of 100 MiB; call it after the burst, not per frame.
// With `stats`: counted as heap_released_kib and timed as stage heap_release.
HeapRelease release_free_heap(Stats* stats = nullptr);

}  // namespace heslam::runtime
