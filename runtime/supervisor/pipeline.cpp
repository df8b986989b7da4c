// Pipeline file loading: fields with defaults, $(arg) substitution, and validation of every
// referenced file, collecting one message per problem (what --check prints).
#include "runtime/supervisor/pipeline.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>

#include "runtime/config.hpp"
#include "runtime/participant.hpp"
#include "runtime/quote_value.hpp"
#include "runtime/security.hpp"
#include "runtime/topics.hpp"

namespace heslam::supervisor {
namespace {

using runtime::Config;

// The largest niceness Linux has (19) above a supervisor at 0; lowering it (negative) needs privileges.
constexpr int kMaxNiceIncrement = 19;

// The pipeline's name becomes part of the log folder's name: a file name of this many characters at most.
constexpr std::size_t kMaxPipelineName = 64;
// Arguments referring to each other deeper than this are a mistake, not a configuration.
constexpr int kMaxArgDepth = 16;
// A process's shutdown work may be long (heslam-occupancy fuses every keyframe cloud again and writes
// its map as it stops: minutes for a few hundred keyframes on a loaded machine).
constexpr double kMaxStopTimeoutS = 3600.0;

const std::regex& arg_pattern() {
  static const std::regex pattern(R"(\$\((arg|stem)\s+([A-Za-z0-9_\-]+)\s*\))");
  return pattern;
}

// A component name becomes a file name and a DDS key: keep it simple.
bool valid_name(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') return false;
  }
  return true;
}

bool is_executable(const std::filesystem::path& path) {
  return std::filesystem::is_regular_file(path) && access(path.c_str(), X_OK) == 0;
}

// heslam-* and bare names: the supervisor's own folder first (a build's bin/), then $PATH.
std::optional<std::filesystem::path> resolve_executable(const std::string& text, const std::filesystem::path& folder,
                                                        const std::filesystem::path& bin_dir) {
  if (text.find('/') != std::string::npos) {
    std::filesystem::path path = text;
    if (path.is_relative()) path = folder / path;
    return is_executable(path) ? std::optional(std::filesystem::absolute(path)) : std::nullopt;
  }
  if (!bin_dir.empty() && is_executable(bin_dir / text)) return bin_dir / text;
  const char* env_path = std::getenv("PATH");
  std::stringstream dirs(env_path == nullptr ? "" : env_path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (!dir.empty() && is_executable(std::filesystem::path(dir) / text)) return std::filesystem::path(dir) / text;
  }
  return std::nullopt;
}

// An executable chosen by an argument (`executable: $(arg loop_closer)`) that was not found: the
// choices this build offers, named like the file's default (heslam-loop-closer,
// heslam-loop-closer-proximity, ...), and none. Empty when the field is not one argument or the
// default names no executable.
std::string executable_choices(const std::string& field_text, const std::map<std::string, std::string>& defaults,
                               const std::filesystem::path& bin_dir) {
  static const std::regex whole_arg(R"(^\$\(arg ([A-Za-z0-9_]+)\)$)");
  std::smatch match;
  if (!std::regex_match(field_text, match, whole_arg) || bin_dir.empty()) return "";
  const auto declared = defaults.find(match[1].str());
  if (declared == defaults.end() || declared->second.empty() || declared->second == kDisabledExecutable ||
      declared->second.find('/') != std::string::npos) {
    return "";
  }
  std::vector<std::string> choices;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(bin_dir, error)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with(declared->second) && is_executable(entry.path())) choices.push_back(name);
  }
  if (choices.empty()) return "";
  std::sort(choices.begin(), choices.end());
  std::string text = "; --arg " + match[1].str() + " takes ";
  for (const std::string& choice : choices) text += choice + ", ";
  return text + "or none";
}

std::string join_keys(const std::map<std::string, std::string>& map) {
  std::string out;
  for (const auto& [key, value] : map) out += (out.empty() ? "" : ", ") + key;
  return out.empty() ? "none" : out;
}

// Runs fn, turning its runtime_error into a recorded problem.
void collect(std::vector<std::string>& problems, const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::runtime_error& error) {
    problems.emplace_back(error.what());
  }
}

