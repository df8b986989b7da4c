// The one command-line parser (runtime/flags.hpp).
#include "runtime/flags.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include "runtime/quote_value.hpp"

namespace heslam::runtime {
namespace {

// Flag names and metavars up to this wide share one help column; a longer one puts its help on the
// next line, so one long flag does not push every help far right.
constexpr std::size_t kMaxFlagColumn = 30;

std::string format_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

}  // namespace

void throw_bad_flag_value(std::string_view flag, std::string_view expected, std::string_view value) {
  throw std::runtime_error(std::string(flag) + ": expected " + std::string(expected) + ", got '" + quote_value(value) +
                           "'");
}

bool parse_whole_integer(std::string_view text, std::int64_t& value) {
  const char* begin = text.data();
  if (!text.empty() && text.front() == '+') ++begin;  // from_chars refuses a leading '+'
  const auto [end, error] = std::from_chars(begin, text.data() + text.size(), value);
  return !text.empty() && error == std::errc{} && end == text.data() + text.size();
}

bool parse_whole_number(std::string_view text, double& value) {
  const char* begin = text.data();
  if (!text.empty() && text.front() == '+') ++begin;
  const auto [end, error] = std::from_chars(begin, text.data() + text.size(), value);
  return !text.empty() && error == std::errc{} && end == text.data() + text.size() && std::isfinite(value);
}

Flags::Flags(std::string usage_line, std::string description)
    : usage_line_(std::move(usage_line)), description_(std::move(description)) {}

Flags& Flags::add(std::string name, std::string metavar, std::string help, Apply apply) {
  if (find(name) != nullptr) throw std::logic_error("Flags: " + name + " declared twice");
  specs_.push_back(Spec{{std::move(name)}, std::move(metavar), std::move(help), std::move(apply)});
  return *this;
}

Flags::Spec* Flags::find(std::string_view name) {
  for (Spec& spec : specs_) {
    if (spec.is_note) continue;
    if (std::find(spec.names.begin(), spec.names.end(), name) != spec.names.end()) return &spec;
  }
  return nullptr;
}

Flags& Flags::toggle(std::string name, bool* target, std::string help, bool value_when_seen) {
  return add(std::move(name), "", std::move(help),
             [target, value_when_seen](const std::string&) { *target = value_when_seen; });
}

Flags& Flags::text(std::string name, std::string metavar, std::string* target, std::string help) {
  return add(std::move(name), std::move(metavar), std::move(help),
             [target](const std::string& value) { *target = value; });
}

Flags& Flags::non_empty_text(std::string name, std::string metavar, std::string* target, std::string help) {
  std::string flag = name;
  return add(std::move(name), std::move(metavar), std::move(help), [target, flag](const std::string& value) {
    if (value.empty()) throw std::runtime_error(flag + ": expected a non-empty value");
    *target = value;
  });
}

Flags& Flags::path(std::string name, std::string metavar, std::filesystem::path* target, std::string help) {
  return add(std::move(name), std::move(metavar), std::move(help),
             [target](const std::string& value) { *target = value; });
}

Flags& Flags::number(std::string name, std::string metavar, double* target, double min_value, double max_value,
                     std::string help) {
  std::string expected = "a number";
  if (std::isfinite(min_value) && std::isfinite(max_value)) {
    expected += " in [" + format_number(min_value) + ", " + format_number(max_value) + "]";
  } else if (std::isfinite(min_value)) {
    expected += " >= " + format_number(min_value);
  } else if (std::isfinite(max_value)) {
    expected += " <= " + format_number(max_value);
  }
  std::string flag = name;
  return add(std::move(name), std::move(metavar), std::move(help),
             [target, min_value, max_value, flag, expected](const std::string& value) {
               double parsed = 0.0;
               if (!parse_whole_number(value, parsed) || parsed < min_value || parsed > max_value) {
                 throw_bad_flag_value(flag, expected, value);
               }
               *target = parsed;
             });
}

Flags& Flags::number(std::string name, std::string metavar, double* target, std::string help) {
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  return number(std::move(name), std::move(metavar), target, -kInfinity, kInfinity, std::move(help));
}

Flags& Flags::on_off(std::string name, bool* target, std::string help) {
  return choice(std::move(name), target, {{"on", true}, {"off", false}}, std::move(help));
}

Flags& Flags::integer_list(std::string name, std::string metavar, std::vector<int>* target, int min_value,
                           int max_value, std::string help) {
  std::string flag = name;
  const std::string expected =
      "comma-separated integers in [" + std::to_string(min_value) + ", " + std::to_string(max_value) + "]";
  return add(std::move(name), std::move(metavar), std::move(help),
             [target, flag, expected, min_value, max_value](const std::string& value) {
               std::vector<int> numbers;
               std::size_t begin = 0;
               while (begin <= value.size()) {
                 const std::size_t comma = std::min(value.find(',', begin), value.size());
                 std::int64_t number = 0;
                 if (!parse_whole_integer(std::string_view(value).substr(begin, comma - begin), number) ||
                     number < min_value || number > max_value) {
                   throw_bad_flag_value(flag, expected, value);
                 }
                 numbers.push_back(static_cast<int>(number));
                 begin = comma + 1;
               }
               *target = std::move(numbers);
             });
}

Flags& Flags::list(std::string name, std::string metavar, std::vector<std::string>* target, std::string help) {
  return add(std::move(name), std::move(metavar), std::move(help),
             [target](const std::string& value) { target->push_back(value); });
}

Flags& Flags::custom(std::string name, std::string metavar, std::string help, Apply apply) {
  return add(std::move(name), std::move(metavar), std::move(help), std::move(apply));
}

Flags& Flags::alias(std::string name) {
  if (specs_.empty() || specs_.back().is_note) throw std::logic_error("Flags: alias " + name + " without a flag");
  if (find(name) != nullptr) throw std::logic_error("Flags: " + name + " declared twice");
  specs_.back().names.push_back(std::move(name));
  return *this;
}

Flags& Flags::note(std::string text) {
  Spec spec;
  spec.help = std::move(text);
  spec.is_note = true;
  specs_.push_back(std::move(spec));
  return *this;
}

Flags& Flags::positional(std::string metavar, std::string help, Apply apply) {
  positional_metavar_ = std::move(metavar);
  positional_help_ = std::move(help);
  positional_ = std::move(apply);
  return *this;
}

std::vector<std::string> Flags::parse(int argc, const char* const* argv, Unknown unknown) {
  return parse(std::vector<std::string>(argv + (argc > 0 ? 1 : 0), argv + std::max(argc, 0)), unknown);
}

std::vector<std::string> Flags::parse(const std::vector<std::string>& args, Unknown unknown) {
  std::vector<std::string> kept;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    const bool looks_like_flag = arg.size() > 1 && arg.front() == '-';
    if (!looks_like_flag) {
      if (unknown == Unknown::kKeep) {
        kept.push_back(arg);
      } else if (positional_) {
        positional_(arg);
      } else {
        throw std::runtime_error("'" + quote_value(arg) + "': unexpected argument (see --help)");
      }
      continue;
    }
    std::string name = arg;
    std::optional<std::string> inline_value;
    if (const auto eq = arg.find('='); arg.starts_with("--") && eq != std::string::npos) {
      name = arg.substr(0, eq);
      inline_value = arg.substr(eq + 1);
    }
    Spec* spec = find(name);
    if (spec == nullptr) {
      if (unknown == Unknown::kKeep) {
        kept.push_back(arg);
        continue;
      }
      throw std::runtime_error(quote_value(name) + ": unknown option (see --help)");
    }
    if (spec->metavar.empty()) {
      if (inline_value) throw std::runtime_error(name + ": takes no value, got '" + quote_value(*inline_value) + "'");
      spec->apply("");
    } else if (inline_value) {
      spec->apply(*inline_value);
    } else {
      if (i + 1 >= args.size()) throw std::runtime_error(name + ": missing value");
      spec->apply(args[++i]);
    }
    spec->given = true;
  }
  return kept;
}

