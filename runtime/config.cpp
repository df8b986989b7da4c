// Config over cv::FileStorage: typed getters with defaults and one-line errors, used-key tracking.
#include "runtime/config.hpp"

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <opencv2/core.hpp>

#include "runtime/quote_value.hpp"

namespace heslam::runtime {
namespace {

// cv::FileStorage only parses YAML that starts with this directive; users need not write it.
constexpr std::string_view kYamlHeader = "%YAML:1.0\n---\n";
constexpr int kYamlHeaderLines = 2;

std::string describe(const cv::FileNode& node) {
  if (node.isInt()) return std::to_string(static_cast<int>(node));
  if (node.isReal()) {
    std::ostringstream text;
    text << static_cast<double>(node);
    return text.str();
  }
  if (node.isString()) {
    std::string quoted = "'";  // built by appending: GCC 12 -Wrestrict misfires on "'" + std::string&&
    quoted += quote_value(static_cast<std::string>(node));  // a field's value in an error line: short
    quoted += "'";
    return quoted;
  }
  if (node.isSeq()) return "a list";
  if (node.isMap()) return "a map";
  return "nothing";
}

// OpenCV reports "(LINE): reason" in cv::Exception::func for YAML errors.
std::string parse_error(const cv::Exception& error) {
  const std::string& func = error.func;
  if (func.size() > 2 && func.front() == '(') {
    const auto close = func.find("): ");
    if (close != std::string::npos) {
      try {
        const int line = std::stoi(func.substr(1, close - 1)) - kYamlHeaderLines;
        return "line " + std::to_string(line) + ": " + func.substr(close + 3);
      } catch (const std::exception&) {
      }
    }
  }
  return error.err;
}

// cv::FileStorage only understands whole-line comments ("key: v  # note" would become the value
// "v  # note"); strip YAML trailing comments (a '#' after whitespace, outside quotes) first.
std::string strip_trailing_comments(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    char quote = 0;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char c = line[i];
      if (quote != 0) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '#' && i > 0 && (line[i - 1] == ' ' || line[i - 1] == '\t')) {
        line.erase(i);
        break;
      }
    }
    out += line;
    out += '\n';
  }
  return out;
}

void check_duplicates(const cv::FileNode& map, const std::string& prefix, const std::string& source) {
  std::set<std::string> seen;
  for (const cv::FileNode& child : map) {
    const std::string key = prefix + child.name();
    if (!seen.insert(child.name()).second) throw std::runtime_error(source + ": field '" + key + "' appears twice");
    if (child.isMap()) check_duplicates(child, key + ".", source);
  }
}

std::vector<std::string> split_key(std::string_view key) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const auto dot = key.find('.', start);
    parts.emplace_back(key.substr(start, dot == std::string_view::npos ? std::string_view::npos : dot - start));
    if (dot == std::string_view::npos) break;
    start = dot + 1;
  }
  return parts;
}

}  // namespace

struct Config::State {
  std::shared_ptr<cv::FileStorage> storage = std::make_shared<cv::FileStorage>();
  cv::FileNode root;   // this Config's map (the file's root, or a list item)
  std::string prefix;  // key prefix in messages: "" or "components[2]."
  std::string source;
  std::filesystem::path folder;
  std::shared_ptr<const State> base;  // the layer this one overlays (a field absent here is looked up there)
  mutable std::set<std::string> used;

  // The node of key in this layer alone, or an empty node.
  cv::FileNode find_here(std::string_view key) const {
    if (root.empty()) return {};
    cv::FileNode node = root;
    for (const std::string& part : split_key(key)) {
      if (!node.isMap()) return {};
      node = node[part];
      if (node.empty()) return {};
    }
    return node;
  }

  // The node of key in the topmost layer that has it, with that layer (messages and relative paths
  // name the file the value came from); this layer and an empty node when no layer has it. Marks the
  // key used in every layer.
  std::pair<cv::FileNode, const State*> find(std::string_view key) const {
    for (const State* layer = this; layer != nullptr; layer = layer->base.get()) layer->used.insert(std::string(key));
    for (const State* layer = this; layer != nullptr; layer = layer->base.get()) {
      cv::FileNode node = layer->find_here(key);
      if (!node.empty()) return {node, layer};
    }
    return {cv::FileNode(), this};
  }

