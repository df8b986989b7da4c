// Write batching of the map state writers: the samples of one publish packed into few RTPS messages.
//
// Without it every dds_write of a map state goes out as its own UDP datagram to every matched
// participant: on the KITTI-size street a keyframe changes ~5000 points, and the mapper then spent a
// quarter of its CPU in sendmsg (73000 calls in 20 s; docs/benchmarks.md at 5c1f792, "Local mapper cost,
// street and publish"), the receivers one wake-up per datagram. Cyclone 0.10 has no per-writer batching QoS
// (it came with 0.11): a writer batches when the domain's WriteBatch setting was on when it was
// created, and dds_write_set_batch() changes that setting (in 0.10.2 its push-down to existing
// writers does not reach writers under a publisher, i.e. all of them, so it acts on new writers
// only). BatchedWriterCreation turns it on for the creation of the state writers and off again, so
// no other writer of the process batches; flush_writes() sends what a publish left packed. Samples,
// their order per writer and the topics' meaning are unchanged; a publish's states leave before the
// KeyframeDone that follows it (flushed first); a writer that has to wait for acknowledgements
// (history full) flushes by itself (Cyclone's throttle_writer). Should a Cyclone push the setting
// down after all, the writers simply do not batch (every write sent at once, as before).
#pragma once

#include <initializer_list>

#include <dds/dds.h>

namespace heslam::local_mapper {

class BatchedWriterCreation {
 public:
  explicit BatchedWriterCreation(bool enabled);  // false: a no-op
  ~BatchedWriterCreation();
  BatchedWriterCreation(const BatchedWriterCreation&) = delete;
  BatchedWriterCreation& operator=(const BatchedWriterCreation&) = delete;

 private:
  bool enabled_;
};

// Sends what the writers hold packed (nothing when they do not batch).
void flush_writes(std::initializer_list<dds_entity_t> writers);

}  // namespace heslam::local_mapper
