// RunJournal: records of this run come back in order; a torn last line is cut off and the next record
// starts a line of its own; a line failing its checksum, a line out of sequence and every line after
// a lost one are dropped and counted; a file of another run or format is replaced.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "runtime/run_journal.hpp"
#include "test_support.hpp"

namespace heslam::runtime {
namespace {

constexpr const char* kFormat = "heslam-test-journal 1";

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void append_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::app | std::ios::binary) << text;
}

// A journal of run "run-a" holding `records`, closed.
void write_journal(const std::filesystem::path& path, const std::vector<std::string>& records) {
  RunJournal journal(path, kFormat);
  journal.open_for_run("run-a");
  for (const std::string& record : records) journal.append(record);
}

TEST(RunJournal, RecordsOfTheRunComeBackInOrder) {
  const test::ScratchDir dir("run_journal_order");
  const auto path = dir.path() / "sub" / "a.journal";  // the folder is created
  write_journal(path, {"first", "", "with #3 abc inside", "last"});
  EXPECT_EQ(read_text(path).substr(0, 28), "run-a heslam-test-journal 1\n");
  RunJournal journal(path, kFormat);
  const RunJournal::Contents contents = journal.open_for_run("run-a");
  EXPECT_TRUE(contents.same_run);
  EXPECT_FALSE(contents.other_file_replaced);
  EXPECT_EQ(contents.records, (std::vector<std::string>{"first", "", "with #3 abc inside", "last"}));
  EXPECT_EQ(contents.dropped_lines(), 0);
  EXPECT_EQ(contents.torn_lines, 0);
  EXPECT_EQ(contents.dropped_report(path), "");
}

TEST(RunJournal, ATornLastLineIsCutOffAndTheNextRecordContinuesTheSequence) {
  const test::ScratchDir dir("run_journal_torn");
  const auto path = dir.path() / "a.journal";
  write_journal(path, {"one", "two"});
  const std::string complete = read_text(path);
  append_text(path, "three #3 12");  // killed mid-write
  {
    RunJournal journal(path, kFormat);
    const RunJournal::Contents contents = journal.open_for_run("run-a");
    EXPECT_EQ(contents.records, (std::vector<std::string>{"one", "two"}));
    EXPECT_EQ(contents.torn_lines, 1);
    EXPECT_EQ(contents.dropped_lines(), 0);
    EXPECT_EQ(read_text(path), complete);  // cut back to the last complete line
    journal.append("three");
  }
  RunJournal journal(path, kFormat);
  const RunJournal::Contents contents = journal.open_for_run("run-a");
  EXPECT_EQ(contents.records, (std::vector<std::string>{"one", "two", "three"}));
  EXPECT_EQ(contents.torn_lines, 0);
  EXPECT_EQ(contents.dropped_lines(), 0);
}

TEST(RunJournal, ALineFailingItsChecksumIsDroppedAndCounted) {
  const test::ScratchDir dir("run_journal_checksum");
  const auto path = dir.path() / "a.journal";
  write_journal(path, {"one", "two", "three"});
  std::string text = read_text(path);
  const std::size_t two = text.find("two");
  text[two] = 'T';  // a well-formed line that is not what was written
  std::ofstream(path, std::ios::trunc | std::ios::binary) << text;
  append_text(path, "forged #4 00000000\n");  // right format, wrong checksum
  RunJournal journal(path, kFormat);
  const RunJournal::Contents contents = journal.open_for_run("run-a");
  // "three" comes after a lost line: what it records may depend on it, so it is not trusted either.
  EXPECT_EQ(contents.records, std::vector<std::string>{"one"});
  EXPECT_EQ(contents.bad_checksum_lines, 2);
  EXPECT_EQ(contents.out_of_sequence_lines, 1);
  EXPECT_EQ(contents.dropped_report(path),
            path.string() + ": 3 lines dropped, not resumed from (2 failing their checksum, 1 out of sequence)");
}

TEST(RunJournal, ALineOutOfSequenceIsDroppedAndCounted) {
  const test::ScratchDir dir("run_journal_sequence");
  const auto path = dir.path() / "a.journal";
  write_journal(path, {"one", "two"});
  append_text(path, RunJournal::line(2, "a second two"));  // a valid line, but a repeated number
  append_text(path, RunJournal::line(5, "five"));          // and one after a gap
  {
    RunJournal journal(path, kFormat);
    const RunJournal::Contents contents = journal.open_for_run("run-a");
    EXPECT_EQ(contents.records, (std::vector<std::string>{"one", "two"}));
    EXPECT_EQ(contents.bad_checksum_lines, 0);
    EXPECT_EQ(contents.out_of_sequence_lines, 2);
    journal.append("three");  // after the untrusted lines, which are cut off
  }
  RunJournal journal(path, kFormat);
  const RunJournal::Contents contents = journal.open_for_run("run-a");
  EXPECT_EQ(contents.records, (std::vector<std::string>{"one", "two", "three"}));
  EXPECT_EQ(contents.dropped_lines(), 0);  // reported once, not at every open
}

TEST(RunJournal, AFileOfAnotherRunOrFormatIsReplacedByAnEmptyOne) {
  const test::ScratchDir dir("run_journal_other_run");
  const auto path = dir.path() / "a.journal";
  write_journal(path, {"one"});
  {
    RunJournal journal(path, kFormat);
    const RunJournal::Contents contents = journal.open_for_run("run-b");
    EXPECT_FALSE(contents.same_run);
    EXPECT_TRUE(contents.other_file_replaced);
    EXPECT_TRUE(contents.records.empty());
    journal.append("b-one");
  }
  {
    RunJournal journal(path, "heslam-test-journal 2");
    EXPECT_TRUE(journal.open_for_run("run-b").records.empty());  // another format: replaced too
  }
  RunJournal journal(path, "heslam-test-journal 2");
  const RunJournal::Contents contents = journal.open_for_run("run-b");
  EXPECT_TRUE(contents.same_run);
  EXPECT_TRUE(contents.records.empty());
  RunJournal fresh(dir.path() / "none.journal", kFormat);
  const RunJournal::Contents none = fresh.open_for_run("run-a");
  EXPECT_FALSE(none.same_run);
  EXPECT_FALSE(none.other_file_replaced);
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "none.journal"));
}

TEST(RunJournal, ReplaceRewritesTheWholeFileAndAppendsContinueAfterIt) {
  const test::ScratchDir dir("run_journal_replace");
  const auto path = dir.path() / "state";
  {
    RunJournal journal(path, kFormat);
    journal.open_for_run("run-a");
    journal.append("old");
    const std::vector<std::string> state = {"last 7", "counter 2"};
    journal.replace(state);
    journal.append("loop 1 5");
  }
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".tmp"));
  RunJournal journal(path, kFormat);
  EXPECT_EQ(journal.open_for_run("run-a").records, (std::vector<std::string>{"last 7", "counter 2", "loop 1 5"}));
  journal.remove();
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(RunJournal, AnUnwritableFileThrowsNamingIt) {
  RunJournal journal("/proc/heslam_no_such_dir/a.journal", kFormat);
  try {
    journal.open_for_run("run-a");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("/proc/heslam_no_such_dir/a.journal"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace heslam::runtime
