#include "tests/support/open3d_query.h"

#include <sys/wait.h>

#include <cstdio>
#include <sstream>

namespace voxplan::test {

Open3dQuery RunOpen3dDistanceQuery(const std::filesystem::path& mesh, float offset) {
  Open3dQuery q;
  const std::string script = std::string(VOXPLAN_TEST_SUPPORT_DIR) + "/open3d_distance.py";
  const std::string command = "timeout 300 /usr/bin/python3 '" + script + "' '" + mesh.string() +
                              "' " + std::to_string(offset) + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return q;
  char buffer[4096];
  size_t n;
  while ((n = fread(buffer, 1, sizeof(buffer), pipe)) > 0) q.output.append(buffer, n);
  const int status = pclose(pipe);
  q.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  // 3: the script could not import open3d; 127: no /usr/bin/python3.
  q.available = q.exit_code != 3 && q.exit_code != 127;
  if (q.exit_code == 0) {
    std::istringstream in(q.output);
    in >> q.points >> q.max_distance_at_vertices >> q.max_distance_off_surface >>
        q.max_signed_mismatch;
  }
  return q;
}

}  // namespace voxplan::test
