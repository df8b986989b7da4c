// replace_file: the file is either the old complete one or the new complete one; a failed replacement
// leaves the old file and no temporary file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "runtime/atomic_file.hpp"
#include "test_support.hpp"

namespace heslam::runtime {
namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(ReplaceFile, ReplacesTheContentsAndLeavesNoTemporaryFile) {
  const test::ScratchDir dir("replace_file");
  const auto path = dir.path() / "state.txt";
  replace_file_contents(path, "first\n");
  EXPECT_EQ(read_text(path), "first\n");
  replace_file_contents(path, "second\n", /*sync=*/false);
  EXPECT_EQ(read_text(path), "second\n");
  replace_file(path, [](const std::filesystem::path& temp) { std::ofstream(temp) << "third\n"; });
  EXPECT_EQ(read_text(path), "third\n");
  EXPECT_FALSE(std::filesystem::exists(replacement_temp_path(path)));
  EXPECT_EQ(replacement_temp_path(path), dir.path() / "state.txt.tmp");
}

TEST(ReplaceFile, AFailedWriteKeepsTheOldFileAndRemovesTheTemporaryOne) {
  const test::ScratchDir dir("replace_file_fail");
  const auto path = dir.path() / "state.txt";
  replace_file_contents(path, "old\n");
  try {
    replace_file(path, [](const std::filesystem::path& temp) {
      std::ofstream(temp) << "half of the n";
      throw std::runtime_error("disk full");
    });
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()), path.string() + ": cannot replace the file (disk full)");
  }
  EXPECT_EQ(read_text(path), "old\n");
  EXPECT_FALSE(std::filesystem::exists(replacement_temp_path(path)));
}

TEST(ReplaceFile, AFailedRenameKeepsTheOldFileAndRemovesTheTemporaryOne) {
  const test::ScratchDir dir("replace_file_rename");
  const auto path = dir.path() / "taken";
  std::filesystem::create_directories(path / "not empty");  // a folder cannot be renamed over
  try {
    replace_file_contents(path, "new\n");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()).rfind(path.string() + ": cannot replace the file (", 0), 0u) << error.what();
  }
  EXPECT_TRUE(std::filesystem::is_directory(path / "not empty"));
  EXPECT_FALSE(std::filesystem::exists(replacement_temp_path(path)));
}

TEST(ReplaceFile, AMissingFolderIsAnErrorNamingTheFile) {
  const auto path = std::filesystem::path("/proc/heslam_no_such_dir/state.txt");
  try {
    replace_file_contents(path, "x");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()).rfind(path.string() + ": cannot replace the file (", 0), 0u) << error.what();
  }
}

}  // namespace
}  // namespace heslam::runtime
