// heslam-bench-synth: stereo pairs rendered per second (one core, and two threads) for the EuRoC-like
// room (752x480) and the KITTI-like street (1241x376), plus the PNG encoding cost of writing them.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "tools/synth/preset.hpp"
#include "tools/synth/sequence.hpp"

namespace {

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace heslam::synth;
  try {
    const int frames = argc > 1 ? std::atoi(argv[1]) : 60;
    if (frames <= 0) throw std::runtime_error("usage: heslam-bench-synth [frames=60]");
    std::printf("%-8s %-9s %-7s %10s %10s %12s %12s\n", "preset", "size", "threads", "wall_ms", "cpu_ms",
                "pairs/s_wall", "pairs/s_cpu");
    for (const char* name : {"room", "street"}) {
      const Preset preset = load_preset(find_preset(name));
      for (int threads : {1, 2}) {
        SequenceRenderer renderer(preset, {.seed = 1, .frames = frames + 1, .threads = threads});
        renderer.render_frame(0);  // warm-up: first-touch of buffers and tables
        const double w0 = wall_seconds(), c0 = cpu_seconds();
        for (int i = 1; i <= frames; ++i) renderer.render_frame(i);
        const double wall = wall_seconds() - w0, cpu = cpu_seconds() - c0;
        std::printf("%-8s %4dx%-4d %-7d %10.2f %10.2f %12.1f %12.1f\n", name, preset.camera.width_px,
                    preset.camera.height_px, threads, 1e3 * wall / frames, 1e3 * cpu / frames, frames / wall,
                    frames / cpu);
      }
      // Writing to disk: PNG encoding of both images (OpenCV default compression).
      SequenceRenderer renderer(preset, {.seed = 1, .frames = 2});
      const SynthFrame f = renderer.render_frame(1);
      std::vector<unsigned char> buf;
      const int reps = 20;
      const double c0 = cpu_seconds();
      for (int i = 0; i < reps; ++i) {
        cv::imencode(".png", f.left, buf);
        cv::imencode(".png", f.right, buf);
      }
      std::printf("%-8s png encode of one pair: %.2f ms cpu\n", name, 1e3 * (cpu_seconds() - c0) / reps);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "heslam-bench-synth: %s\n", e.what());
    return 1;
  }
}
