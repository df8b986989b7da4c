// Who wrote a sample: the matched writers of a reader, their GUIDs and the run they belong to, for
// readers of topics that expect one writer (runtime/checked_reader.hpp). Plain functions over the
// Cyclone C API.
#pragma once

#include <optional>
#include <string>

#include <dds/dds.h>

namespace heslam::runtime {

// Whether the writer `publication` (SampleInfo::publication_handle) is still matched with `reader`:
// false once it was deleted, or its process died and its lease expired.
bool writer_matched(dds_entity_t reader, dds_instance_handle_t publication);

// "GUID 0110abcd:...:00000102" of a matched writer (the participant's prefix identifies the process),
// or "publication handle N" when it is no longer matched.
std::string describe_writer(dds_entity_t reader, dds_instance_handle_t publication);

// The run id a matched writer advertises in its user data (Writer<T> sets the process's run,
// runtime/run_id.hpp): "" when it advertises none (a writer that is not heslam's), nothing when it
// is no longer matched (nothing can be known about it then).
std::optional<std::string> writer_run_id(dds_entity_t reader, dds_instance_handle_t publication);

// The 24 hex digits of a GUID's participant prefix (its first 12 bytes: host, process, instance).
std::string guid_prefix_hex(const unsigned char* guid);

// The GUID prefix (guid_prefix_hex) of the participant of a matched writer: the process that wrote
// a sample; nothing when the writer is no longer matched.
std::optional<std::string> writer_participant(dds_entity_t reader, dds_instance_handle_t publication);

// Whether a sample of `publication` may be used by a reader of a topic with several legitimate
// writers (lockstep/frame_done, lockstep/keyframe_done): always, unless this run is on one host
// (run_on_one_host()) and the writer is of another run or left before it could be asked. Each call
// asks every writer matched at that moment and remembers the answers, so a writer that was matched
// at any earlier call is still known after it left (its last samples, written just before it
// exited, are used); only a writer that matched, wrote and left between two calls is unknown.
bool writer_of_this_run(dds_entity_t reader, dds_instance_handle_t publication);

}  // namespace heslam::runtime
