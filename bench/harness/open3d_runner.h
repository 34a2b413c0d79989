#pragma once
// Runs Open3D beside voxplan: bench/open3d_fusion.py (from the source tree) under
// /usr/bin/python3 as a child process, fed a frame list in a temporary file, its last stdout
// line read back as JSON. No shell: argv and environment are passed as they are.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/status.h"

namespace voxplan::bench {

// Runs argv with extra environment entries (no shell), stdout captured, stderr passed through
// (or to /dev/null when quiet). Returns the exit status (as waitpid gives it) or an error when it
// could not be started.
Result<int> Spawn(const std::vector<std::string>& argv, const std::vector<std::string>& extra_env,
                  std::string* out, bool quiet = false);

// The frame list in a private temporary file, removed when this goes out of scope.
class TempFrameList {
 public:
  TempFrameList() = default;
  TempFrameList(const TempFrameList&) = delete;
  TempFrameList& operator=(const TempFrameList&) = delete;
  ~TempFrameList();
  Status Write(const nlohmann::json& list);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Refuses Open3D runs before any work when the interpreter, Open3D or the script is missing;
// the message says how to install it.
Status CheckOpen3d();

// One script run: `path` is "legacy" or "vbg", on `threads` OpenMP threads, `repeat` times,
// casting rays from the frames at `raycast_poses` ("0,4,9"). Returns the script's JSON object.
Result<nlohmann::json> RunOpen3d(const std::string& list_path, const std::string& path, int threads,
                                 int repeat, const std::string& raycast_poses);

}  // namespace voxplan::bench
