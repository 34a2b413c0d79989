// The ROS 1 message parsers (io/ros_messages.h) and the bag dataset above them, on one fuzzed
// message inside an otherwise valid bag (tests/fuzz/rosbag_scaffold.h): the first byte picks the
// slot (a depth or colour image, a compressed image, a camera info, a TF message, a pose, the
// RealSense depth units), the rest is the message's serialized bytes. The slot's parser must
// return views inside the bytes, or a Status; the bag, written with the message in its place,
// is opened as a dataset and its frames loaded (tests/fuzz/dataset_check.h).
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "io/dataset.h"
#include "io/ros_messages.h"
#include "tests/fuzz/dataset_check.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/rosbag_scaffold.h"

namespace {

using namespace voxplan;

bool Inside(std::string_view part, std::string_view whole) {
  return part.empty() ||
         (part.data() >= whole.data() && part.data() + part.size() <= whole.data() + whole.size());
}

// The slot's own parser, straight on the bytes.
void Parse(const ros1::MessageType& type, std::string_view bytes) {
  const std::string name = type.name;
  if (name == ros1::kImage.name) {
    const Result<ros1::Image> m = ros1::ParseImage(bytes);
    if (m.ok() && !Inside(m->data, bytes)) std::abort();
  } else if (name == ros1::kCompressedImage.name) {
    const Result<ros1::CompressedImage> m = ros1::ParseCompressedImage(bytes);
    if (m.ok() && !Inside(m->data, bytes)) std::abort();
  } else if (name == ros1::kCameraInfo.name) {
    (void)ros1::ParseCameraInfo(bytes);
  } else if (name == ros1::kTfMessage.name) {
    const Result<std::vector<ros1::Transform>> m = ros1::ParseTfMessage(bytes);
    // Each transform takes at least 76 bytes: a count beyond that is refused, not allocated.
    if (m.ok() && m->size() * 76 > bytes.size()) std::abort();
  } else if (name == ros1::kPoseStamped.name) {
    (void)ros1::ParsePoseStamped(bytes);
  } else if (name == ros1::kFloat32.name) {
    (void)ros1::ParseFloat32(bytes);
  } else {
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const size_t slot = data[0] % fuzz::kNumBagSlots;
  const std::string bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  const std::vector<fuzz::BagMessage> messages = fuzz::SlotMessages(slot, &bytes);
  for (const fuzz::BagMessage& m : messages)
    if (m.topic == fuzz::kBagSlots[slot].topic) {
      Parse(m.type, bytes);
      break;
    }
  const std::string path = (fuzz::ScratchDir() / "scan.bag").string();
  fuzz::WriteBagFile(path, messages);
  fuzz::CheckDatasetFile(OpenDataset(path), path);
  return 0;
}
