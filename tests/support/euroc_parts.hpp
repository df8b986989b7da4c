// A part of a EuRoC-layout folder for the tests of several agents (docs/agents.md): a copy with a range of
// its frames and their ground truth, the stamps optionally moved (e.g. two halves of one walk started
// together). The images are linked, not copied: the frame lists keep the files' names.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace heslam::test {

// `from`'s header lines, and its data rows [first, first + count) with their stamps (the first column, ns)
// moved by shift_ns, written to `to`.
inline void copy_euroc_rows(const std::filesystem::path& from, const std::filesystem::path& to, int first, int count,
                            std::int64_t shift_ns) {
  std::ifstream in(from);
  std::ofstream out(to);
  std::string line;
  int row = 0;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] == '#') {
      out << line << "\n";
      continue;
    }
    if (row >= first && row < first + count) {
      const std::size_t comma = line.find(',');
      out << std::stoll(line.substr(0, comma)) + shift_ns << line.substr(comma) << "\n";
    }
    ++row;
  }
}

// The EuRoC folder `part`: `source`'s frames [first, first + count) of cam0 and cam1 and their ground truth,
// stamps moved by shift_ns.
inline void make_euroc_part(const std::filesystem::path& source, const std::filesystem::path& part, int first,
                            int count, std::int64_t shift_ns = 0) {
  namespace fs = std::filesystem;
  for (const char* camera : {"cam0", "cam1"}) {
    const fs::path from = source / "mav0" / camera;
    const fs::path to = part / "mav0" / camera;
    fs::create_directories(to);
    fs::create_symlink(from / "data", to / "data");
    fs::copy_file(from / "sensor.yaml", to / "sensor.yaml");
    copy_euroc_rows(from / "data.csv", to / "data.csv", first, count, shift_ns);
  }
  fs::copy_file(source / "mav0/body.yaml", part / "mav0/body.yaml");
  const fs::path truth = "mav0/state_groundtruth_estimate0";
  fs::create_directories(part / truth);
  copy_euroc_rows(source / truth / "data.csv", part / truth / "data.csv", first, count, shift_ns);
}

}  // namespace heslam::test
