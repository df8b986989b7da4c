// Config: defaults, typed getters, and one clear message per bad field.
#include "runtime/config.hpp"

#include <fstream>
#include <stdexcept>

#include <gtest/gtest.h>

namespace heslam::runtime {
namespace {

// The message of the exception fn throws ("" if none).
template <typename Fn>
std::string error_of(Fn fn) {
  try {
    fn();
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

TEST(Config, AbsentFieldsGiveDefaults) {
  const Config config = Config::empty();
  EXPECT_EQ(config.get_int("levels", 8, 1, 16), 8);
  EXPECT_DOUBLE_EQ(config.get_double("scale", 1.2), 1.2);
  EXPECT_TRUE(config.get_bool("parallel", true));
  EXPECT_EQ(config.get_string("mode", "global"), "global");
  EXPECT_FALSE(config.has("levels"));
  EXPECT_NO_THROW(config.reject_unknown());
}

TEST(Config, ReadsTypedAndNestedFields) {
  const Config config = Config::parse(
      "levels: 4\nscale: 1.5\nparallel: false\nmode: clahe\norb:\n  fast: [20, 7]\n  name: x\nargs: [a, 5]\n",
      "t.yaml");
  EXPECT_EQ(config.get_int("levels", 8, 1, 16), 4);
  EXPECT_DOUBLE_EQ(config.get_double("scale", 1.2, 1.0, 2.0), 1.5);
  EXPECT_FALSE(config.get_bool("parallel", true));
  EXPECT_EQ(config.get_choice("mode", "global", {"global", "clahe"}), "clahe");
  EXPECT_EQ(config.get_doubles("orb.fast", {}), (std::vector<double>{20, 7}));
  EXPECT_EQ(config.get_string("orb.name", ""), "x");
  EXPECT_EQ(config.get_strings("args", {}), (std::vector<std::string>{"a", "5"}));
  EXPECT_DOUBLE_EQ(config.get_double("levels", 0.0), 4.0);  // an integer is a fine number
  EXPECT_NO_THROW(config.reject_unknown());
}

TEST(Config, WrongTypeNamesFileFieldAndValue) {
  const Config config = Config::parse("levels: abc\nscale: 2.5\n", "frontend.yaml");
  EXPECT_EQ(error_of([&] { config.get_int("levels", 8, 1, 16); }),
            "frontend.yaml: field 'levels': expected an integer in [1, 16], got 'abc'");
  EXPECT_EQ(error_of([&] { config.get_int("scale", 8, 1, 16); }),
            "frontend.yaml: field 'scale': expected an integer in [1, 16], got 2.5");
}

// A field's bad value is quoted short: a 1 MB string is 80 characters and its size, never a 1 MB line.
TEST(Config, AHugeBadValueIsQuotedShort) {
  const Config config = Config::parse("mode: " + std::string(1 << 20, 'x') + "\n", "f.yaml");
  EXPECT_EQ(
      error_of([&] {
        config.get_choice("mode", "global", {"global", "clahe"});
      }),
      "f.yaml: field 'mode': expected one of global clahe, got '" + std::string(80, 'x') + "... (1048576 bytes)'");
}

TEST(Config, OutOfRangeIsAnError) {
  const Config config = Config::parse("levels: 40\nscale: -1\n", "f.yaml");
  EXPECT_EQ(error_of([&] { config.get_int("levels", 8, 1, 16); }),
            "f.yaml: field 'levels': expected an integer in [1, 16], got 40");
  EXPECT_EQ(error_of([&] { config.get_double("scale", 1.2, 1.0, 2.0); }),
            "f.yaml: field 'scale': expected a number in [1, 2], got -1");
}

TEST(Config, BadBoolChoiceAndList) {
  const Config config = Config::parse("parallel: maybe\nmode: fancy\nfast: 20\n", "f.yaml");
  EXPECT_EQ(error_of([&] { config.get_bool("parallel", true); }),
            "f.yaml: field 'parallel': expected true or false, got 'maybe'");
  EXPECT_EQ(error_of([&] {
              config.get_choice("mode", "global", {"global", "clahe"});
            }),
            "f.yaml: field 'mode': expected one of global clahe, got 'fancy'");
  EXPECT_EQ(error_of([&] { config.get_doubles("fast", {}); }),
            "f.yaml: field 'fast': expected a list of numbers, got 20");
}

TEST(Config, UnknownFieldIsRejected) {
  const Config config = Config::parse("levels: 4\norb:\n  levle: 3\n", "f.yaml");
  config.get_int("levels", 8);
  EXPECT_EQ(error_of([&] { config.reject_unknown(); }), "f.yaml: unknown field 'orb.levle' (no such option)");
}

TEST(Config, DuplicateFieldIsRejected) {
  EXPECT_EQ(error_of([] { Config::parse("a: 1\na: 2\n", "f.yaml"); }), "f.yaml: field 'a' appears twice");
}

TEST(Config, BrokenYamlNamesTheLine) {
  EXPECT_EQ(error_of([] { Config::parse("a: 1\nb: [1,\n", "f.yaml"); }),
            "f.yaml: not valid YAML: line 2: Missing , between the elements");
  EXPECT_EQ(error_of([] { Config::parse("just text\n", "f.yaml"); }).rfind("f.yaml: not valid YAML", 0), 0u);
}

TEST(Config, TrailingCommentsAreComments) {
  const Config config = Config::parse("# whole line\nlevels: 4   # trailing\nname: \"a # b\"\nmode: x#y\n", "f.yaml");
  EXPECT_EQ(config.get_int("levels", 8), 4);
  EXPECT_EQ(config.get_string("name", ""), "a # b");
  EXPECT_EQ(config.get_string("mode", ""), "x#y");
}

TEST(Config, MissingFileIsOneLine) {
  EXPECT_EQ(error_of([] { Config::load("/nonexistent/x.yaml"); }), "/nonexistent/x.yaml: cannot open");
}

TEST(Config, PathsResolveAgainstTheConfigFolder) {
  const auto dir = std::filesystem::temp_directory_path() / ("heslam_config_test_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "c.yaml") << "%YAML:1.0\n---\nvocabulary: voc.txt\nabsolute: /x/y\n";
  const Config config = Config::load(dir / "c.yaml");
  EXPECT_EQ(config.get_path("vocabulary", ""), dir / "voc.txt");
  EXPECT_EQ(config.get_path("absolute", ""), std::filesystem::path("/x/y"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace heslam::runtime
