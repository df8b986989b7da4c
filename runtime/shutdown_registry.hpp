// Internal: the guard conditions request_shutdown() triggers (one per live WaitSet).
#pragma once

#include <dds/dds.h>

namespace heslam::runtime::detail {

void register_shutdown_guard(dds_entity_t guard);
void unregister_shutdown_guard(dds_entity_t guard);

}  // namespace heslam::runtime::detail