using Substitute = std::function<std::string(const std::string& field, const std::string& text)>;

// dds_profile: loopback (default) | network, with dds_interface, dds_peers, dds_lease_s.
void load_network_profile(const Config& config, Pipeline& pipeline, std::vector<std::string>& problems,
                          const Substitute& substitute) {
  const std::string source = config.source();
  std::string profile = "loopback";
  collect(problems, [&] {
    profile = substitute("dds_profile", config.get_string("dds_profile", "loopback"));
    if (profile.empty()) profile = "loopback";
    if (profile != "loopback" && profile != "network") {
      throw std::runtime_error(source + ": field 'dds_profile': expected loopback or network, got '" +
                               runtime::quote_value(profile) + "'");
    }
  });
  runtime::DdsNetworkProfile network;
  collect(problems, [&] { network.interface = substitute("dds_interface", config.get_string("dds_interface", "")); });
  collect(problems,
          [&] { network.peers = runtime::split_list(substitute("dds_peers", config.get_string("dds_peers", ""))); });
  collect(problems, [&] {
    const std::string text = substitute("dds_lease_s", config.get_scalar("dds_lease_s", "10"));
    std::istringstream parse(text);
    if (!(parse >> network.lease_s) || !parse.eof() || network.lease_s < runtime::kMinLeaseS ||
        network.lease_s > runtime::kMaxLeaseS) {
      std::ostringstream expected;
      expected << "expected seconds in [" << runtime::kMinLeaseS << ", " << runtime::kMaxLeaseS << "]";
      throw std::runtime_error(source + ": field 'dds_lease_s': " + expected.str() + ", got '" +
                               runtime::quote_value(text) + "'");
    }
  });
  if (profile != "network") return;
  collect(problems, [&] {
    if (!pipeline.dds_config.empty()) {
      throw std::runtime_error(source +
                               ": fields 'dds_config' and 'dds_profile: network' exclude each other "
                               "(the profile writes its own Cyclone XML)");
    }
    if (network.interface.empty()) {
      throw std::runtime_error(source +
                               ": dds_profile network: field 'dds_interface' is empty (give the "
                               "interface by name, e.g. --arg dds_interface=eth0)");
    }
    if (const auto problem = runtime::check_network_interface(network.interface)) {
      throw std::runtime_error(source + ": field 'dds_interface': " + *problem);
    }
    // This host's own address among the peers, or its processes do not find each other (a user
    // listing only "the other host" is the common mistake).
    if (!network.peers.empty()) {
      const auto own = runtime::interface_ipv4_address(network.interface);
      if (own && std::find(network.peers.begin(), network.peers.end(), *own) == network.peers.end()) {
        network.peers.push_back(*own);
      }
    }
    runtime::network_dds_config(network);  // its own checks (peer names)
    pipeline.network = network;
  });
}

// --host / --only: marks the components of other hosts remote. Unknown names are problems.
void select_local_components(Pipeline& pipeline, const PipelineOverrides& overrides,
                             std::vector<std::string>& problems) {
  const std::string source = pipeline.file.filename().string();
  std::set<std::string> known;
  for (const auto& component : pipeline.components) known.insert(component.name);
  for (const auto& name : pipeline.disabled_components) known.insert(name);
  const auto check_known = [&](const std::string& name, const std::string& where) {
    if (known.count(name) != 0) return true;
    std::string names;
    for (const auto& each : known) names += (names.empty() ? "" : ", ") + each;
    problems.push_back(source + ": " + where + ": no component '" + runtime::quote_value(name) +
                       "' (components: " + names + ")");
    return false;
  };
  // Every enabled component in exactly one group, so the hosts together run the whole pipeline.
  std::map<std::string, std::string> group_of;
  for (const auto& [group, names] : pipeline.hosts) {
    for (const auto& name : names) {
      if (!check_known(name, "field 'hosts." + group + "'")) continue;
      const auto [it, inserted] = group_of.emplace(name, group);
      if (!inserted) {
        problems.push_back(source + ": field 'hosts." + group + "': component '" + name + "' is already in hosts." +
                           it->second);
      }
    }
  }
  if (!pipeline.hosts.empty()) {
    for (const auto& component : pipeline.components) {
      if (group_of.count(component.name) == 0) {
        problems.push_back(source + ": field 'hosts': component '" + component.name + "' is in no host group");
      }
    }
  }
  pipeline.host = overrides.host;
  std::set<std::string> local;
  if (!overrides.only.empty()) {
    for (const auto& name : overrides.only) {
      if (check_known(name, "--only")) local.insert(name);
    }
  } else if (!overrides.host.empty()) {
    const auto group = pipeline.hosts.find(overrides.host);
    if (group == pipeline.hosts.end()) {
      std::string groups;
      for (const auto& [name, members] : pipeline.hosts) groups += (groups.empty() ? "" : ", ") + name;
      problems.push_back(source + ": --host " + overrides.host + ": the pipeline has no such host group (hosts: " +
                         (groups.empty() ? "none; use --only a,b" : groups) + ")");
      return;
    }
    local.insert(group->second.begin(), group->second.end());
  } else {
    return;  // the whole pipeline on this host
  }
  for (auto& component : pipeline.components) component.remote = local.count(component.name) == 0;
}

}  // namespace

