// LoopCorrection -> IDL sample (see message_adapter.hpp).
#include "components/loop_closer/message_adapter.hpp"

#include "components/frontend/message_adapter.hpp"
#include "runtime/sequence.hpp"

namespace heslam::loop_closer {

LoopCorrectionMessage::LoopCorrectionMessage(const LoopCorrection& correction) {
  poses_.reserve(correction.corrected_T_wc.size());
  for (const auto& [id, T_wc] : correction.corrected_T_wc) poses_.push_back({id, frontend::to_message(T_wc)});
  merges_.reserve(correction.point_merges.size());
  for (const auto& [from, into] : correction.point_merges) merges_.push_back({from, into});
  points_.reserve(correction.corrected_points.size());
  for (const auto& [id, p_w] : correction.corrected_points) points_.push_back({id, {p_w.x(), p_w.y(), p_w.z()}});
  message_.id = correction.id;
  message_.map_version = correction.map_version;
  message_.loop_keyframe_id = correction.loop_kf;
  message_.matched_keyframe_id = correction.matched_kf;
  message_.T_matched_loop = frontend::to_message(correction.T_matched_loop);
  runtime::borrow(message_.corrected_poses, poses_);
  runtime::borrow(message_.point_merges, merges_);
  message_.kind = correction.kind == CorrectionKind::kGlobalBundleAdjustment ? heslam_msg_CORRECTION_GLOBAL_BA
                                                                              : heslam_msg_CORRECTION_LOOP;
  runtime::borrow(message_.corrected_points, points_);
}

}  // namespace heslam::loop_closer
