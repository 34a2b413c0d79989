#pragma once
// Open3D's RaycastingScene distance queries on a mesh file, the check a user's first script
// after `voxplan fuse` makes: tests/support/open3d_distance.py run by /usr/bin/python3 (Debian's
// python3-open3d). Callers GTEST_SKIP when Open3D is not importable.
#include <filesystem>
#include <string>

namespace voxplan::test {

struct Open3dQuery {
  bool available = false;  // /usr/bin/python3 could import open3d
  int exit_code = -1;      // the script's; 134 when Open3D aborted
  std::string output;      // what it printed (stdout and stderr)
  // Over every vertex, and every vertex moved `offset` along its normal:
  size_t points = 0;
  double max_distance_at_vertices = 0.0, max_distance_off_surface = 0.0;
  double max_signed_mismatch = 0.0;  // max | |signed distance| - distance |
};

Open3dQuery RunOpen3dDistanceQuery(const std::filesystem::path& mesh, float offset);

}  // namespace voxplan::test
