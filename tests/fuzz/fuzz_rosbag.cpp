// ROS 1 bags as `fuse` and `info` read them (io/rosbag_file.h over Debian's rosbag_storage, the
// messages parsed by io/ros_messages.h): one input is a whole .bag file, opened as a dataset
// (topics chosen by type, camera infos, poses from TF or a PoseStamped topic, colour
// associated) and its first frames loaded; tests/fuzz/dataset_check.h says what must hold.
// rosbag_storage itself is not instrumented: the search sees voxplan's side of it.
#include <cstdint>
#include <string>

#include "io/dataset.h"
#include "tests/fuzz/dataset_check.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace voxplan;
  const std::string path = fuzz::InputFile(data, size, "scan.bag");
  fuzz::CheckDatasetFile(OpenDataset(path), path);
  return 0;
}