  [[noreturn]] void fail(std::string_view key, const std::string& expected, const cv::FileNode& node) const {
    throw std::runtime_error(source + ": field '" + prefix + std::string(key) + "': expected " + expected + ", got " +
                             describe(node));
  }
};

Config Config::parse(const std::string& yaml_text, const std::string& source) {
  auto state = std::make_shared<State>();
  state->source = source;
  const bool blank = yaml_text.find_first_not_of(" \t\r\n") == std::string::npos;
  if (blank) return Config(state);
  const std::string stripped = strip_trailing_comments(yaml_text);
  const std::string text = stripped.rfind("%YAML", 0) == 0 ? stripped : std::string(kYamlHeader) + stripped;
  try {
    state->storage->open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& error) {
    throw std::runtime_error(source + ": not valid YAML: " + parse_error(error));
  }
  if (!state->storage->isOpened()) throw std::runtime_error(source + ": not valid YAML");
  const cv::FileNode root = state->storage->root();
  if (!root.isMap() && !root.empty()) throw std::runtime_error(source + ": expected a map of fields at the top level");
  if (root.isMap()) {
    check_duplicates(root, "", source);
    state->root = root;
  }
  return Config(state);
}

Config Config::load(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  Config config = parse(text.str(), file.string());
  config.state_->folder = file.parent_path();
  return config;
}

Config Config::load(const std::vector<std::filesystem::path>& files) {
  if (files.empty()) return empty();
  Config config = load(files.front());
  for (std::size_t i = 1; i < files.size(); ++i) config = load(files[i]).over(config);
  return config;
}

Config Config::over(const Config& base) const {
  if (state_->base != nullptr) throw std::logic_error("Config::over: " + state_->source + " already overlays a config");
  auto state = std::make_shared<State>(*state_);
  state->used.clear();
  state->base = base.state_;
  return Config(state);
}

Config Config::empty(const std::string& source) {
  auto state = std::make_shared<State>();
  state->source = source;
  return Config(state);
}

bool Config::has(std::string_view key) const { return !state_->find(key).first.empty(); }

bool Config::is_list(std::string_view key) const { return state_->find(key).first.isSeq(); }

int Config::get_int(std::string_view key, int default_value, int min, int max) const {
  const auto [node, layer] = state_->find(key);
  if (node.empty()) return default_value;
  const std::string expected = "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
  if (!node.isInt()) layer->fail(key, expected, node);
  const int value = static_cast<int>(node);
  if (value < min || value > max) layer->fail(key, expected, node);
  return value;
}

double Config::get_double(std::string_view key, double default_value, double min, double max) const {
  const auto [node, layer] = state_->find(key);
  if (node.empty()) return default_value;
  std::ostringstream expected;
  expected << "a number in [" << min << ", " << max << "]";
  if (!node.isInt() && !node.isReal()) layer->fail(key, expected.str(), node);
  const double value = static_cast<double>(node);
  if (!(value >= min && value <= max)) layer->fail(key, expected.str(), node);
  return value;
}

bool Config::get_bool(std::string_view key, bool default_value) const {
  const auto [node, layer] = state_->find(key);
  if (node.empty()) return default_value;
  if (node.isInt()) {
    const int value = static_cast<int>(node);
    if (value == 0 || value == 1) return value == 1;
  } else if (node.isString()) {
    const std::string value = node;
    if (value == "true" || value == "yes" || value == "on") return true;
    if (value == "false" || value == "no" || value == "off") return false;
  }
  layer->fail(key, "true or false", node);
}

std::string Config::get_string(std::string_view key, const std::string& default_value) const {
  const auto [node, layer] = state_->find(key);
  if (node.empty()) return default_value;
  if (!node.isString()) layer->fail(key, "a string", node);
  return node;
}

std::string Config::get_choice(std::string_view key, const std::string& default_value,
                               std::initializer_list<std::string_view> choices) const {
  const auto [node, layer] = state_->find(key);
  std::string expected = "one of";
  for (std::string_view choice : choices) {
    expected += ' ';
    expected += choice;
  }
  if (node.empty()) return default_value;
  if (!node.isString()) layer->fail(key, expected, node);
  const std::string value = node;
  for (std::string_view choice : choices) {
    if (value == choice) return value;
  }
  layer->fail(key, expected, node);
}

