// A run file: what a process restarted within the same pipeline run resumes from (the frontend's and
// the recorder's journals, the local mapper's and the loop closer's run state). Lines of text:
//
//   <run id> <format>                      the run that wrote the file and what it holds
//   <record> #<number> <checksum>          one per record, numbered 1, 2, 3, ...
//
// <record> is the user's text (no newline), <checksum> the FNV-1a 32 bit hash of "<number> <record>"
// as 8 lower-case hex digits. A record is trusted only when its checksum holds and its number is one
// more than the last trusted record's: a damaged line, a line written by hand or another program,
// and every line after a lost one (whose state may depend on it) are dropped and counted, never
// resumed from. A file of another run or format is replaced by an empty one.
//
// Records are appended and flushed to the kernel one by one, so a kill -9 loses none written; a kill
// mid-write leaves an incomplete last line, which the next open cuts off (with any other untrusted
// lines at the end) so the next record starts a line of its own and continues the numbering. The
// whole file can also be replaced at once (runtime/atomic_file.hpp). Neither is fsynced: the file
// survives a kill of the process, not a power loss.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace heslam::runtime {

class RunJournal {
 public:
  struct Contents {
    bool same_run = false;             // the file was this run's; otherwise it is now an empty one of this run
    bool other_file_replaced = false;  // a file of another run or format was there (and is replaced)
    std::vector<std::string> records;  // the trusted records, in order
    int torn_lines = 0;                // an incomplete last line (a kill mid-write), cut off
    int bad_checksum_lines = 0;        // complete lines whose checksum does not hold, dropped
    int out_of_sequence_lines = 0;     // lines not numbered one after the last trusted record, dropped

    int dropped_lines() const { return bad_checksum_lines + out_of_sequence_lines; }
    // One line naming the file and the dropped lines by cause; empty when none was dropped.
    std::string dropped_report(const std::filesystem::path& path) const;
  };

  // `format` names what the file holds and its version ("heslam-recorder-journal 2"): a file of
  // another format is not resumed from.
  RunJournal(std::filesystem::path path, std::string format);

  // Reads the records of run `run_id` if the file is that run's and keeps it open for append (after
  // cutting off the untrusted lines at its end); a file of another run or format, or none, is
  // replaced by an empty journal of this run. Throws std::runtime_error naming the file when it
  // cannot be written.
  Contents open_for_run(const std::string& run_id);

  // Appends one record and flushes it to the kernel. A failed write is not reported here: it shows
  // at the next open as a torn or missing line. A record with a newline throws std::invalid_argument.
  void append(std::string_view record);

  // Replaces the whole file at once by the open run's header and `records` (numbered from 1 again),
  // and keeps it open for append. Throws std::runtime_error naming the file when it cannot be written.
  void replace(std::span<const std::string> records);

  // Closes and deletes the file (the run is over).
  void remove();

  const std::filesystem::path& path() const { return path_; }

  // Whether the file at `path` is a run file of run `run_id` and `format` (for another process that
  // only needs to know whether the file's owner wrote it in this run).
  static bool written_by_run(const std::filesystem::path& path, const std::string& run_id, std::string_view format);

  // The line a record numbered `number` is written as, newline included (for tests that forge one).
  static std::string line(std::uint64_t number, std::string_view record);

 private:
  struct Close {
    void operator()(std::FILE* file) const { std::fclose(file); }
  };
  void open_for_append();

  std::filesystem::path path_;
  std::string format_;
  std::string header_;  // of the open run, newline included
  std::uint64_t next_number_ = 1;
  std::unique_ptr<std::FILE, Close> file_;
};

}  // namespace heslam::runtime
