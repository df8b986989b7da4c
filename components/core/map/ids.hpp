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
// "fe:17" for the frontend's 17th id; a creator-less id (tag 0: "0" for no id, the small ids of
// tests) as its plain number; an unknown creator as hex ("0x0700000000000005") so the tag stays
// visible. Files (maps, journals, trajectories) keep the full 64-bit number.
inline std::string format_id(std::uint64_t id) {
  if (creator_of(id) == 0) return std::to_string(id);
  if (const char* name = creator_name(creator_of(id)); name != nullptr) {
    return std::string(name) + ":" + std::to_string(counter_of(id));
  }
  char hex[24];
  std::snprintf(hex, sizeof hex, "0x%016llx", static_cast<unsigned long long>(id));
  return hex;
}

}  // namespace heslam