std::map<std::string, std::string> resolve_args(const std::map<std::string, std::string>& args,
                                                const std::string& source, std::vector<std::string>& problems) {
  std::map<std::string, std::string> resolved;
  std::set<std::string> failed;
  std::vector<std::string> chain;  // the arguments being resolved, outermost first
  std::function<bool(const std::string&)> resolve = [&](const std::string& key) {
    if (resolved.count(key) != 0) return true;
    if (failed.count(key) != 0) return false;
    const auto on_chain = std::find(chain.begin(), chain.end(), key);
    if (on_chain != chain.end() || static_cast<int>(chain.size()) >= kMaxArgDepth) {
      std::string path;
      for (auto it = on_chain == chain.end() ? chain.begin() : on_chain; it != chain.end(); ++it) path += *it + " -> ";
      problems.push_back(source + ": argument '" + chain.front() + "': " +
                         (on_chain != chain.end() ? "the arguments refer to each other in a cycle (" + path + key + ")"
                                                  : "refers to arguments more than " + std::to_string(kMaxArgDepth) +
                                                        " deep (" + path + key + ")"));
      for (const std::string& each : chain) failed.insert(each);
      return false;
    }
    chain.push_back(key);
    bool ok = true;
    const std::string& text = args.at(key);
    for (auto it = std::sregex_iterator(text.begin(), text.end(), arg_pattern()); it != std::sregex_iterator(); ++it) {
      const std::string name = (*it)[2].str();
      if (args.count(name) != 0 && !resolve(name)) ok = false;
    }
    chain.pop_back();
    if (!ok) {
      failed.insert(key);
      return false;
    }
    std::vector<std::string> unknown;
    resolved[key] = substitute_args(text, resolved, unknown);
    for (const std::string& name : unknown) {
      problems.push_back(source + ": argument '" + key + "': unknown $(arg " + name + ")");
    }
    return true;
  };
  for (const auto& [key, value] : args) {
    if (!resolve(key)) resolved[key] = "";
  }
  return resolved;
}

std::string substitute_args(const std::string& text, const std::map<std::string, std::string>& args,
                            std::vector<std::string>& unknown) {
  const std::regex& pattern = arg_pattern();
  std::string out;
  auto begin = std::sregex_iterator(text.begin(), text.end(), pattern);
  std::size_t last = 0;
  for (auto it = begin; it != std::sregex_iterator(); ++it) {
    const std::smatch& match = *it;
    out += text.substr(last, static_cast<std::size_t>(match.position(0)) - last);
    const auto found = args.find(match[2].str());
    if (found == args.end()) {
      unknown.push_back(match[2].str());
    } else if (match[1].str() == "stem") {
      // The value without its extension: a run's outputs are OUTPUT stem + .map, .loop, ...
      out += std::filesystem::path(found->second).replace_extension().string();
    } else {
      out += found->second;
    }
    last = static_cast<std::size_t>(match.position(0) + match.length(0));
  }
  out += text.substr(last);
  return out;
}

