// heslam-occupancy-save: asks a running heslam-occupancy for its map now, as nav2's map_saver_cli asks
// map_server (docs/occupancy.md, "On request"):
//   heslam-occupancy-save -f run/now [--domain N] [--namespace NS] [--timeout S]
// writes run/now.pgm + run/now.yaml (map_server) and run/now.ply; without -f, the process's own output
// stem (the files it writes at the end). Exits 0 once the process replied that it wrote them, 1 when it
// replied a failure, none answered within --timeout, or no heslam-occupancy is running.
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <thread>

#include "runtime/args.hpp"
#include "runtime/flags.hpp"
#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/shutdown.hpp"
#include "runtime/writer.hpp"

namespace {

using namespace heslam;
using Clock = std::chrono::steady_clock;

int run(const runtime::CommonArgs& common, const std::filesystem::path& stem, double timeout_s) {
  const runtime::Participant participant({.domain_id = common.domain_id, .dds_config = common.dds_config});
  const runtime::Topics topics(common.ns);
  // The reply reader first, so that no reply can come before it matched.
  runtime::Reader<msg::OccupancySaveReply> replies(participant, topics.occupancy_save_reply());
  runtime::Writer<msg::OccupancySaveRequest> requests(participant, topics.occupancy_save_request());
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  const auto remaining = [&] {
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::max(Clock::duration{}, deadline - Clock::now()));
  };
  // Volatile: a request written before the process's reader matched would be lost.
  if (!requests.wait_for_readers(1, remaining())) {
    std::cerr << "heslam-occupancy-save: no heslam-occupancy on domain " << common.domain_id << " (topic '"
              << requests.name() << "') within " << timeout_s << " s\n";
    return 1;
  }
  // Wait for its reply writer too, so the reply is not written before we matched it.
  while (replies.matched_writers() < 1 && Clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::random_device random;
  const std::uint64_t id = (static_cast<std::uint64_t>(::getpid()) << 32) ^ random();
  const std::string stem_text = stem.empty() ? std::string() : std::filesystem::absolute(stem).string();
  msg::OccupancySaveRequest request{};
  request.schema_version = msg::kSchemaVersion;
  request.request_id = id;
  request.output_stem = const_cast<char*>(stem_text.c_str());
  requests.write(request);
  while (Clock::now() < deadline && !runtime::shutdown_requested()) {
    for (auto& received : replies.take()) {
      if (!received.info.valid_data || received.sample->request_id != id) continue;  // another requester's
      const msg::OccupancySaveReply& reply = *received.sample;
      if (!reply.ok) {
        std::cerr << "heslam-occupancy-save: heslam-occupancy did not save: " << (reply.message ? reply.message : "")
                  << "\n";
        return 1;
      }
      std::cout << "saved " << reply.output_stem << ".pgm/.yaml (map_server) and " << reply.output_stem
                << ".ply: " << reply.keyframes << " keyframe clouds, " << reply.occupied_cells << " occupied + "
                << reply.free_cells << " free cells, " << reply.points << " points\n";
      return 0;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::cerr << "heslam-occupancy-save: no reply within " << timeout_s
            << " s (the process may be busy fusing: raise --timeout)\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    runtime::install_shutdown_handlers();
    const runtime::CommonArgs common = runtime::parse_common_args(argc, argv, "occupancy_save");
    std::filesystem::path stem;
    double timeout_s = 60.0;
    runtime::Flags flags("heslam-occupancy-save [-f STEM] [options]",
                         "Asks the running heslam-occupancy to write its map now (as nav2's map_saver_cli).");
    flags.path("-f", "STEM", &stem, "STEM.pgm + STEM.yaml (map_server) and STEM.ply (default: the process's own stem)")
        .alias("--output-stem")
        .number("--timeout", "S", &timeout_s, 0.1, 3600.0,
                "seconds for the process to appear and reply (it answers after the work queued before it)");
    if (common.help) {
      std::cout << flags.usage() << runtime::common_args_usage();
      return 0;
    }
    flags.parse(common.rest);
    if (common.check) return 0;
    return run(common, stem, timeout_s);
  } catch (const std::exception& error) {
    std::cerr << "heslam-occupancy-save: " << error.what() << "\n";
    return 1;
  }
}
