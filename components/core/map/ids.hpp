// Keyframe, map point and loop correction ids: allocated without coordination, the creating
// process's tag in the top 8 bits and a per-creator counter (starting at 1) below. Header-only and
// dependency-free, so tools (heslam-spy) can show an id as its creator and counter.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace heslam {

inline constexpr int kIdTagShift = 56;
inline constexpr std::uint64_t kIdCounterMask = (1ULL << kIdTagShift) - 1;

inline constexpr std::uint64_t make_id(std::uint8_t creator_tag, std::uint64_t counter) {
  return (static_cast<std::uint64_t>(creator_tag) << kIdTagShift) | (counter & kIdCounterMask);
}
inline constexpr std::uint8_t creator_of(std::uint64_t id) { return static_cast<std::uint8_t>(id >> kIdTagShift); }
inline constexpr std::uint64_t counter_of(std::uint64_t id) { return id & kIdCounterMask; }

// Creator tags of the shipped processes.
inline constexpr std::uint8_t kFrontendTag = 1;
inline constexpr std::uint8_t kMapperTag = 2;
inline constexpr std::uint8_t kLoopCloserTag = 3;

// Several agents (docs/agents.md): each frontend has an agent id, 0 (a single agent: the tag and ids of
// before) to kMaxAgentId, that goes into every id it creates without asking anyone. Agent 0's frontend
// tags its ids kFrontendTag; agent a > 0's kAgentTagBase + a, so the ids of two agents never collide
// and the creating agent can be read from any keyframe or point id.
inline constexpr std::uint8_t kAgentTagBase = 0x40;
inline constexpr int kMaxAgentId = 63;
inline constexpr std::uint8_t frontend_tag(int agent) {
  return agent == 0 ? kFrontendTag : static_cast<std::uint8_t>(kAgentTagBase + agent);
}
// The agent whose frontend created `id`, -1 when no frontend did (the mapper's, the loop closer's, 0).
inline constexpr int agent_of(std::uint64_t id) {
  const std::uint8_t tag = creator_of(id);
  if (tag == kFrontendTag) return 0;
  if (tag > kAgentTagBase && tag <= kAgentTagBase + kMaxAgentId) return tag - kAgentTagBase;
  return -1;
}

// Map ids carry their agent too: agent a numbers its maps a * 2^24 + 0, 1, 2, ... (agent 0: 0, 1, 2, as
// before). A merged map keeps the id of the map it was merged into, whichever agent started that one.
inline constexpr int kMapIdAgentShift = 24;
inline constexpr std::uint32_t first_map_id(int agent) { return static_cast<std::uint32_t>(agent) << kMapIdAgentShift; }
inline constexpr int agent_of_map(std::uint32_t map_id) { return static_cast<int>(map_id >> kMapIdAgentShift); }

// Short creator names for people: "fe" frontend, "lm" local mapper, "lc" loop closer; nullptr for
// another tag.
inline const char* creator_name(std::uint8_t tag) {
  switch (tag) {
    case kFrontendTag: return "fe";
    case kMapperTag: return "lm";
    case kLoopCloserTag: return "lc";
    default: return nullptr;
  }
}

// The one form of a keyframe / point / correction id in every output (spy, log lines, errors):
// "fe:17" for the frontend's 17th id ("fe2:17" for agent 2's); a creator-less id (tag 0: "0" for no id, the small ids
// of tests) as its plain number; an unknown creator as hex ("0x0700000000000005") so the tag stays visible. Files
// (maps, journals, trajectories) keep the full 64-bit number.
inline std::string format_id(std::uint64_t id) {
  if (creator_of(id) == 0) return std::to_string(id);
  if (const int agent = agent_of(id); agent > 0)
    return "fe" + std::to_string(agent) + ":" + std::to_string(counter_of(id));
  if (const char* name = creator_name(creator_of(id)); name != nullptr) {
    return std::string(name) + ":" + std::to_string(counter_of(id));
  }
  char hex[24];
  std::snprintf(hex, sizeof hex, "0x%016llx", static_cast<unsigned long long>(id));
  return hex;
}

}  // namespace heslam
