// The 256 rBRIEF tests of one keypoint on the blurred level image: bit t of the descriptor (byte
// t / 8, bit t % 8) is 1 when the image at the test's first rotated point is darker than at its
// second, as ORB-SLAM2 and OpenCV compute it. With SSE4.1 the sampled pixels go straight from memory
// into the byte lanes of two vectors (pinsrb), 16 tests per unsigned compare and movemask: about 4
// instructions per test instead of 8 (load, compare, setb, shift, or per test); the scalar version
// is the reference.
#pragma once

#include <cstdint>

#include "components/core/feature/features.hpp"
#include "components/core/feature/rotated_orb_pattern.hpp"

namespace heslam {

// `center`: the keypoint's pixel in the blurred image; `offsets`: rotate_orb_pattern() with that
// image's row step (every offset must point at a readable pixel).
Descriptor rbrief_descriptor(const std::uint8_t* center, const RotatedOrbPattern& offsets);

// The same bits, one test at a time.
Descriptor rbrief_descriptor_scalar(const std::uint8_t* center, const RotatedOrbPattern& offsets);

}  // namespace heslam
