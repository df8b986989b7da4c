// The huge-page cv::Mat allocator: large mats 2 MB-aligned and usable like any other (copies share,
// release frees), small ones from OpenCV's allocator, create_in_huge_pages keeps a matching mat.
#include <cstdint>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "components/core/image/huge_page_allocator.hpp"

namespace heslam {
namespace {

constexpr std::uintptr_t kTwoMegabytes = std::uintptr_t{2} << 20;

TEST(HugePageAllocator, LargeMatsAreTwoMegabyteAlignedAndBehaveAsMats) {
  cv::Mat image;
  create_in_huge_pages(image, 480, 752, CV_8UC1);  // a EuRoC image, 361 KB
  ASSERT_EQ(image.allocator, huge_page_allocator());
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(image.data) % kTwoMegabytes, 0u);
  EXPECT_TRUE(image.isContinuous());
  image.setTo(7);
  image.at<std::uint8_t>(479, 751) = 9;

  const std::uint8_t* data = image.data;
  create_in_huge_pages(image, 480, 752, CV_8UC1);  // same size and type: kept, contents too
  EXPECT_EQ(image.data, data);
  EXPECT_EQ(image.at<std::uint8_t>(479, 751), 9);

  cv::Mat shared = image;  // a copy shares the memory and keeps it alive
  image.release();
  EXPECT_EQ(shared.at<std::uint8_t>(0, 0), 7);
  cv::Mat copy;
  shared.copyTo(copy);
  EXPECT_EQ(cv::countNonZero(copy != shared), 0);

  cv::Mat table;
  create_in_huge_pages(table, 480, 752, CV_16SC2);  // a remap table, 1.4 MB
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(table.data) % kTwoMegabytes, 0u);
  table.setTo(cv::Scalar(-3, 4));
  EXPECT_EQ(table.at<cv::Vec2s>(100, 100), cv::Vec2s(-3, 4));
  create_in_huge_pages(table, 100, 100, CV_16SC2);  // another size: a new allocation, small
  EXPECT_EQ(table.size(), cv::Size(100, 100));
  EXPECT_EQ(table.type(), CV_16SC2);
}

TEST(HugePageAllocator, SmallMatsComeFromOpenCvsAllocator) {
  cv::Mat small;
  create_in_huge_pages(small, 16, 16, CV_8UC1);
  small.setTo(1);
  EXPECT_EQ(cv::countNonZero(small), 256);
  ASSERT_NE(small.u, nullptr);
  EXPECT_EQ(small.u->currAllocator, cv::Mat::getStdAllocator());
}

}  // namespace
}  // namespace heslam
