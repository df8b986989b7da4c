// Write batching of the map state writers (see write_batch.hpp).
#include "components/local_mapper/write_batch.hpp"

namespace heslam::local_mapper {

BatchedWriterCreation::BatchedWriterCreation(bool enabled) : enabled_(enabled) {
  if (enabled_) dds_write_set_batch(true);
}

BatchedWriterCreation::~BatchedWriterCreation() {
  if (enabled_) dds_write_set_batch(false);
}

void flush_writes(std::initializer_list<dds_entity_t> writers) {
  for (const dds_entity_t writer : writers) dds_write_flush(writer);
}

}  // namespace heslam::local_mapper
