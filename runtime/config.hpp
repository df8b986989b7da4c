// Config: a component's YAML options (read with cv::FileStorage, the ORB-SLAM settings format).
//
// Every getter takes the documented default, used when the field is absent. A present field of the
// wrong type or out of range throws std::runtime_error with one line naming file, field and what
// was expected:  "frontend.yaml: field 'orb.levels': expected an integer in [1, 16], got 40".
// Keys use dots for nested maps ("orb.levels"). reject_unknown() turns typos into errors. Several
// files can be layered (a user's file over the shipped one): see load(files).
#pragma once

#include <climits>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace heslam::runtime {

class Config {
 public:
  // Throws "<file>: cannot open" / "<file>: not a YAML map: <reason>".
  static Config load(const std::filesystem::path& file);
  // Layers: each file overlays the ones before it field by field (a nested field absent from a later
  // file keeps the earlier file's value). Messages and relative paths name the file a value came from;
  // reject_unknown() checks every file. No files: empty().
  static Config load(const std::vector<std::filesystem::path>& files);
  // This config laid over base: a field absent here is base's. (This one must not overlay another.)
  Config over(const Config& base) const;
  // Parses YAML text; source names it in messages.
  static Config parse(const std::string& yaml_text, const std::string& source);
  // No fields: every getter returns its default.
  static Config empty(const std::string& source = "<defaults>");

  bool has(std::string_view key) const;
  bool is_list(std::string_view key) const;  // present and a YAML sequence

  int get_int(std::string_view key, int default_value, int min = INT_MIN, int max = INT_MAX) const;
  double get_double(std::string_view key, double default_value, double min = -std::numeric_limits<double>::infinity(),
                    double max = std::numeric_limits<double>::infinity()) const;
  // true/false, yes/no, on/off or 1/0.
  bool get_bool(std::string_view key, bool default_value) const;
  std::string get_string(std::string_view key, const std::string& default_value) const;
  // One of choices (exact match).
  std::string get_choice(std::string_view key, const std::string& default_value,
                         std::initializer_list<std::string_view> choices) const;
  // A relative path is resolved against the config file's folder.
  std::filesystem::path get_path(std::string_view key, const std::filesystem::path& default_value) const;
  std::vector<double> get_doubles(std::string_view key, const std::vector<double>& default_value) const;
  std::vector<std::string> get_strings(std::string_view key, const std::vector<std::string>& default_value) const;

  // Any scalar as text (numbers as written, strings as they are): for fields that may hold "$(arg x)".
  std::string get_scalar(std::string_view key, const std::string& default_value) const;
  // A map of string (or number) values, e.g. environment variables.
  std::map<std::string, std::string> get_string_map(std::string_view key) const;
  // A list of maps, each as its own Config (field names in messages read "components[2].name").
  std::vector<Config> get_sections(std::string_view key) const;

  // Throws for the first top-level or nested field no getter asked for:
  //   "frontend.yaml: unknown field 'orb.levle' (no such option)".
  void reject_unknown() const;

  const std::string& source() const;
  std::filesystem::path folder() const;  // of the file ("" for text / empty)

 private:
  struct State;
  explicit Config(std::shared_ptr<State> state) : state_(std::move(state)) {}
  std::shared_ptr<State> state_;
};

}  // namespace heslam::runtime