bool Flags::given(std::string_view name) const {
  for (const Spec& spec : specs_) {
    if (!spec.is_note && spec.names.front() == name) return spec.given;
  }
  throw std::logic_error("Flags::given: " + std::string(name) + " is not declared");
}

std::string Flags::flag_lines() const {
  const auto left_of = [](const Spec& spec) {
    std::string left;
    for (std::size_t k = 0; k < spec.names.size(); ++k) left += (k == 0 ? "" : ", ") + spec.names[k];
    if (!spec.metavar.empty()) left += " " + spec.metavar;
    return left;
  };
  std::size_t column = 0;
  for (const Spec& spec : specs_) {
    if (spec.is_note) continue;
    const std::size_t width = left_of(spec).size();
    if (width <= kMaxFlagColumn) column = std::max(column, width);
  }
  if (!positional_metavar_.empty() && positional_metavar_.size() <= kMaxFlagColumn) {
    column = std::max(column, positional_metavar_.size());
  }
  const std::string indent(2 + column + 2, ' ');
  // The help's own line breaks continue under the help column.
  const auto help_text = [&indent](const std::string& help) {
    std::string out;
    for (const char c : help) {
      out += c;
      if (c == '\n') out += indent;
    }
    return out;
  };
  std::string out;
  const auto add_line = [&](const std::string& left, const std::string& help) {
    out += "  " + left;
    if (help.empty()) {
      out += "\n";
      return;
    }
    if (left.size() > column) {
      out += "\n" + indent;
    } else {
      out += std::string(column - left.size() + 2, ' ');
    }
    out += help_text(help) + "\n";
  };
  if (!positional_metavar_.empty() && !positional_help_.empty()) add_line(positional_metavar_, positional_help_);
  for (const Spec& spec : specs_) {
    if (spec.is_note) {
      out += "  " + spec.help + "\n";
    } else {
      add_line(left_of(spec), spec.help);
    }
  }
  return out;
}

std::string Flags::usage() const {
  std::string out = "usage: " + usage_line_ + "\n";
  if (!description_.empty()) out += description_ + (description_.ends_with('\n') ? "" : "\n");
  return out + flag_lines();
}

}  // namespace heslam::runtime
