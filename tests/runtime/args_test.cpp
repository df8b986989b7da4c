// Common command-line flags: values, defaults, pass-through, and one-line errors.
#include "runtime/args.hpp"

#include <stdexcept>

#include <gtest/gtest.h>

namespace heslam::runtime {
namespace {

CommonArgs parse(std::vector<const char*> argv) {
  argv.insert(argv.begin(), "heslam-x");
  return parse_common_args(static_cast<int>(argv.size()), argv.data(), "x");
}

std::string error_of(std::vector<const char*> argv) {
  try {
    parse(std::move(argv));
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

TEST(CommonArgs, DefaultsAndPassThrough) {
  unsetenv("HESLAM_DOMAIN");
  const CommonArgs args = parse({"DATASET", "--rate", "1"});
  EXPECT_EQ(args.domain_id, 0);
  EXPECT_EQ(args.ns, "heslam");
  EXPECT_EQ(args.name, "x");
  EXPECT_EQ(args.log_level, LogLevel::kInfo);
  EXPECT_EQ(args.rest, (std::vector<std::string>{"DATASET", "--rate", "1"}));
}

// Error lines name the executable the user ran, not the component's internal name.
TEST(CommonArgs, ProgramNameIsTheExecutable) {
  EXPECT_EQ(program_name("/work/build/bin/heslam-local-mapper", "local_mapper"), "heslam-local-mapper");
  EXPECT_EQ(program_name("heslam-loop-closer-proximity", "loop_closer"), "heslam-loop-closer-proximity");
  EXPECT_EQ(program_name(nullptr, "local_mapper"), "heslam-local-mapper");
  EXPECT_EQ(program_name("/tmp/a.out", "loop_closer"), "heslam-loop-closer");
  EXPECT_EQ(parse({}).program, "heslam-x");
}

TEST(CommonArgs, ParsesBothSpellings) {
  const CommonArgs args =
      parse({"--domain", "7", "--namespace=robot1", "--name", "fe", "--config", "c.yaml", "--log-level=debug", "x"});
  EXPECT_EQ(args.domain_id, 7);
  EXPECT_EQ(args.ns, "robot1");
  EXPECT_EQ(args.name, "fe");
  EXPECT_EQ(args.config_files, std::vector<std::filesystem::path>{"c.yaml"});
  EXPECT_EQ(args.log_level, LogLevel::kDebug);
  EXPECT_EQ(args.rest, (std::vector<std::string>{"x"}));
}

TEST(CommonArgs, EnvironmentDomainIsTheDefault) {
  setenv("HESLAM_DOMAIN", "12", 1);
  EXPECT_EQ(parse({}).domain_id, 12);
  EXPECT_EQ(parse({"--domain", "3"}).domain_id, 3);
  unsetenv("HESLAM_DOMAIN");
}

TEST(CommonArgs, BadValuesAreOneLine) {
  EXPECT_EQ(error_of({"--domain", "x"}), "--domain: expected an integer in [0, 232], got 'x'");
  EXPECT_EQ(error_of({"--domain", "500"}), "--domain: expected an integer in [0, 232], got '500'");
  EXPECT_EQ(error_of({"--domain"}), "--domain: missing value");
  EXPECT_EQ(error_of({"--log-level", "loud"}), "--log-level: expected debug, info, warn, error or off, got 'loud'");
  EXPECT_EQ(error_of({"--namespace", "bad name"}),
            "namespace 'bad name': expected letters, digits, '_', '-' or inner '/', not starting with a digit");
}

}  // namespace
}  // namespace heslam::runtime
