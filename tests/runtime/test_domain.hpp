// A DDS domain id of this test process's own (ctest runs every TEST as its own process, so tests
// running in parallel never share a domain).
#pragma once

#include "test_support.hpp"

namespace heslam::test {

inline int test_domain_id() { return exclusive_domain_id(); }

}  // namespace heslam::test
