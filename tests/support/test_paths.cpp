// Where the shared data, the built programs and the sources are (declared in test_support.hpp).
#include <filesystem>

namespace heslam::test {

std::filesystem::path shared_data() { return HESLAM_SHARED_DATA; }
std::filesystem::path bin_dir() { return HESLAM_BIN_DIR; }
std::filesystem::path source_dir() { return HESLAM_SOURCE_DIR; }

}  // namespace heslam::test
