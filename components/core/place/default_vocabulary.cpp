// The default vocabulary's path, compiled in by components/core/CMakeLists.txt.
#include "components/core/place/default_vocabulary.hpp"

#ifndef HESLAM_DEFAULT_VOCABULARY
#error "HESLAM_DEFAULT_VOCABULARY must be defined by the build (components/core/CMakeLists.txt)"
#endif

namespace heslam {

std::filesystem::path default_vocabulary_path() { return HESLAM_DEFAULT_VOCABULARY; }

}  // namespace heslam
