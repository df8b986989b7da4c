// Several agents on one map (docs/agents.md): what a keyframe reader (the local mapper, a loop closer)
// refuses from the frontends that share the map/keyframes topic. Each frontend puts its agent id into
// its ids (ids.hpp), so a keyframe says which agent made it; this guard holds every writer to the agent
// of its first keyframe and every keyframe to a map that exists. Dependency-free (a writer is any
// 64-bit handle, e.g. the DDS publication handle), so it is unit-tested without DDS.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "components/core/map/ids.hpp"

namespace heslam {

class AgentKeyframeGuard {
 public:
  // `agents`: the agent ids 0 .. agents - 1 that may publish keyframes.
  explicit AgentKeyframeGuard(int agents) : agents_(agents) {}

  int agents() const { return agents_; }

  // Why keyframe `id` of map `map_id` from `writer` must be refused, or nothing. `map_exists` says
  // whether the reader's map holds keyframes of a map id. Refused: an id no agent's frontend made (or
  // of an agent beyond `agents`); a writer publishing the ids of another agent than its first keyframe's
  // (a frontend started with the wrong --agent, or one forging another's ids); a keyframe for a map that
  // neither exists nor belongs to its agent (an agent starts its own maps; another agent's map it may
  // join only once the reader holds it, i.e. after a merge).
  std::optional<std::string> check(std::uint64_t writer, std::uint64_t id, std::uint32_t map_id,
                                   const std::function<bool(std::uint32_t)>& map_exists) {
    const int agent = agent_of(id);
    if (agent < 0 || agent >= agents_) {
      return "keyframe " + format_id(id) + ": not made by the frontend of an agent 0.." + std::to_string(agents_ - 1);
    }
    const auto [bound, first] = writer_agent_.emplace(writer, agent);
    if (!first && bound->second != agent) {
      return "keyframe " + format_id(id) + " is agent " + std::to_string(agent) +
             "'s, but its writer publishes agent " + std::to_string(bound->second) +
             "'s keyframes (ids of another agent)";
    }
    if (agent_of_map(map_id) != agent && !map_exists(map_id)) {
      return "keyframe " + format_id(id) + " of agent " + std::to_string(agent) + " is for map " +
             std::to_string(map_id) + " (agent " + std::to_string(agent_of_map(map_id)) + "'s), which does not exist";
    }
    return std::nullopt;
  }

 private:
  int agents_;
  std::map<std::uint64_t, int> writer_agent_;  // each writer's agent: the one of its first keyframe
};

}  // namespace heslam
