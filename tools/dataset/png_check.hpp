// A structural check of a PNG file before it is decoded: signature, every chunk inside the file with
// a correct CRC, an IHDR with a plausible size, an IEND. libpng reports a truncated or corrupt file
// by printing "libpng error: Read Error" on stderr (a line naming no file) before OpenCV gives up,
// and a corrupt header size makes OpenCV throw its own allocation errors; this check finds those
// files first and says which file and what is wrong.
//
// API:
//   if (is_png(bytes)) check_png(bytes);   // throws std::runtime_error("truncated PNG: ...") etc.
#pragma once

#include <cstdint>
#include <span>

namespace heslam {

bool is_png(std::span<const std::uint8_t> bytes);

// Throws std::runtime_error with what is wrong (no file name: the caller adds it).
void check_png(std::span<const std::uint8_t> bytes);

}  // namespace heslam
