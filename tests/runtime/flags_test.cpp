// The one command-line parser (runtime/flags.hpp): every value kind, both spellings, positional
// arguments, pass-through, one-line errors and the usage generated from the declarations.
#include "runtime/flags.hpp"

#include <stdexcept>

#include <gtest/gtest.h>

namespace heslam::runtime {
namespace {

enum class Mode { kFast, kSlow };

struct Values {
  std::string name = "default";
  std::filesystem::path file;
  int count = 3;
  std::uint64_t big = 0;
  double rate = 1.0;
  double offset = 0.0;
  bool pinned = true;
  bool lockstep = false;
  bool progress = true;
  Mode mode = Mode::kFast;
  std::vector<std::string> tags;
  std::vector<std::string> positionals;
};

Flags declare(Values& v) {
  Flags flags("heslam-x INPUT [options]", "  Does x.");
  flags.text("--name", "NAME", &v.name, "a name")
      .path("--file", "FILE", &v.file, "a file")
      .integer("--count", "N", &v.count, 1, 10, "how many (1-10)")
      .integer("--big", "N", &v.big, std::uint64_t{1}, std::numeric_limits<std::uint64_t>::max(), "at least one")
      .number("--rate", "R", &v.rate, 0.0, 100.0, "speed")
      .number("--offset", "S", &v.offset, "any finite number")
      .on_off("--pin", &v.pinned, "pin the threads")
      .toggle("--lockstep", &v.lockstep, "one frame at a time")
      .toggle("--no-progress", &v.progress, "no progress line", false)
      .choice("--mode", &v.mode, {{"fast", Mode::kFast}, {"slow", Mode::kSlow}}, "how")
      .list("--tag", "T", &v.tags, "repeatable")
      .positional("INPUT", "what to read", [&v](const std::string& arg) { v.positionals.push_back(arg); });
  return flags;
}

std::string error_of(const std::vector<std::string>& args) {
  Values v;
  Flags flags = declare(v);
  try {
    flags.parse(args);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

TEST(Flags, DefaultsStayWithoutFlags) {
  Values v;
  declare(v).parse(std::vector<std::string>{});
  EXPECT_EQ(v.name, "default");
  EXPECT_EQ(v.count, 3);
  EXPECT_EQ(v.rate, 1.0);
  EXPECT_TRUE(v.pinned);
  EXPECT_TRUE(v.progress);
  EXPECT_TRUE(v.positionals.empty());
}

TEST(Flags, EveryKindInBothSpellings) {
  Values v;
  Flags flags = declare(v);
  flags.parse({"in1",
               "--name",
               "a b",
               "--file=x.txt",
               "--count",
               "+7",
               "--big=9223372036854775807",
               "--rate",
               "2.5",
               "--offset=-0.25",
               "--pin",
               "off",
               "--lockstep",
               "--no-progress",
               "--mode=slow",
               "--tag",
               "t1",
               "in2",
               "--tag=t2",
               "--tag="});
  EXPECT_EQ(v.name, "a b");
  EXPECT_EQ(v.file, "x.txt");
  EXPECT_EQ(v.count, 7);
  EXPECT_EQ(v.big, 9223372036854775807u);
  EXPECT_EQ(v.rate, 2.5);
  EXPECT_EQ(v.offset, -0.25);
  EXPECT_FALSE(v.pinned);
  EXPECT_TRUE(v.lockstep);
  EXPECT_FALSE(v.progress);
  EXPECT_EQ(v.mode, Mode::kSlow);
  EXPECT_EQ(v.tags, (std::vector<std::string>{"t1", "t2", ""}));
  EXPECT_EQ(v.positionals, (std::vector<std::string>{"in1", "in2"}));
  EXPECT_TRUE(flags.given("--rate"));
  EXPECT_TRUE(flags.given("--name"));
  EXPECT_THROW(flags.given("--nope"), std::logic_error);
}

TEST(Flags, TheLastOccurrenceWins) {
  Values v;
  declare(v).parse({"--count", "2", "--count=5"});
  EXPECT_EQ(v.count, 5);
}

TEST(Flags, BadValuesAreOneLineNamingTheFlag) {
  EXPECT_EQ(error_of({"--count", "x"}), "--count: expected an integer in [1, 10], got 'x'");
  EXPECT_EQ(error_of({"--count", "11"}), "--count: expected an integer in [1, 10], got '11'");
  EXPECT_EQ(error_of({"--count", "2.0"}), "--count: expected an integer in [1, 10], got '2.0'");
  EXPECT_EQ(error_of({"--count", ""}), "--count: expected an integer in [1, 10], got ''");
  EXPECT_EQ(error_of({"--big", "0"}), "--big: expected an integer >= 1, got '0'");
  EXPECT_EQ(error_of({"--big", "-1"}), "--big: expected an integer >= 1, got '-1'");
  EXPECT_EQ(error_of({"--rate", "fast"}), "--rate: expected a number in [0, 100], got 'fast'");
  EXPECT_EQ(error_of({"--rate=1e308"}), "--rate: expected a number in [0, 100], got '1e308'");
  EXPECT_EQ(error_of({"--offset", "nan"}), "--offset: expected a number, got 'nan'");
  EXPECT_EQ(error_of({"--offset", "inf"}), "--offset: expected a number, got 'inf'");
  EXPECT_EQ(error_of({"--offset", "1e999"}), "--offset: expected a number, got '1e999'");
  EXPECT_EQ(error_of({"--pin", "yes"}), "--pin: expected on or off, got 'yes'");
  EXPECT_EQ(error_of({"--mode", "medium"}), "--mode: expected fast or slow, got 'medium'");
  EXPECT_EQ(error_of({"--lockstep=on"}), "--lockstep: takes no value, got 'on'");
}

TEST(Flags, MissingValueAndUnknownFlag) {
  EXPECT_EQ(error_of({"--rate"}), "--rate: missing value");
  EXPECT_EQ(error_of({"--bogus"}), "--bogus: unknown option (see --help)");
  EXPECT_EQ(error_of({"--bogus=1"}), "--bogus: unknown option (see --help)");
  EXPECT_EQ(error_of({"-x"}), "-x: unknown option (see --help)");
}

TEST(Flags, HugeOrBinaryValuesAreQuotedShort) {
  const std::string huge(100000, '9');
  EXPECT_EQ(error_of({"--count", huge}),
            "--count: expected an integer in [1, 10], got '" + std::string(80, '9') + "... (100000 bytes)'");
  EXPECT_EQ(error_of({"--mode", std::string("a\x01", 2)}), "--mode: expected fast or slow, got 'a\\x01'");
  EXPECT_EQ(error_of({"--" + huge}), "--" + std::string(78, '9') + "... (100002 bytes): unknown option (see --help)");
}

TEST(Flags, WithoutAPositionalDeclarationAnArgumentIsAnError) {
  bool seen = false;
  Flags flags("heslam-y");
  flags.toggle("--seen", &seen, "");
  try {
    flags.parse({"extra"});
    FAIL() << "no error";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "'extra': unexpected argument (see --help)");
  }
  // "-" alone is an argument (stdin, stdout), not a flag.
  try {
    flags.parse({"-"});
    FAIL() << "no error";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "'-': unexpected argument (see --help)");
  }
}

TEST(Flags, KeepsWhatItDoesNotKnowInOrder) {
  Values v;
  Flags flags = declare(v);
  const auto rest =
      flags.parse({"DATASET", "--count", "4", "--rate-x", "1", "--other=2", "--lockstep"}, Flags::Unknown::kKeep);
  EXPECT_EQ(rest, (std::vector<std::string>{"DATASET", "--rate-x", "1", "--other=2"}));
  EXPECT_EQ(v.count, 4);
  EXPECT_TRUE(v.lockstep);
  EXPECT_TRUE(v.positionals.empty()) << "kept arguments go back to the caller, not to the positional";
}

TEST(Flags, ArgvSkipsTheProgram) {
  Values v;
  const char* argv[] = {"heslam-x", "--count", "9", "in"};
  declare(v).parse(4, argv);
  EXPECT_EQ(v.count, 9);
  EXPECT_EQ(v.positionals, (std::vector<std::string>{"in"}));
}

TEST(Flags, IntegerLists) {
  std::vector<int> sizes{1};
  Flags flags("heslam-l");
  flags.integer_list("--sizes", "N,N", &sizes, 1, 1000, "sizes");
  flags.parse({"--sizes", "10,+20,1000"});
  EXPECT_EQ(sizes, (std::vector<int>{10, 20, 1000}));
  for (const std::string bad : {"", "10,", "10,x", "0", "1001", "1;2"}) {
    try {
      flags.parse({"--sizes", bad});
      FAIL() << bad;
    } catch (const std::runtime_error& error) {
      EXPECT_EQ(error.what(), "--sizes: expected comma-separated integers in [1, 1000], got '" + bad + "'");
    }
  }
}

TEST(Flags, AliasesAndCustomValues) {
  bool help = false;
  std::string pair;
  Flags flags("heslam-z");
  flags.toggle("--help", &help, "this help")
      .alias("-h")
      .custom("--arg", "K=V", "a pair", [&](const std::string& value) {
        if (value.find('=') == std::string::npos) throw_bad_flag_value("--arg", "key=value", value);
        pair = value;
      });
  flags.parse({"-h", "--arg", "a=1"});
  EXPECT_TRUE(help);
  EXPECT_TRUE(flags.given("--help"));
  EXPECT_EQ(pair, "a=1");
  try {
    flags.parse({"--arg=x"});
    FAIL() << "no error";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "--arg: expected key=value, got 'x'");
  }
  EXPECT_THROW(flags.alias("--arg"), std::logic_error);
  EXPECT_THROW(flags.toggle("--help", &help, ""), std::logic_error);
}

TEST(Flags, UsageComesFromTheDeclarations) {
  Values v;
  Flags flags = declare(v);
  flags.note("Pause: space.").text("--a-flag-whose-name-is-far-too-long", "VALUE", &v.name, "first line\nsecond line");
  const std::string usage = flags.usage();
  EXPECT_EQ(usage.substr(0, usage.find('\n')), "usage: heslam-x INPUT [options]");
  EXPECT_NE(usage.find("\n  Does x.\n"), std::string::npos);
  EXPECT_NE(usage.find("\n  INPUT             what to read\n"), std::string::npos) << usage;
  EXPECT_NE(usage.find("\n  --count N         how many (1-10)\n"), std::string::npos) << usage;
  EXPECT_NE(usage.find("\n  --pin on|off      pin the threads\n"), std::string::npos) << usage;
  EXPECT_NE(usage.find("\n  --mode fast|slow  how\n"), std::string::npos) << usage;
  EXPECT_NE(usage.find("\n  --lockstep        one frame at a time\n"), std::string::npos) << usage;
  EXPECT_NE(usage.find("\n  Pause: space.\n"), std::string::npos) << usage;
  EXPECT_NE(usage.find("\n  --a-flag-whose-name-is-far-too-long VALUE\n"
                       "                    first line\n"
                       "                    second line\n"),
            std::string::npos)
      << usage;
  EXPECT_EQ(usage.find("usage", 1), std::string::npos);
}

}  // namespace
}  // namespace heslam::runtime