LoadResult load_pipeline(const std::filesystem::path& file, const PipelineOverrides& overrides,
                         const std::filesystem::path& bin_dir) {
  LoadResult result;
  Pipeline& pipeline = result.pipeline;
  std::vector<std::string>& problems = result.problems;
  pipeline.file = std::filesystem::absolute(file);
  const std::string source = file.string();

  std::optional<Config> config;
  collect(problems, [&] { config = Config::load(file); });
  if (!config) return result;

  // Arguments: declared with defaults in the file, overridden by --arg.
  std::map<std::string, std::string> args;
  collect(problems, [&] { args = config->get_string_map("args"); });
  const std::map<std::string, std::string> declared_args = args;  // the file's defaults
  for (const auto& [key, value] : overrides.args) {
    if (args.count(key) == 0) {
      problems.push_back(source + ": --arg " + key +
                         ": the pipeline declares no such argument (declared: " + join_keys(args) + ")");
    }
    args[key] = value;
  }
  args = resolve_args(args, source, problems);
  const auto substitute = [&](const std::string& field, const std::string& text) {
    std::vector<std::string> unknown;
    std::string out = substitute_args(text, args, unknown);
    for (const auto& name : unknown) {
      problems.push_back(source + ": field '" + field + "': unknown $(arg " + name + ") (declared: " + join_keys(args) +
                         ")");
    }
    return out;
  };
  const std::filesystem::path folder = pipeline.file.parent_path();

  collect(problems, [&] {
    pipeline.name = config->get_string("name", file.stem().string());
    // It names the log folder: letters, digits, '_', '-', '.', never a path or an unprintable byte.
    const bool valid = !pipeline.name.empty() && pipeline.name.size() <= kMaxPipelineName &&
                       pipeline.name.front() != '.' &&
                       std::all_of(pipeline.name.begin(), pipeline.name.end(), [](char c) {
                         return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
                       });
    if (!valid) {
      throw std::runtime_error(source + ": field 'name': expected 1-" + std::to_string(kMaxPipelineName) +
                               " letters, digits, '_', '-' or '.' (it names the log folder), got '" +
                               runtime::quote_value(pipeline.name) + "'");
    }
  });
  collect(problems, [&] {
    const std::string text = substitute("domain", config->get_scalar("domain", "0"));
    int domain = -1;
    std::istringstream parse(text);
    if (!(parse >> domain) || !parse.eof() || domain < 0 || domain > runtime::kMaxDomainId) {
      throw std::runtime_error(source + ": field 'domain': expected an integer in [0, " +
                               std::to_string(runtime::kMaxDomainId) + "], got '" + runtime::quote_value(text) + "'");
    }
    pipeline.domain_id = domain;
  });
  if (overrides.domain_id) pipeline.domain_id = *overrides.domain_id;
  collect(problems, [&] {
    pipeline.ns = substitute("namespace", config->get_string("namespace", std::string(runtime::kDefaultNamespace)));
    if (overrides.ns) pipeline.ns = *overrides.ns;
    runtime::Topics check(pipeline.ns);
  });
  collect(problems, [&] {
    const std::string text = substitute("dds_config", config->get_string("dds_config", ""));
    if (text.empty()) return;
    std::filesystem::path path = text;
    if (path.is_relative()) path = folder / path;
    if (!std::filesystem::is_regular_file(path)) {
      throw std::runtime_error(source + ": field 'dds_config': file " + path.string() + " does not exist");
    }
    pipeline.dds_config = "file://" + std::filesystem::absolute(path).string();
  });
  collect(problems,
          [&] { pipeline.stop_timeout_s = config->get_double("stop_timeout_s", 5.0, 0.1, kMaxStopTimeoutS); });
  collect(problems, [&] {
    std::string text = substitute("image_transport", config->get_string("image_transport", "udp"));
    if (overrides.image_transport) text = *overrides.image_transport;
    const auto transport = runtime::parse_image_transport(text);
    if (!transport) {
      throw std::runtime_error(source + ": field 'image_transport': expected udp or shm, got '" +
                               runtime::quote_value(text) + "'");
    }
    pipeline.image_transport = *transport;
    // Read even for udp: every field of the file is consumed (unknown ones are an error).
    const std::string domain_text = substitute("image_domain", config->get_scalar("image_domain", ""));
    std::filesystem::path roudi = substitute("roudi_config", config->get_string("roudi_config", ""));
    if (pipeline.image_transport == runtime::ImageTransport::kUdp) return;
    if (overrides.image_domain_id) {
      pipeline.image_domain_id = *overrides.image_domain_id;
    } else if (domain_text.empty()) {
      pipeline.image_domain_id =
          pipeline.domain_id < runtime::kMaxDomainId ? pipeline.domain_id + 1 : pipeline.domain_id - 1;
    } else {
      std::istringstream parse(domain_text);
      if (!(parse >> pipeline.image_domain_id) || !parse.eof()) pipeline.image_domain_id = -1;
    }
    if (pipeline.image_domain_id < 0 || pipeline.image_domain_id > runtime::kMaxDomainId ||
        pipeline.image_domain_id == pipeline.domain_id) {
      throw std::runtime_error(source + ": field 'image_domain': expected an integer in [0, " +
                               std::to_string(runtime::kMaxDomainId) + "] other than the domain (" +
                               std::to_string(pipeline.domain_id) + ")");
    }
    if (roudi.empty()) roudi = folder / ".." / "iceoryx" / "roudi.toml";
    if (roudi.is_relative()) roudi = folder / roudi;
    if (!std::filesystem::is_regular_file(roudi)) {
      throw std::runtime_error(source + ": field 'roudi_config': file " + roudi.string() + " does not exist");
    }
    pipeline.roudi_config = std::filesystem::absolute(roudi).lexically_normal();
  });
  load_network_profile(*config, pipeline, problems, substitute);
  collect(problems,
          [&] { pipeline.remote_ready_timeout_s = config->get_double("remote_ready_timeout_s", 120.0, 0.1, 86400.0); });
  collect(problems, [&] {
    for (const auto& [group, names] : config->get_string_map("hosts")) {
      pipeline.hosts[group] = runtime::split_list(substitute("hosts." + group, names));
    }
  });
  collect(problems, [&] {
    std::string text = substitute("security", config->get_string("security", ""));
    if (overrides.security_dir) text = *overrides.security_dir;
    if (text.empty()) return;
    // Like inputs, a folder given on the command line is relative to where the user is.
    std::filesystem::path path = text;
    if (path.is_relative()) path = std::filesystem::current_path() / path;
    if (!std::filesystem::is_directory(path)) {
      throw std::runtime_error(source + ": field 'security': folder " + text +
                               " does not exist (make it with heslam-security init " + text + ")");
    }
    if (pipeline.domain_id > runtime::kMaxSecureDomainId) {
      throw std::runtime_error(source + ": field 'security': DDS security supports domains 0-" +
                               std::to_string(runtime::kMaxSecureDomainId) + ", the pipeline runs on domain " +
                               std::to_string(pipeline.domain_id));
    }
    if (pipeline.image_transport == runtime::ImageTransport::kShm) {
      throw std::runtime_error(source +
                               ": field 'security': DDS security with image_transport shm is not supported "
                               "(untested); use image_transport udp");
    }
    pipeline.security_dir = std::filesystem::absolute(path).lexically_normal();
    try {
      runtime::check_security_files(runtime::security_files(pipeline.security_dir, kSupervisorIdentity));
    } catch (const std::runtime_error& error) {
      throw std::runtime_error(source + ": field 'security': " + error.what());
    }
  });

  std::vector<Config> sections;
  collect(problems, [&] { sections = config->get_sections("components"); });
  if (sections.empty() && problems.empty())
    problems.push_back(source + ": field 'components': expected a non-empty list");
  collect(problems, [&] { config->reject_unknown(); });

  // A component of another host reads its inputs there: not checked here (the dataset is on the
  // camera host only). hosts.NAME may be misspelled: select_local_components reports that below.
  const auto runs_here = [&](const std::string& name) {
    if (!overrides.only.empty())
      return std::find(overrides.only.begin(), overrides.only.end(), name) != overrides.only.end();
    const auto group = pipeline.hosts.find(overrides.host);
    if (overrides.host.empty() || group == pipeline.hosts.end()) return true;
    return std::find(group->second.begin(), group->second.end(), name) != group->second.end();
  };
  std::map<std::string, int> first_index;
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const Config& section = sections[i];
    const std::string where = "components[" + std::to_string(i) + "]";
    ComponentSpec spec;
    collect(problems, [&] {
      spec.name = section.get_string("name", "");
      if (!valid_name(spec.name)) {
        throw std::runtime_error(source + ": field '" + where + ".name': expected letters, digits, '_' or '-', got '" +
                                 spec.name + "'");
      }
      const auto [it, inserted] = first_index.emplace(spec.name, static_cast<int>(i));
      if (!inserted) {
        throw std::runtime_error(source + ": " + where + ": duplicate name '" + runtime::quote_value(spec.name) +
                                 "' (also components[" + std::to_string(it->second) + "])");
      }
    });
    const std::string label = spec.name.empty() ? where : "component '" + runtime::quote_value(spec.name) + "'";
    bool disabled = false;
    collect(problems, [&] {
      const std::string text = substitute(where + ".executable", section.get_string("executable", ""));
      if (text.empty()) throw std::runtime_error(source + ": " + label + ": field 'executable' is required");
      if (text == kDisabledExecutable) {
        disabled = true;
        return;
      }
      const auto resolved = resolve_executable(text, folder, bin_dir);
      if (!resolved) {
        throw std::runtime_error(source + ": " + label + ": executable '" + runtime::quote_value(text) +
                                 "' not found (looked in " +
                                 (bin_dir.empty() ? std::string() : bin_dir.string() + " and ") + "$PATH)" +
                                 executable_choices(section.get_string("executable", ""), declared_args, bin_dir));
      }
      spec.executable = *resolved;
    });
    collect(problems, [&] {
      for (const std::string& arg : section.get_strings("args", {}))
        spec.args.push_back(substitute(where + ".args", arg));
    });
    collect(problems, [&] {
      const std::vector<std::string> entries =
          section.is_list("config") ? section.get_strings("config", {}) : std::vector{section.get_string("config", "")};
      if (disabled) return;  // a disabled component's config may name its executable
      for (const std::string& entry : entries) {
        const std::string text = substitute(where + ".config", entry);
        if (text.empty()) continue;
        // A relative path names a file beside the pipeline (the shipped configs) or, failing that, one
        // in the current directory (a user's --arg file).
        std::filesystem::path path = text;
        if (path.is_relative() && !std::filesystem::is_regular_file(folder / path) &&
            std::filesystem::is_regular_file(path)) {
          path = std::filesystem::absolute(path);
        }
        if (path.is_relative()) path = folder / path;
        if (!std::filesystem::is_regular_file(path)) {
          throw std::runtime_error(source + ": " + label + ": config " + path.string() + " does not exist");
        }
        spec.configs.push_back(std::filesystem::absolute(path));
      }
      Config::load(spec.configs);  // their own syntax errors, named by their files
    });
    collect(problems, [&] {
      for (const std::string& input : section.get_strings("inputs", {})) {
        const std::string text = substitute(where + ".inputs", input);
        if (!runs_here(spec.name)) continue;
        if (text.empty()) {
          throw std::runtime_error(source + ": " + label + ": input '" + input +
                                   "' is empty (give it with --arg, e.g. --arg dataset=DIR)");
        }
        std::filesystem::path path = text;
        if (path.is_relative()) path = std::filesystem::current_path() / path;
        if (!disabled && !std::filesystem::exists(path)) {
          throw std::runtime_error(source + ": " + label + ": input " + text + " does not exist");
        }
        spec.inputs.push_back(path);
      }
    });
    collect(problems, [&] {
      for (auto& [key, value] : section.get_string_map("env")) spec.env[key] = substitute(where + ".env", value);
    });
    collect(problems, [&] {
      const std::string restart = section.get_choice("restart", "never", {"never", "on-failure", "always"});
      spec.restart = restart == "always"       ? RestartPolicy::kAlways
                     : restart == "on-failure" ? RestartPolicy::kOnFailure
                                               : RestartPolicy::kNever;
    });
    collect(problems, [&] { spec.max_restarts = section.get_int("max_restarts", 3, 0, 1000); });
    collect(problems, [&] {
      if (!section.has("stop_timeout_s")) return;
      // A number, or "$(arg x)": a pipeline lets a run with long shutdown work (heslam-occupancy's final
      // fusion) raise it, e.g. --arg occupancy_stop_timeout_s=600.
      const std::string text = substitute(where + ".stop_timeout_s", section.get_scalar("stop_timeout_s", "5"));
      double value = 0.0;
      std::istringstream parse(text);
      if (!(parse >> value) || !parse.eof() || !(value >= 0.1 && value <= kMaxStopTimeoutS)) {
        std::ostringstream expected;
        expected << "expected seconds in [0.1, " << kMaxStopTimeoutS << "]";
        throw std::runtime_error(source + ": field '" + where + ".stop_timeout_s': " + expected.str() + ", got '" +
                                 runtime::quote_value(text) + "'");
      }
      spec.stop_timeout_s = value;
    });
    collect(problems, [&] { spec.restart_backoff_s = section.get_double("restart_backoff_s", 0.1, 0.0, 600.0); });
    collect(problems,
            [&] { spec.restart_backoff_max_s = section.get_double("restart_backoff_max_s", 5.0, 0.0, 3600.0); });
    collect(problems, [&] {
      spec.ready = section.get_choice("ready", "status", {"status", "started"}) == "status" ? Readiness::kStatus
                                                                                            : Readiness::kStarted;
    });
    collect(problems, [&] { spec.ready_timeout_s = section.get_double("ready_timeout_s", 10.0, 0.1, 3600.0); });
    collect(problems, [&] {
      if (!section.has("after")) return;
      spec.after.emplace();
      for (const std::string& name : section.get_strings("after", {})) {
        const auto earlier = first_index.find(name);
        if (earlier == first_index.end() || earlier->second >= static_cast<int>(i)) {
          throw std::runtime_error(source + ": " + label + ": field 'after': '" + runtime::quote_value(name) +
                                   "' is not a component before it in the file (components start in file order)");
        }
        spec.after->push_back(name);
      }
    });
    collect(problems, [&] { spec.required = section.get_bool("required", true); });
    collect(problems, [&] {
      const std::string on_exit = section.get_choice("on_exit", "none", {"none", "shutdown", "shutdown_with_all"});
      spec.shutdown_on_exit = on_exit == "shutdown";
      spec.shutdown_with_all = on_exit == "shutdown_with_all";
    });
    collect(problems, [&] { spec.common_args = section.get_bool("common_args", true); });
    collect(problems, [&] { spec.pausable = section.get_bool("pausable", false); });
    collect(problems, [&] { spec.nice = section.get_int("nice", 0, 0, kMaxNiceIncrement); });
    collect(problems, [&] {
      spec.identity = substitute(where + ".identity", section.get_string("identity", spec.name));
      if (pipeline.security_dir.empty() || disabled) return;
      if (!valid_name(spec.identity)) {
        throw std::runtime_error(source + ": " + label +
                                 ": field 'identity': expected letters, digits, '_' or '-', got '" +
                                 runtime::quote_value(spec.identity) + "'");
      }
      const std::filesystem::path identity_dir = pipeline.security_dir / "identities" / spec.identity;
      try {
        runtime::check_security_files(runtime::security_files(identity_dir));
      } catch (const std::runtime_error& error) {
        throw std::runtime_error(source + ": " + label + ": " + error.what());
      }
      // Its own identity unless the pipeline gave it one explicitly in env.
      spec.env.emplace(runtime::kSecurityEnv, identity_dir.string());
    });
    collect(problems, [&] { section.reject_unknown(); });
    if (disabled) {
      pipeline.disabled_components.push_back(spec.name);
    } else {
      pipeline.components.push_back(std::move(spec));
    }
  }
  if (problems.empty()) select_local_components(pipeline, overrides, problems);
  return result;
}

}  // namespace heslam::supervisor
