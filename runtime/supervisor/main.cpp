// heslam-supervisor PIPELINE.yaml [--arg key=value ...] [--check] [--domain N|auto] [--namespace NAME]
//                   [--log-dir DIR] [--log-level LEVEL] [--host NAME | --only a,b] [--no-progress]
//                   [--security DIR] [--image-transport udp|shm] [--image-domain N]
#include <signal.h>
#include <unistd.h>

#include <ctime>
#include <fstream>
#include <iostream>

#include "runtime/log.hpp"
#include "runtime/participant.hpp"
#include "runtime/quote_value.hpp"
#include "runtime/run_self.hpp"
#include "runtime/shutdown.hpp"
#include "runtime/supervisor/child_process.hpp"
#include "runtime/supervisor/domain_check.hpp"
#include "runtime/supervisor/pipeline.hpp"
#include "runtime/supervisor/supervisor.hpp"

namespace {

using namespace heslam;

constexpr const char* kUsage =
    "usage: heslam-supervisor PIPELINE.yaml [--arg key=value ...] [--check] [--domain N|auto] [--namespace NAME]\n"
    "                         [--log-dir DIR] [--log-level debug|info|warn|error] [--host NAME | --only a,b]\n"
    "                         [--no-progress] [--security DIR] [--image-transport udp|shm] [--image-domain N]\n"
    "  --check      validate the pipeline file, every file it references and each heslam program's\n"
    "               arguments and config (the program's own --check); start nothing\n"
    "  --domain N   DDS domain 0-232 (overrides the file's); auto: the first domain no other heslam run\n"
    "               uses (the file's, then 1, 2, ...). A domain in use by another run is refused\n"
    "  --arg k=v    value for $(arg k) in the pipeline file (overrides its 'args' default)\n"
    "  --log-dir    per-component logs (default: $HESLAM_LOG_DIR or ~/.heslam/log, + /<pipeline>-<time>)\n"
    "  --host NAME  run only the components of the file's hosts.NAME group; the others run on other hosts\n"
    "  --only a,b   run only these components; the others run on other hosts (docs/deployment.md)\n"
    "  --no-progress  no run progress (default: a line redrawn on a terminal, else a line per 10 %)\n"
    "  --security   DDS Security: run every process with its identity from DIR (heslam-security init DIR;\n"
    "               overrides the file's 'security'; docs/security.md)\n"
    "  --image-transport  shm: the stereo images over iceoryx shared memory on --image-domain (default:\n"
    "               domain + 1); the supervisor uses a running iox-roudi or starts one (docs/topics.md)\n";

std::filesystem::path default_log_dir(const std::string& pipeline_name) {
  std::filesystem::path base;
  if (const char* env = std::getenv("HESLAM_LOG_DIR"); env != nullptr && *env != '\0') {
    base = env;
  } else if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    base = std::filesystem::path(home) / ".heslam" / "log";
  } else {
    base = std::filesystem::temp_directory_path() / "heslam-log";
  }
  char stamp[32];
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &local);
  return base / (pipeline_name + "-" + stamp + "-" + std::to_string(getpid()));
}

std::string value_of(int argc, char** argv, int& i, const std::string& flag) {
  if (i + 1 >= argc) throw std::runtime_error(flag + ": missing value");
  return argv[++i];
}

