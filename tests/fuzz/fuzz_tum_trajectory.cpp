// TUM trajectory files (io/tum_trajectory.h), as `eval trajectory`, `sim render --trajectory` and
// the TUM / ICL-NUIM readers read them: a trajectory comes back with one finite pose per
// timestamp, or a Status.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "io/tum_trajectory.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace voxplan;
  const std::string path = fuzz::InputFile(data, size, "trajectory.txt");
  std::vector<std::string> warnings;
  const Result<TumTrajectory> t = ReadTumTrajectory(path, &warnings);
  if (t.ok()) {
    if (t->timestamps_s.size() != t->T_W_C.size() || t->T_W_C.empty()) std::abort();
    for (const Pose3d& pose : t->T_W_C)
      if (!pose.matrix().allFinite()) std::abort();
  }
  return 0;
}
