// Flags: the one command-line parser of every heslam program. Each flag is declared once, with its
// name, where its value goes (and what values it takes) and a one-line help; the parser and the usage
// text both come from the declarations, so they cannot disagree.
//
//   runtime::Flags flags("heslam-replay DATASET [options]");
//   flags.number("--rate", "R", &options.rate, 0.0, 100.0, "speed, 1 = real time")
//        .toggle("--lockstep", &options.lockstep, "publish frame n+1 after FrameDone(n)")
//        .positional("DATASET", [&](const std::string& arg) { options.dataset = arg; });
//   flags.parse(args);
//
// "--flag value" and "--flag=value" are both accepted. An unknown flag, a missing value or a bad
// value throws std::runtime_error with one line naming the flag and quoting the value (quote_value):
//   "--rate: expected a number in [0, 100], got 'fast'"   "--rate: missing value"
//   "--bogus: unknown option (see --help)"
// Values are applied in the order given; a later occurrence of a flag overrides an earlier one,
// except list() flags, which collect every occurrence.
#pragma once

#include <concepts>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace heslam::runtime {

class Flags {
 public:
  using Apply = std::function<void(const std::string& value)>;

  // usage_line: what follows "usage: " in the generated usage, e.g. "heslam-replay DATASET [options]";
  // description: lines printed under it (may be empty).
  explicit Flags(std::string usage_line, std::string description = {});

  // A flag without a value: when seen, *target = value_when_seen ("--no-progress" sets false).
  Flags& toggle(std::string name, bool* target, std::string help, bool value_when_seen = true);
  Flags& text(std::string name, std::string metavar, std::string* target, std::string help);
  // As text(), but an empty value is refused ("--name: expected a non-empty value").
  Flags& non_empty_text(std::string name, std::string metavar, std::string* target, std::string help);
  Flags& path(std::string name, std::string metavar, std::filesystem::path* target, std::string help);
  // An integer in [min_value, max_value]; the error line shows the range (or ">= min" without a maximum).
  template <std::integral T>
  Flags& integer(std::string name, std::string metavar, T* target, T min_value, T max_value, std::string help);
  template <std::integral T>
  Flags& integer(std::string name, std::string metavar, T* target, std::string help) {
    return integer(std::move(name), std::move(metavar), target, std::numeric_limits<T>::min(),
                   std::numeric_limits<T>::max(), std::move(help));
  }
  // A finite number in [min_value, max_value] (infinite bounds: no bound).
  Flags& number(std::string name, std::string metavar, double* target, double min_value, double max_value,
                std::string help);
  Flags& number(std::string name, std::string metavar, double* target, std::string help);
  // "on" or "off".
  Flags& on_off(std::string name, bool* target, std::string help);
  // One of the named choices; the error line lists them ("expected a, b or c, got 'x'").
  template <typename T>
  Flags& choice(std::string name, T* target, std::vector<std::pair<std::string, T>> choices, std::string help);
  // Comma-separated integers in [min_value, max_value], e.g. "100,1000,5000" (at least one).
  Flags& integer_list(std::string name, std::string metavar, std::vector<int>* target, int min_value, int max_value,
                      std::string help);
  // Repeatable: every occurrence appends its value.
  Flags& list(std::string name, std::string metavar, std::vector<std::string>* target, std::string help);
  // Anything else: apply receives the value and throws std::runtime_error with its own line.
  Flags& custom(std::string name, std::string metavar, std::string help, Apply apply);
  // Another spelling of the flag declared last (e.g. "-h" for "--help").
  Flags& alias(std::string name);
  // A line of its own in the usage, after the flags declared so far.
  Flags& note(std::string text);
  // Arguments that are not flags go to apply, in order (it may throw for an extra one). Without a
  // positional declaration, such an argument is an error. metavar and help only serve the usage.
  Flags& positional(std::string metavar, std::string help, Apply apply);

  // Unknown flags: an error, or handed back (with everything that is not a declared flag, in order)
  // for another parser; parse_common_args keeps them for the tool's own flags.
  enum class Unknown { kError, kKeep };
  // args: the arguments without argv[0]. Returns the kept arguments (empty with Unknown::kError).
  std::vector<std::string> parse(const std::vector<std::string>& args, Unknown unknown = Unknown::kError);
  std::vector<std::string> parse(int argc, const char* const* argv, Unknown unknown = Unknown::kError);

  // Whether the flag (by its declared name) was on the command line.
  bool given(std::string_view name) const;

  // "usage: <usage_line>\n<description>" then one line per flag: "  --name METAVAR   help".
  std::string usage() const;
  // The flag lines alone (no usage line), e.g. to append the common flags to a tool's usage.
  std::string flag_lines() const;

 private:
  struct Spec {
    std::vector<std::string> names;  // the first is the declared name
    std::string metavar;             // empty: the flag takes no value
    std::string help;
    Apply apply;
    bool given = false;
    bool is_note = false;
  };
  Flags& add(std::string name, std::string metavar, std::string help, Apply apply);
  Spec* find(std::string_view name);

  std::string usage_line_;
  std::string description_;
  std::vector<Spec> specs_;
  std::string positional_metavar_;
  std::string positional_help_;
  Apply positional_;
};

// The error line of a bad value: "<flag>: expected <expected>, got '<quoted value>'".
[[noreturn]] void throw_bad_flag_value(std::string_view flag, std::string_view expected, std::string_view value);
// Parses a whole string as a decimal integer / a finite number; false if it is not one.
bool parse_whole_integer(std::string_view text, std::int64_t& value);
bool parse_whole_number(std::string_view text, double& value);

template <std::integral T>
Flags& Flags::integer(std::string name, std::string metavar, T* target, T min_value, T max_value, std::string help) {
  std::string expected = "an integer";
  if (min_value != std::numeric_limits<T>::min() && max_value != std::numeric_limits<T>::max()) {
    expected += " in [" + std::to_string(min_value) + ", " + std::to_string(max_value) + "]";
  } else if (min_value != std::numeric_limits<T>::min()) {
    expected += " >= " + std::to_string(min_value);
  } else if (max_value != std::numeric_limits<T>::max()) {
    expected += " <= " + std::to_string(max_value);
  }
  std::string flag = name;
  return add(std::move(name), std::move(metavar), std::move(help),
             [target, min_value, max_value, flag, expected](const std::string& value) {
               std::int64_t parsed = 0;
               if (!parse_whole_integer(value, parsed) || std::cmp_less(parsed, min_value) ||
                   std::cmp_greater(parsed, max_value)) {
                 throw_bad_flag_value(flag, expected, value);
               }
               *target = static_cast<T>(parsed);
             });
}

template <typename T>
Flags& Flags::choice(std::string name, T* target, std::vector<std::pair<std::string, T>> choices, std::string help) {
  std::string metavar;
  std::string expected;
  for (std::size_t i = 0; i < choices.size(); ++i) {
    metavar += (i == 0 ? "" : "|") + choices[i].first;
    expected += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i].first;
  }
  std::string flag = name;
  return add(std::move(name), std::move(metavar), std::move(help),
             [target, choices = std::move(choices), flag, expected](const std::string& value) {
               for (const auto& [text, choice_value] : choices) {
                 if (text == value) {
                   *target = choice_value;
                   return;
                 }
               }
               throw_bad_flag_value(flag, expected, value);
             });
}

}  // namespace heslam::runtime
