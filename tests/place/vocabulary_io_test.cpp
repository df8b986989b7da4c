// Vocabulary files: DBoW2 text and heslam binary round trips, and the one-line errors for malformed,
// truncated and corrupted files.
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "components/core/place/vocabulary_io.hpp"
#include "components/core/place/vocabulary_training.hpp"
#include "test_support.hpp"
#include "vocabulary_test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

Vocabulary trained_vocabulary() {
  const auto clusters = test::clustered_descriptors(30, 40, 20, 9);
  std::vector<std::vector<Descriptor>> images(10);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    for (std::size_t i = 0; i < clusters[c].size(); ++i) images[(c * 3 + i) % images.size()].push_back(clusters[c][i]);
  }
  VocabularyTrainingOptions options;
  options.branching = 5;
  options.levels = 3;
  return train_vocabulary(images, options);
}

std::vector<Descriptor> query_descriptors() {
  std::vector<Descriptor> out;
  for (const auto& cluster : test::clustered_descriptors(30, 5, 30, 9))
    out.insert(out.end(), cluster.begin(), cluster.end());
  return out;
}

void write_file(const fs::path& path, const std::string& content) { std::ofstream(path, std::ios::binary) << content; }

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The message of the exception `load` throws, or "" when it does not throw.
template <typename Load>
std::string error_of(Load&& load) {
  try {
    load();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::string node_line(const std::string& parent, const std::string& is_leaf, int bytes = 32,
                      const std::string& weight = "0.5") {
  std::string line = parent + " " + is_leaf;
  for (int i = 0; i < bytes; ++i) line += " 7";
  return line + " " + weight + "\n";
}

TEST(VocabularyText, RoundTripGivesTheSameVocabularyAndTransforms) {
  test::ScratchDir dir("vocab_text");
  const Vocabulary original = trained_vocabulary();
  const fs::path path = dir.path() / "voc.txt";
  save_vocabulary_text(path, original);
  EXPECT_FALSE(fs::exists(dir.path() / "voc.txt.tmp"));
  EXPECT_EQ(detect_vocabulary_format(path), VocabularyFileFormat::kDbow2Text);
  const Vocabulary loaded = load_vocabulary(path);
  test::expect_same_vocabulary(original, loaded);
  test::expect_same_transform(original, loaded, query_descriptors(), 1);
  // DBoW2's header spelling.
  EXPECT_EQ(read_file(path).substr(0, 8), "5 3  0 0");
}

TEST(VocabularyText, ReadsTheDbow2Layout) {
  test::ScratchDir dir("vocab_dbow2");
  const fs::path path = dir.path() / "tiny.txt";
  write_file(path, "2 1  0 0\n" + node_line("0", "1", 32, "0.693147") + node_line("0", "1", 32, "0"));
  const Vocabulary vocabulary = load_vocabulary(path);
  EXPECT_EQ(vocabulary.word_count(), 2u);
  EXPECT_FLOAT_EQ(vocabulary.word_weight(0), 0.693147f);
  EXPECT_EQ(vocabulary.node_records()[0].descriptor[31], 7);
}

TEST(VocabularyText, MalformedFilesNameTheLine) {
  test::ScratchDir dir("vocab_bad_text");
  const fs::path path = dir.path() / "bad.txt";
  const std::string prefix = "vocabulary " + path.string() + ":";
  struct Case {
    std::string content;
    std::string expected;  // after "vocabulary <path>:"
  };
  const std::string inner = node_line("0", "0");
  const std::vector<Case> cases = {
      {"", "1: empty file"},
      {"10 6 0\n", "1: expected header"},
      {"10 six 0 0\n", "1: expected header 'k L scoring weighting', 'six' is not an integer"},
      {"10 6 0 9\n" + inner, "1: weighting 9"},
      {"2 2 0 0\n" + inner + node_line("1", "1", 20, ""), "3: node line has 22 fields"},
      {"2 2 0 0\n" + inner + node_line("1", "1", 32, "x1"), "3: weight 'x1'"},
      {"2 2 0 0\n" + inner + "1 1 7 7 abc" + node_line("", "", 29).substr(1), "3: descriptor byte 2 'abc'"},
      {"2 2 0 0\n" + inner + node_line("1", "1", 32, ""), "3: node line has 34 fields"},
      {"2 2 0 0\n" + node_line("5", "1"), "2: parent 5 of node 1 is not an earlier node"},
      {"2 2 0 0\n" + node_line("0", "1") + node_line("1", "1"), "3: parent 1 is a leaf"},
      {"2 2 0 0\n" + node_line("0", "2"), "2: is_leaf '2'"},
      {"2 2 0 0\n", "2: no nodes"},
      // Truncated at a line end: node 1 is inner and has no children.
      {"2 2 0 0\n" + inner, "2: node 1 is an inner node without children"},
      // Truncated inside a line.
      {"2 2 0 0\n" + inner + node_line("1", "1").substr(0, 30), "3: node line has"},
  };
  for (const Case& c : cases) {
    write_file(path, c.content);
    const std::string error = error_of([&] { load_vocabulary_text(path); });
    EXPECT_EQ(error.rfind(prefix + c.expected, 0), 0u) << "content:\n" << c.content << "\nerror: " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
  EXPECT_EQ(error_of([&] { load_vocabulary(dir.path() / "missing.txt"); }),
            "vocabulary " + (dir.path() / "missing.txt").string() + ": cannot open file");
}

TEST(VocabularyBinary, RoundTripGivesTheSameVocabularyAndTransforms) {
  test::ScratchDir dir("vocab_binary");
  const Vocabulary original = trained_vocabulary();
  const fs::path path = dir.path() / "voc.hvoc";
  save_vocabulary_binary(path, original);
  EXPECT_EQ(detect_vocabulary_format(path), VocabularyFileFormat::kHeslamBinary);
  EXPECT_EQ(fs::file_size(path), 40 + 41 * (original.node_count() - 1) + 8);
  const Vocabulary loaded = load_vocabulary(path);
  test::expect_same_vocabulary(original, loaded);
  test::expect_same_transform(original, loaded, query_descriptors(), 2);
  // text -> binary -> text gives the same text.
  save_vocabulary_text(dir.path() / "a.txt", original);
  save_vocabulary_binary(dir.path() / "b.hvoc", load_vocabulary(dir.path() / "a.txt"));
  save_vocabulary_text(dir.path() / "c.txt", load_vocabulary(dir.path() / "b.hvoc"));
  EXPECT_EQ(read_file(dir.path() / "a.txt"), read_file(dir.path() / "c.txt"));
}

TEST(VocabularyBinary, CorruptedOrTruncatedFilesFailWithOneLine) {
  test::ScratchDir dir("vocab_bad_binary");
  const fs::path good = dir.path() / "good.hvoc";
  save_vocabulary_binary(good, test::tiny_vocabulary());
  const std::string bytes = read_file(good);
  const fs::path path = dir.path() / "bad.hvoc";
  const std::string prefix = "vocabulary " + path.string() + ": ";
  auto expect_error = [&](const std::string& content, const std::string& expected) {
    write_file(path, content);
    const std::string error = error_of([&] { load_vocabulary(path); });
    EXPECT_EQ(error.rfind(prefix + expected, 0), 0u) << "error: " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  };
  std::string flipped = bytes;
  flipped[60] ^= 0x10;
  expect_error(flipped, "checksum mismatch");
  expect_error(bytes.substr(0, bytes.size() - 9), "size ");
  expect_error(bytes.substr(0, bytes.size() - 9), "size " + std::to_string(bytes.size() - 9));
  expect_error(bytes + "x", "size ");
  expect_error(bytes.substr(0, 20), "truncated");
  std::string version = bytes;
  version[8] = 2;
  expect_error(version, "format version 2");
  std::string count = bytes;
  count[32] = 100;  // node count 100: file too short for it
  expect_error(count, "size ");
  std::string magic = bytes;
  magic[0] = 'X';
  EXPECT_EQ(error_of([&] {
              write_file(path, magic);
              load_vocabulary_binary(path);
            }),
            prefix + "not a heslam binary vocabulary (bad magic)");
}

}  // namespace
}  // namespace heslam