int run(int argc, char** argv) {
  std::filesystem::path pipeline_file;
  supervisor::PipelineOverrides overrides;
  bool check = false;
  bool progress = true;
  bool domain_auto = false;
  std::filesystem::path log_dir;
  runtime::LogLevel log_level = runtime::LogLevel::kInfo;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      std::cout << kUsage;
      return 0;
    } else if (arg == "--check") {
      check = true;
    } else if (arg == "--no-progress") {
      progress = false;
    } else if (arg == "--arg") {
      const std::string pair = value_of(argc, argv, i, arg);
      const auto eq = pair.find('=');
      if (eq == std::string::npos || eq == 0) {
        throw std::runtime_error("--arg: expected key=value, got '" + runtime::quote_value(pair) + "'");
      }
      overrides.args[pair.substr(0, eq)] = pair.substr(eq + 1);
    } else if (arg == "--domain") {
      const std::string text = value_of(argc, argv, i, arg);
      if (text == "auto") {
        domain_auto = true;
        continue;
      }
      try {
        std::size_t used = 0;
        const int domain = std::stoi(text, &used);
        if (used != text.size() || domain < 0 || domain > runtime::kMaxDomainId) throw std::out_of_range(text);
        overrides.domain_id = domain;
      } catch (const std::logic_error&) {
        throw std::runtime_error("--domain: expected an integer in [0, " + std::to_string(runtime::kMaxDomainId) +
                                 "] or auto, got '" + runtime::quote_value(text) + "'");
      }
    } else if (arg == "--namespace") {
      overrides.ns = value_of(argc, argv, i, arg);
    } else if (arg == "--host") {
      overrides.host = value_of(argc, argv, i, arg);
      if (overrides.host.empty()) throw std::runtime_error("--host: expected a host group name");
    } else if (arg == "--only") {
      const std::string text = value_of(argc, argv, i, arg);
      overrides.only = runtime::split_list(text);
      if (overrides.only.empty()) throw std::runtime_error("--only: expected component names, e.g. --only frontend,replay");
    } else if (arg == "--security") {
      overrides.security_dir = value_of(argc, argv, i, arg);
    } else if (arg == "--image-transport") {
      overrides.image_transport = value_of(argc, argv, i, arg);
    } else if (arg == "--image-domain") {
      const std::string text = value_of(argc, argv, i, arg);
      try {
        std::size_t used = 0;
        const int domain = std::stoi(text, &used);
        if (used != text.size() || domain < 0 || domain > runtime::kMaxDomainId) throw std::out_of_range(text);
        overrides.image_domain_id = domain;
      } catch (const std::logic_error&) {
        throw std::runtime_error("--image-domain: expected an integer in [0, " + std::to_string(runtime::kMaxDomainId) +
                                 "], got '" + runtime::quote_value(text) + "'");
      }
    } else if (arg == "--log-dir") {
      log_dir = value_of(argc, argv, i, arg);
    } else if (arg == "--log-level") {
      const std::string text = value_of(argc, argv, i, arg);
      const auto level = runtime::parse_log_level(text);
      if (!level) {
        throw std::runtime_error("--log-level: expected debug, info, warn, error or off, got '" +
                                 runtime::quote_value(text) + "'");
      }
      log_level = *level;
    } else if (!arg.empty() && arg[0] == '-') {
      throw std::runtime_error("unknown option '" + runtime::quote_value(arg) + "' (see --help)");
    } else if (pipeline_file.empty()) {
      pipeline_file = arg;
    } else {
      throw std::runtime_error("unexpected argument '" + runtime::quote_value(arg) +
                               "': one pipeline file per supervisor");
    }
  }
  if (pipeline_file.empty()) throw std::runtime_error(std::string("missing PIPELINE.yaml\n") + kUsage);

  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe");
  auto loaded = supervisor::load_pipeline(pipeline_file, overrides, self.parent_path());
  if (loaded.problems.empty() && check) {
    // What each heslam program of the pipeline would refuse at its start (its own flags and fields).
    for (std::string& problem : supervisor::check_programs(loaded.pipeline, self)) {
      loaded.problems.push_back(std::move(problem));
    }
  }
  if (!loaded.problems.empty()) {
    for (const std::string& problem : loaded.problems) std::cerr << "heslam-supervisor: " << problem << "\n";
    return 1;
  }
  if (check) {
    std::cout << pipeline_file.string() << ": OK (" << loaded.pipeline.components.size() << " components:";
    for (const auto& component : loaded.pipeline.components) {
      std::cout << " " << component.name << (component.remote ? " [other host]" : "");
    }
    for (const auto& name : loaded.pipeline.disabled_components) std::cout << " [" << name << " disabled]";
    std::cout << ")";
    if (!loaded.pipeline.security_dir.empty()) {
      std::cout << ", DDS security from " << loaded.pipeline.security_dir.string();
    }
    std::cout << "\n";
    return 0;
  }
  std::optional<supervisor::DomainClaim> claim;
  if (!loaded.pipeline.split()) {
    // One run per domain and namespace on this host; --domain auto takes the first free one.
    std::string holder;
    if (domain_auto) {
      const int domain = supervisor::free_domain(loaded.pipeline, claim);
      if (domain != loaded.pipeline.domain_id) {
        overrides.domain_id = domain;
        loaded = supervisor::load_pipeline(pipeline_file, overrides, self.parent_path());
        if (!loaded.problems.empty()) throw std::runtime_error(loaded.problems.front());
      }
    } else if (!(claim = supervisor::DomainClaim::try_claim(loaded.pipeline.domain_id, loaded.pipeline.ns, &holder))) {
      throw std::runtime_error("domain " + std::to_string(loaded.pipeline.domain_id) + ", namespace '" +
                               loaded.pipeline.ns + "' is in use by another heslam run on this host (supervisor pid " +
                               (holder.empty() ? "unknown" : holder) +
                               "); stop it, or choose another domain (--domain N, or --domain auto for a free one)");
    }
  } else if (domain_auto) {
    throw std::runtime_error(
        "--domain auto: a run over several hosts needs the same domain on every host; give it with --domain N");
  }
  runtime::install_shutdown_handlers();
  signal(SIGPIPE, SIG_IGN);  // a closed terminal must not kill the supervisor before it stops its children
  supervisor::SupervisorOptions options;
  options.self_executable = self;
  options.log_dir = log_dir.empty() ? default_log_dir(loaded.pipeline.name) : log_dir;
  options.log_level = log_level;
  options.progress = !progress                 ? supervisor::RunProgress::Mode::kOff
                     : isatty(STDERR_FILENO) ? supervisor::RunProgress::Mode::kLive
                                             : supervisor::RunProgress::Mode::kPlain;
  
  supervisor::Pipeline pipeline = loaded.pipeline;
  if (pipeline.network) {
    // The profile's XML beside the logs: every process reads the same file, and it is kept with
    // the run for inspection.
    std::filesystem::create_directories(options.log_dir);
    const std::filesystem::path xml_file = options.log_dir / "cyclonedds-network.xml";
    std::ofstream xml(xml_file);
    xml << runtime::network_dds_config(*pipeline.network);
    if (!xml.flush()) throw std::runtime_error(xml_file.string() + ": cannot write the network profile's Cyclone XML");
    pipeline.dds_config = "file://" + std::filesystem::absolute(xml_file).string();
  }
  supervisor::Supervisor supervisor(pipeline, options);
  return supervisor.run();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::string(argv[1]) == "--exec-child") heslam::supervisor::exec_child(argc, argv);
  heslam::runtime::adopt_own_run_id();
  try {
    return run(argc, argv);
  } catch (const std::exception& error) {
    std::cerr << "heslam-supervisor: " << error.what() << "\n";
    return 1;
  }
}
