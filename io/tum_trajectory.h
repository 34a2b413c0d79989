#pragma once
// TUM RGB-D trajectory files (Sturm et al. 2012): one `t tx ty tz qx qy qz qw` line per
// camera-to-world pose. The one reader and writer of the format: the TUM and ICL-NUIM dataset
// readers, `fuse --trajectory`, the simulator's tours and datasets and the trajectory
// evaluation all use it.
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/status.h"

namespace voxplan {

struct TumTrajectory {
  std::vector<double> timestamps_s;
  std::vector<Pose3d> T_W_C;  // one per timestamp, camera-to-world
  std::string source;         // the file it came from, for messages; may be empty
};

// Reads the lines as io/text_file.h tokenises them (`#` comments, blank lines, CRLF and a BOM
// accepted). Timestamps must be finite, non-negative and strictly increasing; quaternions unit
// to 1 %: a near-unit one is renormalised and, when `warnings` is given, a warning added.
// `fields` names the eight fields in messages (ICL-NUIM's first is a frame id). A malformed line
// is refused as `path:line: ...`, a file without poses too.
Result<TumTrajectory> ReadTumTrajectory(
    const std::string& path, std::vector<std::string>* warnings = nullptr,
    const std::string& fields = "timestamp tx ty tz qx qy qz qw");

// Writes `t tx ty tz qx qy qz qw` lines (timestamps with 6 decimals), temporary file then
// rename. Refuses vectors of different lengths.
Status WriteTumTrajectory(const std::string& path, const std::vector<double>& timestamps_s,
                          const std::vector<Pose3d>& T_W_C);
Status WriteTumTrajectory(const std::string& path, const std::vector<double>& timestamps_s,
                          const std::vector<Pose3f>& T_W_C);

}  // namespace voxplan
