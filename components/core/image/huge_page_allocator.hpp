// A cv::Mat allocator that backs large images and tables with 2 MB pages where the kernel allows it
// (transparent huge pages in "madvise" mode, Debian's default): a frame's working set (remap tables,
// images) then needs a few TLB entries instead of hundreds. A frontend paced by its camera sleeps
// between frames while other processes (mapper, loop closer, other VMs on the host) take the cores
// and their TLBs; with 4 KB pages each frame starts with hundreds of page walks, and the hardware
// prefetchers stop at every 4 KB boundary. Measured in docs/benchmarks.md ("Equalization on both
// threads and the camera-paced gap").
#pragma once

#include <opencv2/core.hpp>

namespace heslam {

// The process's one huge-page allocator (it lives as long as the process, as cv::Mat allocators
// must). Allocations of at least kHugePageMinBytes are rounded up to whole 2 MB pages, aligned to
// 2 MB and advised MADV_HUGEPAGE; smaller ones come from OpenCV's own allocator. Without huge pages
// (THP "never", another OS) it is still correct, only ordinary pages.
cv::MatAllocator* huge_page_allocator();

// Allocations below this size stay on ordinary pages: rounding them up to 2 MB would waste more
// memory than their TLB misses cost.
inline constexpr std::size_t kHugePageMinBytes = std::size_t{256} << 10;

// (Re)allocates `mat` as rows x cols of `type` with the huge-page allocator, unless it already has
// that size and type (its contents are then kept).
void create_in_huge_pages(cv::Mat& mat, int rows, int cols, int type);

}  // namespace heslam
