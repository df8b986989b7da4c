// release_free_heap (see heap.hpp).
#include "runtime/heap.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <chrono>

#include "runtime/stats.hpp"
#include "runtime/status.hpp"

namespace heslam::runtime {

HeapRelease release_free_heap(Stats* stats) {
  const auto started = std::chrono::steady_clock::now();
  HeapRelease release;
  release.rss_before_bytes = resident_bytes();
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
  release.rss_after_bytes = resident_bytes();
  release.elapsed_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
  if (stats != nullptr) {
    stats->record_ms("heap_release", release.elapsed_ms);
    stats->count("heap_released_kib", release.released_bytes() / 1024);
  }
  return release;
}

}  // namespace heslam::runtime
