// Where the build puts heslam's default ORB vocabulary (build/vocabulary/heslam_orb.hvoc, trained by
// tools/train-vocabulary.sh as part of the build; docs/place_recognition.md).
#pragma once

#include <filesystem>

namespace heslam {

// The default vocabulary file of this build tree. It may not exist (a build that skipped it);
// callers report that as a missing file. Users with DBoW2's ORBvoc.txt pass that path instead.
std::filesystem::path default_vocabulary_path();

}  // namespace heslam
