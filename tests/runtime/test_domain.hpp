// A DDS domain id of this test process's own (ctest runs every TEST as its own process, so tests
// running in parallel never share a domain).
#pragma once

#include <unistd.h>

namespace heslam::test {

// 1..230: Cyclone allows up to 232; 0 is left to users' interactive runs.
inline int test_domain_id() { return 1 + static_cast<int>(getpid() % 230); }

}  // namespace heslam::test
