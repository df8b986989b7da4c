// quote_value: a user's value as an error line may show it. Header-only and dependency-free, so
// DDS-free libraries (the replay's option parser) use the same rule as every heslam program.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace heslam::runtime {

// At most max_chars characters (then "... (N bytes)"), every byte that is not printable UTF-8 as
// \xNN: a huge or binary value never floods a line or a terminal.
inline std::string quote_value(std::string_view text, std::size_t max_chars = 80) {
  std::string out;
  std::size_t chars = 0;
  std::size_t i = 0;
  while (i < text.size() && chars < max_chars) {
    const auto byte = static_cast<unsigned char>(text[i]);
    // The length of a valid UTF-8 sequence starting here (0: not one).
    std::size_t length = byte < 0x80             ? 1
                         : (byte & 0xE0) == 0xC0 ? 2
                         : (byte & 0xF0) == 0xE0 ? 3
                         : (byte & 0xF8) == 0xF0 ? 4
                                                 : 0;
    if (length > 1 && (i + length > text.size() || byte == 0xC0 || byte == 0xC1 || byte > 0xF4)) length = 0;
    for (std::size_t k = 1; k < length; ++k) {
      if ((static_cast<unsigned char>(text[i + k]) & 0xC0) != 0x80) length = 0;
    }
    if (length == 0 || (length == 1 && (byte < 0x20 || byte == 0x7F))) {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02X", byte);
      out += hex;
      ++i;
    } else {
      out.append(text.substr(i, length));
      i += length;
    }
    ++chars;
  }
  if (i < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace heslam::runtime
