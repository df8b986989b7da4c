// RunJournal: numbered, checksummed lines after a run-id header; see run_journal.hpp for the format.
#include "runtime/run_journal.hpp"

#include <charconv>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <system_error>

#include "runtime/atomic_file.hpp"

namespace heslam::runtime {
namespace {

// Separates a record from its number and checksum. The last occurrence on a line is the separator,
// so a record may contain it.
constexpr std::string_view kNumberMark = " #";

// FNV-1a, 32 bit: enough to tell a damaged or hand-written line from one this class wrote.
std::uint32_t fnv1a_32(std::string_view bytes) {
  constexpr std::uint32_t kOffsetBasis = 2166136261u;
  constexpr std::uint32_t kPrime = 16777619u;
  std::uint32_t hash = kOffsetBasis;
  for (const char byte : bytes) {
    hash ^= static_cast<unsigned char>(byte);
    hash *= kPrime;
  }
  return hash;
}

// The number a line claims, if it has one; whether the checksum holds is checked by writing the
// line again (RunJournal::line) and comparing.
bool claimed_number(std::string_view line, std::uint64_t& number) {
  const std::size_t mark = line.rfind(kNumberMark);
  if (mark == std::string_view::npos) return false;
  const std::string_view rest = line.substr(mark + kNumberMark.size());
  const auto [end, error] = std::from_chars(rest.data(), rest.data() + rest.size(), number);
  return error == std::errc() && end != rest.data();
}

// A record is one line: a newline in it would split it into two that fail their checksum.
void check_record(const std::filesystem::path& path, std::string_view record) {
  if (record.find('\n') != std::string_view::npos) {
    throw std::invalid_argument(path.string() + ": a record must not contain a newline");
  }
}

// The first line of a run file of run `run_id` and `format`, newline included.
std::string header_line(const std::string& run_id, std::string_view format) {
  return run_id + " " + std::string(format) + "\n";
}

}  // namespace

std::string RunJournal::Contents::dropped_report(const std::filesystem::path& path) const {
  if (dropped_lines() == 0) return "";
  return path.string() + ": " + std::to_string(dropped_lines()) + (dropped_lines() == 1 ? " line" : " lines") +
         " dropped, not resumed from (" + std::to_string(bad_checksum_lines) + " failing their checksum, " +
         std::to_string(out_of_sequence_lines) + " out of sequence)";
}

bool RunJournal::written_by_run(const std::filesystem::path& path, const std::string& run_id, std::string_view format) {
  std::ifstream in(path, std::ios::binary);
  std::string first_line;
  return std::getline(in, first_line) && first_line + "\n" == header_line(run_id, format);
}

RunJournal::RunJournal(std::filesystem::path path, std::string format)
    : path_(std::move(path)), format_(std::move(format)) {}

std::string RunJournal::line(std::uint64_t number, std::string_view record) {
  const std::string numbered = std::to_string(number) + " " + std::string(record);
  char checksum[9];
  std::snprintf(checksum, sizeof(checksum), "%08x", static_cast<unsigned>(fnv1a_32(numbered)));
  std::string text(record);
  text += kNumberMark;
  text += std::to_string(number);
  text += ' ';
  text += checksum;
  text += '\n';
  return text;
}

RunJournal::Contents RunJournal::open_for_run(const std::string& run_id) {
  Contents contents;
  header_ = header_line(run_id, format_);
  next_number_ = 1;
  std::string text;
  {
    std::ifstream in(path_, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    contents.other_file_replaced = in.is_open() && !text.starts_with(header_);
  }
  std::error_code ignored;  // an uncreatable folder fails the write below, with its message
  if (path_.has_parent_path()) std::filesystem::create_directories(path_.parent_path(), ignored);
  if (!text.starts_with(header_)) {
    replace({});
    return contents;
  }
  contents.same_run = true;
  std::size_t trusted_end = header_.size();
  for (std::size_t begin = header_.size(); begin < text.size();) {
    const std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) {
      contents.torn_lines = 1;
      break;
    }
    const std::string_view line_text = std::string_view(text).substr(begin, end + 1 - begin);
    begin = end + 1;
    std::uint64_t number = 0;
    if (!claimed_number(line_text, number)) {
      ++contents.bad_checksum_lines;
      continue;
    }
    const std::string_view record = line_text.substr(0, line_text.rfind(kNumberMark));
    if (line(number, record) != line_text) {
      ++contents.bad_checksum_lines;
    } else if (number != next_number_) {
      ++contents.out_of_sequence_lines;
    } else {
      contents.records.emplace_back(record);
      ++next_number_;
      trusted_end = begin;
    }
  }
  // Lines after the last trusted one can never be trusted (the next record is numbered after it):
  // cut off, so the next record is not glued to a torn line and no drop is reported twice.
  std::error_code error;
  std::filesystem::resize_file(path_, trusted_end, error);
  if (error) throw std::runtime_error(path_.string() + ": cannot cut off its untrusted last lines: " + error.message());
  open_for_append();
  return contents;
}

void RunJournal::open_for_append() {
  file_.reset(std::fopen(path_.c_str(), "a"));
  if (!file_) throw std::runtime_error(path_.string() + ": cannot open for append");
}

void RunJournal::append(std::string_view record) {
  check_record(path_, record);
  if (!file_) return;
  const std::string text = line(next_number_++, record);
  std::fwrite(text.data(), 1, text.size(), file_.get());
  std::fflush(file_.get());
}

void RunJournal::replace(std::span<const std::string> records) {
  std::string text = header_;
  next_number_ = 1;
  for (const std::string& record : records) {
    check_record(path_, record);
    text += line(next_number_++, record);
  }
  file_.reset();  // the handle would keep appending to the replaced file
  replace_file_contents(path_, text, /*sync=*/false);
  open_for_append();
}

void RunJournal::remove() {
  file_.reset();
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);
}

}  // namespace heslam::runtime
