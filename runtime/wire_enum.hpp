// IDL enum fields read and written as the integers they hold on the wire.
//
// idlc makes C enums without a fixed underlying type. In C++ such an enum only has the values of
// the smallest bit field that holds its enumerators (0..3 for three enumerators); loading any other
// value through the enum type is undefined behaviour (UBSan: "load of value 7, which is not a valid
// value for type 'heslam_msg_TrackingState'"), and the optimiser may assume it never happens (a
// `default:` that reports "unknown value" can be dropped). A sample, a journal line or a file can
// hold any 32-bit value there, so code that checks or prints such a field reads its bytes as the
// underlying integer (wire_value) and compares that with the enumerators; only a checked field is
// then used as the enum.
#pragma once

#include <cstdint>
#include <cstring>
#include <type_traits>

namespace heslam::runtime {

// The integer an IDL enum field holds, whatever it is (no load through the enum type).
template <typename Enum>
requires std::is_enum_v<Enum> std::int64_t wire_value(const Enum& field) {
  std::underlying_type_t<Enum> raw;
  std::memcpy(&raw, &field, sizeof raw);
  return static_cast<std::int64_t>(raw);
}

// Stores `value` into an IDL enum field as the wire would (a parsed journal or file field, or a test
// making a hostile sample); check it with wire_value before using the field as the enum.
template <typename Enum>
requires std::is_enum_v<Enum>
void set_wire_value(Enum& field, std::int64_t value) {
  const auto raw = static_cast<std::underlying_type_t<Enum>>(value);
  std::memcpy(&field, &raw, sizeof raw);
}

// True when the field holds one of `enumerators`.
template <typename Enum, typename... Enumerators>
requires std::is_enum_v<Enum>
bool wire_value_is_one_of(const Enum& field, Enumerators... enumerators) {
  const std::int64_t value = wire_value(field);
  return ((value == static_cast<std::int64_t>(enumerators)) || ...);
}

}  // namespace heslam::runtime
