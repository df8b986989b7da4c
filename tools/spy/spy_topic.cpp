// Topic argument resolution for heslam-spy.
#include "tools/spy/spy_topic.hpp"

namespace heslam {

ResolvedTopic resolve_topic(const std::string& topic, const std::string& ns) {
  std::string name = topic;
  while (!name.empty() && name.front() == '/') name.erase(name.begin());
  std::string known;
  for (const runtime::TopicEntry& entry : runtime::all_topics()) {
    const std::string relative(entry.relative_name);
    if (name == relative) return {ns + "/" + relative, std::string(entry.type_name), entry.role};
    if (name.size() > relative.size() + 1 && name.ends_with("/" + relative)) {
      return {name, std::string(entry.type_name), entry.role};
    }
    known += (known.empty() ? "" : ", ") + relative;
  }
  throw std::runtime_error("topic '" + topic + "': not a heslam topic (known: " + known + ")");
}

}  // namespace heslam
