// A digest of a map's point ids, printed by the local mapper ("map: ...") and the loop closer ("map copy:
// ...") at shutdown: two holders of the map hold the same points exactly when the counts and digests match
// (the recovery tests compare the loop closer's mirror with the mapper's map this way).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

#include "components/core/map/map.hpp"

namespace heslam {

// FNV-1a over the ids in the map's (ascending) order, as 16 hex digits.
inline std::string point_ids_digest(const Map& map) {
  std::uint64_t hash = 14695981039346656037ull;
  for (const auto& [id, point] : map.points) {
    for (int byte = 0; byte < 8; ++byte) {
      hash ^= (id >> (8 * byte)) & 0xffu;
      hash *= 1099511628211ull;
    }
  }
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

}  // namespace heslam
