// Vocabulary files: DBoW2's text format (ORBvoc.txt, read and written unchanged) and heslam's own
// binary format, which loads a 1M-word tree in one read.
//
// DBoW2 text: first line "k L scoring weighting" (DBoW2's enum numbers), then one line per node
// other than the root, in node-id order starting at 1: "parent is_leaf d0 .. d31 weight" with the
// 32 descriptor bytes as decimal numbers.
//
// Binary (little-endian): "HESLAMVB", u32 format version, u32 k, u32 L, u32 scoring, u32 weighting,
// u32 reserved, u64 node count (without the root), then per-field arrays (u32 parent[n], u8
// is_leaf[n], u8 descriptor[n][32], f32 weight[n]), then a u64 checksum of everything before it:
// FNV-1a 64 taken over little-endian 64-bit words, the last < 8 bytes one by one (vocabulary_checksum;
// word-wise because byte-wise FNV-1a costs ~0.1 s on a 45 MB file, an eighth of that word-wise).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

#include "components/core/place/vocabulary.hpp"

namespace heslam {

inline constexpr std::uint32_t kVocabularyBinaryFormatVersion = 1;

enum class VocabularyFileFormat { kDbow2Text, kHeslamBinary };

// By content: the binary magic, else text. Throws std::runtime_error when the file cannot be read.
VocabularyFileFormat detect_vocabulary_format(const std::filesystem::path& path);

// All loaders throw std::runtime_error with one line "vocabulary <path>[:<line>]: <what>"
// (missing file, bad header, malformed node at which line, bad magic / version, truncated,
// checksum mismatch).
Vocabulary load_vocabulary(const std::filesystem::path& path);  // either format, by content
Vocabulary load_vocabulary_text(const std::filesystem::path& path);
Vocabulary load_vocabulary_binary(const std::filesystem::path& path);

// The binary format's checksum of `bytes` (see the top of this file).
std::uint64_t vocabulary_checksum(std::span<const char> bytes);

// Written to "<path>.tmp" and renamed over <path>. Throw std::runtime_error naming the path.
void save_vocabulary_text(const std::filesystem::path& path, const Vocabulary& vocabulary);
void save_vocabulary_binary(const std::filesystem::path& path, const Vocabulary& vocabulary);

}  // namespace heslam
