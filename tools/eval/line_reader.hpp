// Reads a text file line by line as rows of numbers, with errors that name file:line.
//
// API:
//   LineReader reader(path);            throws "cannot open <path>" when unreadable
//   while (reader.next()) {             skips blank lines and '#' comments
//     reader.values();                  the numbers of the row (separated by spaces, tabs or commas)
//     reader.fail("expected ...");      throws std::runtime_error "<path>:<line>: expected ..."
//   }
#pragma once

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace heslam::eval {

class LineReader {
 public:
  explicit LineReader(const std::filesystem::path& path);

  // Advances to the next data row; false at the end of the file.
  bool next();

  const std::vector<double>& values() const { return values_; }
  // The first token of the row as an integer (for nanosecond stamps and frame indices that must not
  // pass through a double).
  long long integer_token(std::size_t index) const;
  std::size_t line_number() const { return line_number_; }
  const std::filesystem::path& path() const { return path_; }
  // The comment lines ('#' first) read so far before the first data row, as written.
  const std::vector<std::string>& header_comments() const { return header_comments_; }

  // Throws "<path>:<line>: <what>".
  [[noreturn]] void fail(const std::string& what) const;
  // Throws unless the row has one of the two column counts (b == 0: only a).
  void expect_columns(std::size_t a, std::size_t b, const char* layout) const;

 private:
  std::filesystem::path path_;
  std::ifstream stream_;
  std::string line_;
  std::vector<std::string> tokens_;
  std::vector<double> values_;
  std::size_t line_number_ = 0;
  std::vector<std::string> header_comments_;
  bool data_seen_ = false;
};

}  // namespace heslam::eval
