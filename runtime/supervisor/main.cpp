// heslam-supervisor PIPELINE.yaml [--arg key=value ...] [--check] [--domain N|auto] [--namespace NAME]
//                   [--log-dir DIR] [--log-level LEVEL] [--host NAME | --only a,b] [--no-progress] [--no-keyboard]
//                   [--security DIR] [--image-transport udp|shm] [--image-domain N]
#include <signal.h>
#include <unistd.h>

#include <ctime>
#include <fstream>
#include <iostream>

#include "runtime/flags.hpp"
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

// The supervisor's command line, declared once for the parser and the usage.
struct Arguments {
  std::filesystem::path pipeline_file;
  supervisor::PipelineOverrides overrides;
  bool check = false;
  bool progress = true;
  bool keyboard = true;
  bool domain_auto = false;
  bool help = false;
  std::filesystem::path log_dir;
  runtime::LogLevel log_level = runtime::LogLevel::kInfo;
};

runtime::Flags supervisor_flags(Arguments& a) {
  const std::string domain_range = "[0, " + std::to_string(runtime::kMaxDomainId) + "]";
  runtime::Flags flags(
      "heslam-supervisor PIPELINE.yaml [--arg key=value ...] [--check] [--domain N|auto] [--namespace NAME]\n"
      "                         [--log-dir DIR] [--log-level debug|info|warn|error] [--host NAME | --only a,b]\n"
      "                         [--no-progress] [--no-keyboard] [--security DIR] [--image-transport udp|shm] "
      "[--image-domain N]");
  flags
      .toggle("--check", &a.check,
              "validate the pipeline file, every file it references and each heslam program's\n"
              "arguments and config (the program's own --check); start nothing")
      .custom("--domain", "N|auto",
              "DDS domain 0-232 (overrides the file's); auto: the first domain no other heslam run\n"
              "uses (the file's, then 1, 2, ...). A domain in use by another run is refused",
              [&a, domain_range](const std::string& value) {
                if (value == "auto") {
                  a.domain_auto = true;
                  return;
                }
                std::int64_t domain = -1;
                if (!runtime::parse_whole_integer(value, domain) || domain < 0 || domain > runtime::kMaxDomainId) {
                  runtime::throw_bad_flag_value("--domain", "an integer in " + domain_range + " or auto", value);
                }
                a.overrides.domain_id = static_cast<int>(domain);
              })
      .custom("--arg", "k=v", "value for $(arg k) in the pipeline file (overrides its 'args' default)",
              [&a](const std::string& pair) {
                const auto eq = pair.find('=');
                if (eq == std::string::npos || eq == 0) runtime::throw_bad_flag_value("--arg", "key=value", pair);
                a.overrides.args[pair.substr(0, eq)] = pair.substr(eq + 1);
              })
      .custom("--namespace", "NAME", "topic namespace (overrides the file's)",
              [&a](const std::string& value) { a.overrides.ns = value; })
      .path("--log-dir", "DIR", &a.log_dir,
            "per-component logs (default: $HESLAM_LOG_DIR or ~/.heslam/log, + /<pipeline>-<time>)")
      .custom("--log-level", "LEVEL", "debug, info, warn, error or off (default: info)",
              [&a](const std::string& value) {
                const auto level = runtime::parse_log_level(value);
                if (!level) runtime::throw_bad_flag_value("--log-level", "debug, info, warn, error or off", value);
                a.log_level = *level;
              })
      .custom("--host", "NAME", "run only the components of the file's hosts.NAME group; the others run on other hosts",
              [&a](const std::string& value) {
                if (value.empty()) throw std::runtime_error("--host: expected a host group name");
                a.overrides.host = value;
              })
      .custom("--only", "a,b", "run only these components; the others run on other hosts (docs/deployment.md)",
              [&a](const std::string& value) {
                a.overrides.only = runtime::split_list(value);
                if (a.overrides.only.empty()) {
                  throw std::runtime_error("--only: expected component names, e.g. --only frontend,replay");
                }
              })
      .toggle("--no-progress", &a.progress,
              "no run progress (default: a line redrawn on a terminal, else a line per 10 %)", false)
      .toggle("--no-keyboard", &a.keyboard,
              "do not read the terminal (default: space pauses/resumes the components with\n"
              "'pausable: true', e.g. the replay)",
              false)
      .custom("--security", "DIR",
              "DDS Security: run every process with its identity from DIR (heslam-security init DIR;\n"
              "overrides the file's 'security'; docs/security.md)",
              [&a](const std::string& value) { a.overrides.security_dir = value; })
      .custom("--image-transport", "udp|shm",
              "shm: the stereo images over iceoryx shared memory on --image-domain (default:\n"
              "domain + 1); the supervisor uses a running iox-roudi or starts one (docs/topics.md)",
              [&a](const std::string& value) { a.overrides.image_transport = value; })
      .custom("--image-domain", "N", "the DDS domain of the shm image topic (0-232)",
              [&a, domain_range](const std::string& value) {
                std::int64_t domain = -1;
                if (!runtime::parse_whole_integer(value, domain) || domain < 0 || domain > runtime::kMaxDomainId) {
                  runtime::throw_bad_flag_value("--image-domain", "an integer in " + domain_range, value);
                }
                a.overrides.image_domain_id = static_cast<int>(domain);
              })
      .toggle("--help", &a.help, "this help")
      .alias("-h")
      .positional("PIPELINE.yaml", "", [&a](const std::string& arg) {
        if (!a.pipeline_file.empty()) {
          throw std::runtime_error("unexpected argument '" + runtime::quote_value(arg) +
                                   "': one pipeline file per supervisor");
        }
        a.pipeline_file = arg;
      });
  return flags;
}

int run(int argc, char** argv) {
  Arguments arguments;
  runtime::Flags flags = supervisor_flags(arguments);
  flags.parse(argc, argv);
  if (arguments.help) {
    std::cout << flags.usage();
    return 0;
  }
  const std::filesystem::path& pipeline_file = arguments.pipeline_file;
  supervisor::PipelineOverrides& overrides = arguments.overrides;
  const bool check = arguments.check;
  const bool domain_auto = arguments.domain_auto;
  if (pipeline_file.empty()) throw std::runtime_error("missing PIPELINE.yaml\n" + flags.usage());

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
  options.log_dir = arguments.log_dir.empty() ? default_log_dir(loaded.pipeline.name) : arguments.log_dir;
  options.log_level = arguments.log_level;
  options.keyboard = arguments.keyboard;
  options.progress = !arguments.progress     ? supervisor::RunProgress::Mode::kOff
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
