// The local mapper: owner of the map after keyframe creation (ORB-SLAM2's LocalMapping thread as a
// plain class; the DDS process in components/local_mapper/ wraps it).
//
// process_keyframe runs, in order: insertion (observations, point statistics, covisibility, spanning
// tree), recent point culling, triangulation, fusion, local bundle adjustment and keyframe culling,
// and returns what changed so the caller can publish exactly that. apply_correction applies a loop
// closer's LoopCorrection. The map version is bumped once per call that changed anything.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/local_bundle_adjustment.hpp"
#include "components/core/mapping/local_mapper_options.hpp"
#include "components/core/mapping/loop_correction.hpp"
#include "components/core/mapping/map_changes.hpp"
#include "components/core/mapping/map_file.hpp"
#include "components/core/mapping/mapper_state.hpp"

namespace heslam {

class LocalMapper {
 public:
  LocalMapper(const PinholeStereo& camera, const LocalMapperOptions& options);
  // Resumes from a snapshot (map file load).
  LocalMapper(const PinholeStereo& camera, const LocalMapperOptions& options, MapSnapshot snapshot);

  // `kf.point_ids` may reference existing points and the `new_points` (the frontend's stereo points,
  // each referenced by exactly the keypoint that created it). References to unknown points are
  // dropped and counted; references to merged points follow the merge. Throws std::invalid_argument
  // when the keyframe is malformed (duplicate id, mismatched vector sizes).
  // `tracked`: what the frontend tracked the keyframe against. A keyframe tracked at a map version
  // older than a correction applied since is first moved, with its new points, as its reference
  // keyframe was moved (correction_history.hpp); without a reference it is inserted as it comes.
  MapChanges process_keyframe(Keyframe kf, std::vector<MapPoint> new_points, const TrackedAgainst& tracked = {});

  MapChanges apply_correction(const LoopCorrection& correction);

  // A local BA run instead of the visual one (the inertial BA, inertial_mapping.hpp); when it returns
  // nothing, the visual BA runs. Unset (the default): the visual BA always.
  using BundleAdjustment = std::function<std::optional<LocalBundleAdjustmentResult>(
      Map&, KeyframeId, const PinholeStereo&, const LocalBundleAdjustmentOptions&, MapChanges&)>;
  void set_bundle_adjustment(BundleAdjustment bundle_adjustment) { bundle_adjustment_ = std::move(bundle_adjustment); }

  const Map& map() const { return map_; }
  const MapperState& state() const { return state_; }
  const PinholeStereo& camera() const { return camera_; }

  // Snapshot of map + state (see map_file.hpp).
  MapFileWriteStats save(const std::filesystem::path& path, bool sync = false) const;

 private:
  void insert_keyframe(Keyframe kf, std::vector<MapPoint> new_points, const TrackedAgainst& tracked,
                       MapChanges& changes);
  // At keyframe `current`: the recent points of its agent (several agents: each ages in its own).
  void cull_recent_points(KeyframeId current, MapChanges& changes);
  void record_removed(const MapChanges& changes);
  void refresh_culled_keyframes(MapChanges& changes);
  PointId resolve_merges(PointId id) const;

  PinholeStereo camera_;
  LocalMapperOptions options_;
  Map map_;
  MapperState state_;
  // Recent points of one agent: the keyframes of other agents processed since they were made, which
  // their age leaves out (not saved: a resumed mapper counts them again from the map, local_mapper.cpp).
  std::map<PointId, std::uint64_t> other_agents_keyframes_;
  // Every map id a keyframe was inserted in (the loaded map's too): one of them without keyframes now was
  // merged into another (correction_application.cpp relabels a merged map's keyframes).
  std::set<MapId> maps_seen_;
  BundleAdjustment bundle_adjustment_;
};

}  // namespace heslam
