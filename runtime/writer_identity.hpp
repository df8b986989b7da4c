// Who wrote a sample: the matched writers of a reader and their GUIDs, for readers of topics that
// expect one writer (runtime/single_writer_reader.hpp). Plain functions over the Cyclone C API.
#pragma once

#include <string>

#include <dds/dds.h>

namespace heslam::runtime {

// Whether the writer `publication` (SampleInfo::publication_handle) is still matched with `reader`:
// false once it was deleted, or its process died and its lease expired.
bool writer_matched(dds_entity_t reader, dds_instance_handle_t publication);

// "GUID 0110abcd:...:00000102" of a matched writer (the participant's prefix identifies the process),
// or "publication handle N" when it is no longer matched.
std::string describe_writer(dds_entity_t reader, dds_instance_handle_t publication);

}  // namespace heslam::runtime
