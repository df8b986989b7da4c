// Tokenising and number parsing for the trajectory readers (std::from_chars: locale-free, exact).
#include "tools/eval/line_reader.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace heslam::eval {

namespace {

bool is_separator(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; }

}  // namespace

LineReader::LineReader(const std::filesystem::path& path) : path_(path), stream_(path) {
  if (!stream_) throw std::runtime_error("cannot open " + path.string());
}

bool LineReader::next() {
  while (std::getline(stream_, line_)) {
    ++line_number_;
    tokens_.clear();
    std::size_t i = 0;
    while (i < line_.size()) {
      while (i < line_.size() && is_separator(line_[i])) ++i;
      if (i >= line_.size() || line_[i] == '#') break;
      std::size_t end = i;
      while (end < line_.size() && !is_separator(line_[end])) ++end;
      tokens_.push_back(line_.substr(i, end - i));
      i = end;
    }
    if (tokens_.empty()) {
      const std::size_t first = line_.find_first_not_of(" \t");
      if (!data_seen_ && first != std::string::npos && line_[first] == '#')
        header_comments_.push_back(line_.substr(first));
      continue;
    }
    data_seen_ = true;
    values_.assign(tokens_.size(), 0.0);
    for (std::size_t k = 0; k < tokens_.size(); ++k) {
      const std::string& token = tokens_[k];
      const char* first = token.data();
      const char* last = token.data() + token.size();
      if (*first == '+') ++first;  // from_chars rejects a leading '+', some writers emit it
      const auto [end, error] = std::from_chars(first, last, values_[k]);
      if (error != std::errc{} || end != last) {
        fail("expected a number in column " + std::to_string(k + 1) + ", got '" + token + "'");
      }
      // from_chars accepts "nan" and "inf"; one such pose would turn every statistic into nan.
      if (!std::isfinite(values_[k])) {
        fail("column " + std::to_string(k + 1) + " is not a finite number ('" + token + "')");
      }
    }
    return true;
  }
  return false;
}

long long LineReader::integer_token(std::size_t index) const {
  const std::string& token = tokens_.at(index);
  long long value = 0;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (error != std::errc{} || end != token.data() + token.size()) {
    fail("expected an integer in column " + std::to_string(index + 1) + ", got '" + token + "'");
  }
  return value;
}

void LineReader::fail(const std::string& what) const {
  throw std::runtime_error(path_.string() + ":" + std::to_string(line_number_) + ": " + what);
}

void LineReader::expect_columns(std::size_t a, std::size_t b, const char* layout) const {
  const std::size_t n = values_.size();
  if (n == a || (b != 0 && n == b)) return;
  std::string expected = std::to_string(a);
  if (b != 0) expected += " or " + std::to_string(b);
  fail("expected " + expected + " columns (" + layout + "), got " + std::to_string(n));
}

}  // namespace heslam::eval
