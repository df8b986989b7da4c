// Bridging IDL sequences/strings and C++ containers without copies where possible.
//
// Writing: borrow() points a sequence at a std::vector the caller keeps alive until write() returns
// (dds_write serialises immediately; _release=false so Cyclone never frees it).
// Reading: view() gives a std::span over a taken sample's sequence, valid while the Sample lives.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace heslam::runtime {

// Any idlc sequence struct: {_maximum, _length, _buffer, _release}.
template <typename Seq>
concept IdlSequence = requires(Seq seq) {
  seq._maximum;
  seq._length;
  seq._buffer;
  seq._release;
};

template <IdlSequence Seq>
using SequenceElement = std::remove_pointer_t<decltype(Seq::_buffer)>;

// Points seq at values (no copy). values must outlive every write of the sample.
template <IdlSequence Seq>
void borrow(Seq& seq, std::vector<SequenceElement<Seq>>& values) {
  seq._buffer = values.data();
  seq._length = static_cast<uint32_t>(values.size());
  seq._maximum = seq._length;
  seq._release = false;
}

// Read-only overload for const data (dds_write never modifies the buffer).
template <IdlSequence Seq>
void borrow(Seq& seq, std::span<const SequenceElement<Seq>> values) {
  seq._buffer = const_cast<SequenceElement<Seq>*>(values.data());
  seq._length = static_cast<uint32_t>(values.size());
  seq._maximum = seq._length;
  seq._release = false;
}

template <IdlSequence Seq>
std::span<const SequenceElement<Seq>> view(const Seq& seq) {
  if (seq._buffer == nullptr) return {};
  return {seq._buffer, seq._length};
}

// A char* field for writing from a std::string the caller keeps alive.
inline char* borrow(const std::string& text) { return const_cast<char*>(text.c_str()); }

// A string field of a taken sample ("" when null).
inline std::string to_string(const char* text) { return text == nullptr ? std::string{} : std::string{text}; }

}  // namespace heslam::runtime