std::filesystem::path Config::get_path(std::string_view key, const std::filesystem::path& default_value) const {
  const auto [node, layer] = state_->find(key);
  if (node.empty()) return default_value;
  if (!node.isString()) layer->fail(key, "a path", node);
  const std::filesystem::path path = static_cast<std::string>(node);
  return path.is_relative() && !layer->folder.empty() ? layer->folder / path : path;
}

std::vector<double> Config::get_doubles(std::string_view key, const std::vector<double>& default_value) const {
  const auto [node, layer] = state_->find(key);
  if (node.empty()) return default_value;
  if (!node.isSeq()) layer->fail(key, "a list of numbers", node);
  std::vector<double> values;
  for (const cv::FileNode& item : node) {
    if (!item.isInt() && !item.isReal()) layer->fail(key, "a list of numbers", item);
    values.push_back(static_cast<double>(item));
  }
  return values;
}

std::vector<std::string> Config::get_strings(std::string_view key,
                                             const std::vector<std::string>& default_value) const {
  const auto [node, layer] = state_->find(key);
  if (node.empty()) return default_value;
  if (!node.isSeq()) layer->fail(key, "a list of strings", node);
  std::vector<std::string> values;
  for (const cv::FileNode& item : node) {
    if (item.isString()) {
      values.push_back(item);
    } else if (item.isInt() || item.isReal()) {
      values.push_back(describe(item));  // numbers are fine as strings (arguments like "5")
    } else {
      layer->fail(key, "a list of strings", item);
    }
  }
  return values;
}

std::string Config::get_scalar(std::string_view key, const std::string& default_value) const {
  const auto [node, layer] = state_->find(key);
  if (node.empty()) return default_value;
  if (node.isString()) return node;
  if (node.isInt() || node.isReal()) return describe(node);
  layer->fail(key, "a single value", node);
}

std::map<std::string, std::string> Config::get_string_map(std::string_view key) const {
  const auto [node, layer] = state_->find(key);
  std::map<std::string, std::string> values;
  if (node.empty()) return values;
  if (!node.isMap()) layer->fail(key, "a map of names to values", node);
  for (const cv::FileNode& item : node) {
    if (item.isString()) {
      values[item.name()] = static_cast<std::string>(item);
    } else if (item.isInt() || item.isReal()) {
      values[item.name()] = describe(item);
    } else {
      layer->fail(std::string(key) + "." + item.name(), "a string", item);
    }
  }
  return values;
}

std::vector<Config> Config::get_sections(std::string_view key) const {
  const auto [node, layer] = state_->find(key);
  std::vector<Config> sections;
  if (node.empty()) return sections;
  if (!node.isSeq()) layer->fail(key, "a list of maps", node);
  int index = 0;
  for (const cv::FileNode& item : node) {
    const std::string item_key = std::string(key) + "[" + std::to_string(index++) + "]";
    if (!item.isMap()) layer->fail(item_key, "a map of fields", item);
    auto state = std::make_shared<State>();
    state->storage = layer->storage;
    state->root = item;
    state->prefix = layer->prefix + item_key + ".";
    state->source = layer->source;
    state->folder = layer->folder;
    check_duplicates(item, state->prefix, state->source);
    sections.push_back(Config(state));
  }
  return sections;
}

void Config::reject_unknown() const {
  for (const State* layer = state_.get(); layer != nullptr; layer = layer->base.get()) {
    if (layer->root.empty()) continue;
    // Depth-first over the map: a field is known when it or one of its parents was asked for.
    std::vector<std::pair<cv::FileNode, std::string>> stack{{layer->root, ""}};
    while (!stack.empty()) {
      auto [map, prefix] = stack.back();
      stack.pop_back();
      if (!map.isMap()) continue;
      for (const cv::FileNode& child : map) {
        const std::string key = prefix + child.name();
        if (layer->used.count(key) != 0) continue;
        if (child.isMap()) {
          stack.emplace_back(child, key + ".");
        } else {
          throw std::runtime_error(layer->source + ": unknown field '" + layer->prefix + key + "' (no such option)");
        }
      }
    }
  }
}

const std::string& Config::source() const { return state_->source; }

std::filesystem::path Config::folder() const { return state_->folder; }

}  // namespace heslam::runtime
