// The one place a "vocabulary" setting (the frontend's `vocabulary.file`, heslam-frontend-offline's
// `--vocabulary`) becomes a vocabulary: empty = the build's default vocabulary, "none" = no vocabulary
// (no keyframe database; relocalization against the newest keyframes only), anything else a file.
#pragma once

#include <memory>
#include <string>

#include "components/core/place/vocabulary.hpp"

namespace heslam {

inline constexpr const char* kNoVocabularySetting = "none";

// Null for "none". Throws std::runtime_error with one line naming the file and the problem (missing,
// malformed, empty tree) — callers exit non-zero with it.
std::shared_ptr<const Vocabulary> load_vocabulary_setting(const std::string& setting);

// What the setting names, for log lines: the default file's path for an empty setting.
std::string describe_vocabulary_setting(const std::string& setting);

}  // namespace heslam
