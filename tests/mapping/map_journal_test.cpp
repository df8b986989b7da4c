// The map file's journal (map_journal.hpp): snapshot + journal is the map a full snapshot holds, to the
// byte, through triangulation, fusion, local BA, culling and loop corrections with point merges; a torn
// or damaged last record is dropped with one warning and the map is that of the complete records; a
// stale journal is ignored; compaction keeps the journal below the snapshot.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "components/core/mapping/local_mapper.hpp"
#include "components/core/mapping/map_file.hpp"
#include "components/core/mapping/map_journal.hpp"
#include "tests/mapping/correction_test_util.hpp"
#include "tests/mapping/synthetic_world.hpp"

namespace heslam {
namespace {

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() / ("heslam_journal_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

std::vector<char> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {(std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::filesystem::path& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::vector<std::uint8_t> payload_of(const MapSnapshot& snapshot) {
  return serialize_map_payload(snapshot.map, snapshot.state, snapshot.camera ? &*snapshot.camera : nullptr);
}

class MapJournalTest : public ::testing::Test {
 protected:
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Keyframe k of the synthetic circle (k may exceed one lap: the later ones revisit the first ones'
  // places, so fusion merges and culling happen).
  MapChanges map_keyframe(int k) {
    auto view =
        test::make_view(world_, static_cast<KeyframeId>(k + 1), test::circle_pose(k), 1000 + static_cast<unsigned>(k));
    auto [kf, points] = frontend_.keyframe(mapper_.map(), view, view.kf.T_wc);
    return mapper_.process_keyframe(std::move(kf), std::move(points));
  }

  // A loop correction moving the newest keyframes a little and merging two points they observe.
  MapChanges correct(std::uint64_t id) {
    LoopCorrection correction;
    correction.id = id;
    correction.map_version = mapper_.map().version;
    const Pose3 T = test::motion(0.01, Eigen::Vector3d::UnitY(), Eigen::Vector3d(0.02, 0.0, -0.01));
    auto it = mapper_.map().keyframes.rbegin();
    for (int n = 0; n < 3 && it != mapper_.map().keyframes.rend(); ++n, ++it) {
      if (!it->second.culled) correction.corrected_T_wc.emplace_back(it->first, T * it->second.T_wc);
    }
    auto point = mapper_.map().points.begin();
    const PointId from = point->first;
    const PointId into = std::next(point)->first;
    correction.point_merges.emplace_back(from, into);
    return mapper_.apply_correction(correction);
  }

  // After each save: the payload a full snapshot of the map in memory would have.
  std::vector<std::uint8_t> expected() const {
    return serialize_map_payload(mapper_.map(), mapper_.state(), &mapper_.camera());
  }

  std::filesystem::path dir_ = temp_dir();
  std::filesystem::path file_ = dir_ / "map.map";
  test::SyntheticWorld world_ = test::make_room(1500, 81);
  LocalMapper mapper_{world_.camera, LocalMapperOptions{}};
  test::FrontendEmulator frontend_{world_};
};

MapJournalOptions journal_only() {
  MapJournalOptions options;
  options.compact_ratio = 100.0;  // no compaction: every save after the first is a record
  return options;
}

// The known answer: after every keyframe (and two loop corrections), the file read back (snapshot + the
// records so far) is, byte for byte, the full snapshot of the map the mapper holds.
TEST_F(MapJournalTest, SnapshotPlusJournalEqualsTheFullSnapshot) {
  MapJournal journal(file_, journal_only());
  int culled = 0;
  int merged = 0;
  for (int k = 0; k < 70; ++k) {
    MapChanges changes = map_keyframe(k);
    if (k == 30 || k == 60) changes.merge(correct(static_cast<std::uint64_t>(k)));
    culled += changes.counts.culled_keyframes;
    for (const auto& [id, into] : changes.removed_points) merged += into != kNoId ? 1 : 0;
    const MapSaveStats saved = journal.save(mapper_.map(), mapper_.state(), &mapper_.camera(), changes);
    EXPECT_EQ(saved.snapshot, k == 0) << k;
    const MapSnapshot loaded = load_map_file(file_);
    EXPECT_EQ(loaded.journal.records, static_cast<std::uint64_t>(k));
    EXPECT_TRUE(loaded.journal.warning.empty()) << loaded.journal.warning;
    const auto difference = first_map_difference(loaded.map, loaded.state, mapper_.map(), mapper_.state());
    ASSERT_FALSE(difference.has_value()) << "keyframe " << k << ": " << *difference;
    ASSERT_EQ(payload_of(loaded), expected()) << "keyframe " << k;
  }
  // The run exercised what a record must carry beyond new keyframes and moved points.
  EXPECT_GT(culled, 0);
  EXPECT_GT(merged, 0);
  EXPECT_FALSE(mapper_.state().merged_into.empty());
  EXPECT_FALSE(mapper_.state().culled_T_pc.empty());

  // A full snapshot of the same map, written as the mapper did before the journal, reads the same.
  const auto full = dir_ / "full.map";
  mapper_.save(full);
  EXPECT_EQ(payload_of(load_map_file(full)), payload_of(load_map_file(file_)));
  // A mapper resumed from snapshot + journal goes on exactly as the one that never stopped.
  LocalMapper resumed(world_.camera, LocalMapperOptions{}, load_map_file(file_));
  test::FrontendEmulator frontend_copy = frontend_;
  for (int k = 70; k < 74; ++k) {
    map_keyframe(k);
    auto view =
        test::make_view(world_, static_cast<KeyframeId>(k + 1), test::circle_pose(k), 1000 + static_cast<unsigned>(k));
    auto [kf, points] = frontend_copy.keyframe(resumed.map(), view, view.kf.T_wc);
    resumed.process_keyframe(std::move(kf), std::move(points));
  }
  EXPECT_FALSE(first_map_difference(resumed.map(), resumed.state(), mapper_.map(), mapper_.state()).has_value());
}

// A writer killed mid-record: the last record cut anywhere (or a byte of it damaged) is dropped with
// one warning, and the map is the one after the complete records (known answer: the payload saved
// then).
TEST_F(MapJournalTest, TornLastRecordIsDroppedWithOneWarning) {
  MapJournal journal(file_, journal_only());
  std::vector<std::vector<std::uint8_t>> after;  // the map after save k
  std::vector<std::uint64_t> journal_size;       // the journal's size after save k
  for (int k = 0; k < 8; ++k) {
    const MapChanges changes = map_keyframe(k);
    journal.save(mapper_.map(), mapper_.state(), &mapper_.camera(), changes);
    after.push_back(expected());
    journal_size.push_back(std::filesystem::file_size(map_journal_path(file_)));
  }
  const std::vector<char> whole = read_bytes(map_journal_path(file_));
  const std::size_t last_start = journal_size[6];
  const std::size_t last_size = whole.size() - last_start;
  ASSERT_GT(last_size, 100u);
  for (const std::size_t keep :
       {std::size_t{1}, std::size_t{7}, std::size_t{8}, last_size / 2, last_size - 8, last_size - 1}) {
    std::vector<char> torn(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(last_start + keep));
    write_bytes(map_journal_path(file_), torn);
    const MapSnapshot loaded = load_map_file(file_);
    EXPECT_EQ(loaded.journal.records, 6u) << keep;
    EXPECT_EQ(loaded.journal.dropped_bytes, keep);
    EXPECT_NE(loaded.journal.warning.find("record 7 is incomplete"), std::string::npos) << loaded.journal.warning;
    EXPECT_EQ(loaded.journal.warning.find('\n'), std::string::npos);
    EXPECT_EQ(payload_of(loaded), after[6]) << keep;
  }
  std::vector<char> damaged = whole;
  damaged[last_start + last_size / 2] ^= 0x5a;
  write_bytes(map_journal_path(file_), damaged);
  const MapSnapshot loaded = load_map_file(file_);
  EXPECT_EQ(loaded.journal.records, 6u);
  EXPECT_NE(loaded.journal.warning.find("record 7 fails its checksum"), std::string::npos) << loaded.journal.warning;
  EXPECT_EQ(payload_of(loaded), after[6]);
  // Only the header left (a writer killed before its first record): the snapshot, no warning.
  write_bytes(map_journal_path(file_), std::vector<char>(whole.begin(), whole.begin() + 24));
  const MapSnapshot header_only = load_map_file(file_);
  EXPECT_EQ(payload_of(header_only), after[0]);
  EXPECT_TRUE(header_only.journal.warning.empty());
  // Untouched: every record.
  write_bytes(map_journal_path(file_), whole);
  EXPECT_EQ(payload_of(load_map_file(file_)), after[7]);
}

// Compaction: the journal stays below compact_ratio x the snapshot (plus one record), a new snapshot
// replaces the journal, and a journal of an earlier snapshot (the writer killed between the snapshot's
// rename and the new journal) is ignored.
TEST_F(MapJournalTest, CompactionBoundsTheJournalAndAStaleJournalIsIgnored) {
  MapJournalOptions options;
  options.compact_ratio = 0.5;
  MapJournal journal(file_, options);
  int snapshots = 0;
  std::vector<char> stale;
  for (int k = 0; k < 30; ++k) {
    const std::vector<char> before =
        std::filesystem::exists(map_journal_path(file_)) ? read_bytes(map_journal_path(file_)) : std::vector<char>{};
    const MapSaveStats saved = journal.save(mapper_.map(), mapper_.state(), &mapper_.camera(), map_keyframe(k));
    if (saved.snapshot) {
      ++snapshots;
      if (snapshots == 2) stale = before;
    }
    EXPECT_LE(static_cast<double>(saved.journal_bytes), 0.5 * static_cast<double>(saved.snapshot_bytes) + saved.bytes);
    EXPECT_EQ(payload_of(load_map_file(file_)), expected()) << k;
  }
  EXPECT_GE(snapshots, 3);
  ASSERT_FALSE(stale.empty());
  write_bytes(map_journal_path(file_), stale);
  const MapSnapshot loaded = load_map_file(file_);
  EXPECT_TRUE(loaded.journal.stale);
  EXPECT_EQ(loaded.journal.records, 0u);
  // The final compaction (keep_journal false) leaves a plain snapshot.
  journal.compact(mapper_.map(), mapper_.state(), &mapper_.camera(), /*keep_journal=*/false);
  EXPECT_FALSE(std::filesystem::exists(map_journal_path(file_)));
  EXPECT_EQ(payload_of(load_map_file(file_)), expected());
}

// Disabled, every save is a snapshot and no journal exists (the behaviour before the journal).
TEST_F(MapJournalTest, DisabledWritesSnapshotsOnly) {
  MapJournalOptions options;
  options.enabled = false;
  MapJournal journal(file_, options);
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(journal.save(mapper_.map(), mapper_.state(), &mapper_.camera(), map_keyframe(k)).snapshot);
  }
  EXPECT_FALSE(std::filesystem::exists(map_journal_path(file_)));
  EXPECT_EQ(payload_of(load_map_file(file_)), expected());
}

}  // namespace
}  // namespace heslam
