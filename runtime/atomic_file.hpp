// Replacing a whole file so that a reader, or a process restarted after a kill -9, finds either the
// previous complete file or the new complete one, never half of either: the new contents go to a
// temporary file in the same folder (a rename is atomic only within one file system), which is then
// renamed over the file.
#pragma once

#include <filesystem>
#include <functional>
#include <string_view>

namespace heslam::runtime {

// The temporary file replace_file writes: the file's name + ".tmp", in its folder. Removed when the
// replacement fails; a kill -9 mid-write can leave it behind, and the next replacement overwrites it.
std::filesystem::path replacement_temp_path(const std::filesystem::path& path);

// Replaces `path` with the file `write` creates at the temporary path it is given. With `sync` the
// new contents are fsynced before the rename and the folder after it: durable across a power loss,
// not only a kill (slower). Throws std::runtime_error naming `path` (and the reason) when `write`
// throws, or the temporary file cannot be synced or renamed; the temporary file is removed then and
// `path` keeps its previous contents.
void replace_file(const std::filesystem::path& path,
                  const std::function<void(const std::filesystem::path& temp)>& write, bool sync = true);

// replace_file with `bytes` as the new contents.
void replace_file_contents(const std::filesystem::path& path, std::string_view bytes, bool sync = true);

}  // namespace heslam::runtime
