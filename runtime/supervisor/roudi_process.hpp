// iox-roudi for a pipeline whose images go over shared memory (image_transport shm): a running RouDi
// is used as it is; otherwise one is started with the pipeline's roudi_config and stopped (SIGTERM)
// when the supervisor ends. RouDi is one daemon per host, so two pipelines with shm on one host share
// it, and the one that started it stops it at its end (docs/topics.md, Image transport).
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <memory>

#include "runtime/log.hpp"

namespace heslam::supervisor {

class RoudiProcess {
 public:
  // nullptr when a RouDi already runs. Throws one line when iox-roudi is not installed, exits at
  // once, or does not say it is ready in time. Its output goes to log_file.
  static std::unique_ptr<RoudiProcess> ensure(const std::filesystem::path& config,
                                              const std::filesystem::path& log_file, const runtime::Logger& log);
  ~RoudiProcess();
  RoudiProcess(const RoudiProcess&) = delete;
  RoudiProcess& operator=(const RoudiProcess&) = delete;

 private:
  explicit RoudiProcess(pid_t pid) : pid_(pid) {}
  pid_t pid_;
};

}  // namespace heslam::supervisor
