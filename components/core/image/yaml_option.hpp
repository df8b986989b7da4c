// Reading optional tunables from an OpenCV YAML settings file (flat ORB-SLAM2-style keys such as
// "ORBextractor.nFeatures"): a missing key keeps the documented default, a present key of the wrong
// type is one clear error naming the source and the key.
#pragma once

#include <initializer_list>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include <opencv2/core/persistence.hpp>

namespace heslam::yaml_option {

[[noreturn]] inline void fail(const std::string& source, const std::string& key, const std::string& expected) {
  throw std::runtime_error(source + ": " + key + ": expected " + expected);
}

// Every key the readers below looked up on this thread while a KeyLog lives: what a settings file
// holds beyond them is a key no reader knows (a typo, or another program's), which the caller names.
class KeyLog {
 public:
  KeyLog() : previous_(active()) { active() = this; }
  ~KeyLog() { active() = previous_; }
  KeyLog(const KeyLog&) = delete;
  KeyLog& operator=(const KeyLog&) = delete;
  const std::set<std::string>& keys() const { return keys_; }
  static void note(const std::string& key) {
    if (active() != nullptr) active()->keys_.insert(key);
  }

 private:
  static KeyLog*& active() {
    static thread_local KeyLog* log = nullptr;
    return log;
  }
  KeyLog* previous_;
  std::set<std::string> keys_;
};

inline bool present(const cv::FileNode& root, const std::string& key) {
  KeyLog::note(key);
  const cv::FileNode node = root[key];
  return !node.empty() && !node.isNone();
}

inline void read(const cv::FileNode& root, const std::string& key, const std::string& source, double& value) {
  if (!present(root, key)) return;
  const cv::FileNode node = root[key];
  if (!node.isReal() && !node.isInt()) fail(source, key, "a number");
  value = static_cast<double>(node);
}

inline void read(const cv::FileNode& root, const std::string& key, const std::string& source, float& value) {
  double v = value;
  read(root, key, source, v);
  value = static_cast<float>(v);
}

inline void read(const cv::FileNode& root, const std::string& key, const std::string& source, int& value) {
  if (!present(root, key)) return;
  const cv::FileNode node = root[key];
  if (!node.isInt()) fail(source, key, "an integer");
  value = static_cast<int>(node);
}

inline void read(const cv::FileNode& root, const std::string& key, const std::string& source, bool& value) {
  int v = value ? 1 : 0;
  read(root, key, source, v);
  if (v != 0 && v != 1) fail(source, key, "0 or 1");
  value = v == 1;
}

inline void read(const cv::FileNode& root, const std::string& key, const std::string& source, std::string& value) {
  if (!present(root, key)) return;
  const cv::FileNode node = root[key];
  if (!node.isString()) fail(source, key, "a string");
  value = static_cast<std::string>(node);
}

// A named choice, e.g. `Stereo.cost: sad | zncc | census`; `value` keeps its default when the key is
// absent, and a name outside `choices` fails with the list of the accepted ones.
template <typename Choice>
void read_choice(const cv::FileNode& root, const std::string& key, const std::string& source,
                 std::initializer_list<std::pair<const char*, Choice>> choices, Choice& value) {
  if (!present(root, key)) return;
  std::string name;
  read(root, key, source, name);
  std::string accepted;
  for (const auto& [choice_name, choice] : choices) {
    if (name == choice_name) {
      value = choice;
      return;
    }
    accepted += (accepted.empty() ? "" : " | ") + std::string(choice_name);
  }
  fail(source, key, accepted + ", got '" + name + "'");
}

}  // namespace heslam::yaml_option
