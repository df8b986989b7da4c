// cv::MatAllocator over 2 MB-aligned memory advised MADV_HUGEPAGE.
#include "components/core/image/huge_page_allocator.hpp"

#include <cstdlib>
#include <memory>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace heslam {
namespace {

constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;  // x86-64's transparent huge page

class HugePageAllocator final : public cv::MatAllocator {
 public:
  cv::UMatData* allocate(int dims, const int* sizes, int type, void* data, std::size_t* step, cv::AccessFlag flags,
                         cv::UMatUsageFlags usage) const override {
    // User data (a header over foreign memory) and small mats: OpenCV's own allocator.
    std::size_t total = CV_ELEM_SIZE(type);
    for (int i = 0; i < dims; ++i) total *= static_cast<std::size_t>(sizes[i]);
    if (data || total < kHugePageMinBytes) {
      return cv::Mat::getStdAllocator()->allocate(dims, sizes, type, data, step, flags, usage);
    }
    if (step) {  // continuous: each dimension's step is the product of the element size and the later sizes
      std::size_t inner = CV_ELEM_SIZE(type);
      for (int i = dims - 1; i >= 0; --i) {
        step[i] = inner;
        inner *= static_cast<std::size_t>(sizes[i]);
      }
    }
    const std::size_t rounded = (total + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
    void* memory = std::aligned_alloc(kHugePageBytes, rounded);
    if (memory == nullptr) CV_Error(cv::Error::StsNoMem, "huge_page_allocator: out of memory");
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(memory, rounded, MADV_HUGEPAGE);  // advice only: without THP the pages stay 4 KB
#endif
    // OpenCV's interface hands UMatData out by pointer and takes it back in deallocate().
    auto u = std::make_unique<cv::UMatData>(this);
    u->data = u->origdata = static_cast<uchar*>(memory);
    u->size = total;
    return u.release();
  }

  bool allocate(cv::UMatData* u, cv::AccessFlag, cv::UMatUsageFlags) const override { return u != nullptr; }

  void deallocate(cv::UMatData* u) const override {
    if (u == nullptr) return;
    const std::unique_ptr<cv::UMatData> owned(u);
    if (!(u->flags & cv::UMatData::USER_ALLOCATED)) std::free(u->origdata);
    u->origdata = nullptr;
  }
};

}  // namespace

cv::MatAllocator* huge_page_allocator() {
  static HugePageAllocator allocator;  // never destroyed before the mats it made (static storage, first use)
  return &allocator;
}

void create_in_huge_pages(cv::Mat& mat, int rows, int cols, int type) {
  if (mat.rows == rows && mat.cols == cols && mat.type() == type && mat.allocator == huge_page_allocator()) return;
  cv::Mat fresh;
  fresh.allocator = huge_page_allocator();
  fresh.create(rows, cols, type);
  mat = fresh;
}

}  // namespace heslam
