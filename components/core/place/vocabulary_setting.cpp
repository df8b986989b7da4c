// Resolving a vocabulary setting to a loaded vocabulary.
#include "components/core/place/vocabulary_setting.hpp"

#include <stdexcept>

#include "components/core/place/default_vocabulary.hpp"
#include "components/core/place/vocabulary_io.hpp"

namespace heslam {

std::string describe_vocabulary_setting(const std::string& setting) {
  if (setting.empty()) return default_vocabulary_path().string();
  return setting;
}

std::shared_ptr<const Vocabulary> load_vocabulary_setting(const std::string& setting) {
  if (setting == kNoVocabularySetting) return nullptr;
  const std::filesystem::path path = setting.empty() ? default_vocabulary_path() : std::filesystem::path(setting);
  auto vocabulary = std::make_shared<const Vocabulary>(load_vocabulary(path));  // throws naming the file
  if (vocabulary->empty()) throw std::runtime_error("vocabulary " + path.string() + ": the tree has no words");
  return vocabulary;
}

}  // namespace heslam
