#pragma once
// The ROS 1 bags fuzz_ros_messages fuzzes one message of, and fuzz_rosbag's seeds: two small
// recordings written with voxplan's own bag writer (io/rosbag_file.h) from messages serialized
// by io/ros_messages.h. Layout A: 16UC1 depth, bgr8 colour at twice its size, both camera infos,
// poses on /tf + /tf_static, a RealSense "Depth Units" option; layout B: 32FC1 depth, JPEG
// CompressedImage colour, a PoseStamped topic. Slot s replaces message kSlots[s] of its layout.
#include <Eigen/Core>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "core/image.h"
#include "io/image_io.h"
#include "io/ros_messages.h"
#include "io/rosbag_file.h"

namespace voxplan::fuzz {

enum class BagLayout { kA, kB };

struct BagMessage {
  std::string topic;
  double time_s = 0.0;
  ros1::MessageType type;
  std::string bytes;
};

inline constexpr int kBagFrames = 3;
inline constexpr int kBagDepthWidth = 4, kBagDepthHeight = 3;
inline double BagFrameTime(int i) { return 10.0 + i / 30.0; }

inline ros1::Header BagHeader(double t, const std::string& frame) {
  ros1::Header h;
  h.stamp_s = t;
  h.frame_id = frame;
  return h;
}

inline std::string BagDepthBytes(bool float_depth, int frame) {
  std::string out;
  for (int k = 0; k < kBagDepthWidth * kBagDepthHeight; ++k) {
    const float metres = 1.5f + 0.01f * float(k) + 0.05f * float(frame);
    if (float_depth) {
      const uint32_t bits = std::bit_cast<uint32_t>(metres);
      for (int b = 0; b < 4; ++b) out.push_back(char((bits >> (8 * b)) & 0xff));
    } else {
      const unsigned mm = unsigned(metres * 1000.f);
      out.push_back(char(mm & 0xff));
      out.push_back(char(mm >> 8));
    }
  }
  return out;
}

inline ColorImage BagColor(int width, int height) {
  ColorImage c(width, height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) c.at(u, v) = PackRgb(uint8_t(40 * u), uint8_t(60 * v), 128);
  return c;
}

inline ros1::CameraInfo BagCameraInfo(int width, int height, double f, const std::string& frame) {
  ros1::CameraInfo info;
  info.header = BagHeader(BagFrameTime(0), frame);
  info.width = uint32_t(width);
  info.height = uint32_t(height);
  const double k[9] = {f, 0, (width - 1) / 2.0, 0, f, (height - 1) / 2.0, 0, 0, 1};
  for (int i = 0; i < 9; ++i) info.K[i] = k[i];
  return info;
}

inline ros1::Transform BagTransform(const std::string& parent, const std::string& child, double t,
                                    double x) {
  ros1::Transform tr;
  tr.header = BagHeader(t, parent);
  tr.child_frame_id = child;
  tr.translation = Eigen::Vector3d(x, 0, 0.1);
  return tr;
}

// The messages of a layout, in the order they are written.
inline std::vector<BagMessage> BagMessages(BagLayout layout) {
  std::vector<BagMessage> out;
  const bool a = layout == BagLayout::kA;
  if (a) {
    out.push_back({"/camera/depth/camera_info", BagFrameTime(0), ros1::kCameraInfo,
                   ros1::SerializeCameraInfo(BagCameraInfo(4, 3, 4.0, "depth_optical"))});
    out.push_back({"/camera/rgb/camera_info", BagFrameTime(0), ros1::kCameraInfo,
                   ros1::SerializeCameraInfo(BagCameraInfo(8, 6, 8.0, "rgb_optical"))});
    out.push_back(
        {"/tf_static", BagFrameTime(0), ros1::kTfMessage,
         ros1::SerializeTfMessage({BagTransform("camera_link", "depth_optical", 0.0, 0.0),
                                   BagTransform("camera_link", "rgb_optical", 0.0, 0.02)})});
    out.push_back({"/device_0/sensor_0/option/Depth Units/value", BagFrameTime(0), ros1::kFloat32,
                   ros1::SerializeFloat32(0.001f)});
  }
  // Poses at 50 Hz around the frames.
  for (int k = -2; k <= 2 * kBagFrames + 2; ++k) {
    const double t = BagFrameTime(0) + 0.02 * k;
    if (a) {
      out.push_back({"/tf", t, ros1::kTfMessage,
                     ros1::SerializeTfMessage({BagTransform("world", "camera_link", t, 0.1 * t)})});
    } else {
      ros1::PoseStamped p;
      p.header = BagHeader(t, "world");
      p.position = Eigen::Vector3d(0.1 * t, 0, 0);
      out.push_back({"/camera/pose", t, ros1::kPoseStamped, ros1::SerializePoseStamped(p)});
    }
  }
  const std::string jpeg = EncodeJpeg(BagColor(8, 6), 90).value();
  for (int i = 0; i < kBagFrames; ++i) {
    const double t = BagFrameTime(i);
    ros1::Image depth;
    depth.header = BagHeader(t, "depth_optical");
    depth.width = kBagDepthWidth, depth.height = kBagDepthHeight;
    depth.encoding = a ? "16UC1" : "32FC1";
    depth.step = uint32_t(kBagDepthWidth * (a ? 2 : 4));
    const std::string depth_bytes = BagDepthBytes(!a, i);
    depth.data = depth_bytes;
    out.push_back({"/camera/depth/image", t, ros1::kImage, ros1::SerializeImage(depth)});
    const double tc = t + 0.005;
    if (a) {
      ros1::Image c;
      c.header = BagHeader(tc, "rgb_optical");
      c.width = 8, c.height = 6;
      c.encoding = "bgr8";
      c.step = 8 * 3;
      std::string bgr;
      for (uint32_t p : BagColor(8, 6).data) {
        bgr.push_back(char(Blue(p)));
        bgr.push_back(char(Green(p)));
        bgr.push_back(char(Red(p)));
      }
      c.data = bgr;
      out.push_back({"/camera/rgb/image_color", tc, ros1::kImage, ros1::SerializeImage(c)});
    } else {
      ros1::CompressedImage c;
      c.header = BagHeader(tc, "depth_optical");
      c.format = "jpeg";
      c.data = jpeg;
      out.push_back({"/camera/rgb/image_color/compressed", tc, ros1::kCompressedImage,
                     ros1::SerializeCompressedImage(c)});
    }
  }
  return out;
}

// Which message each slot of fuzz_ros_messages replaces: the n-th message of a topic.
struct BagSlot {
  BagLayout layout;
  std::string topic;
  int n;
};
inline const BagSlot kBagSlots[] = {
    {BagLayout::kA, "/camera/depth/image", 0},
    {BagLayout::kA, "/camera/depth/image", 1},
    {BagLayout::kA, "/camera/rgb/image_color", 0},
    {BagLayout::kA, "/camera/depth/camera_info", 0},
    {BagLayout::kA, "/camera/rgb/camera_info", 0},
    {BagLayout::kA, "/tf", 3},
    {BagLayout::kA, "/tf_static", 0},
    {BagLayout::kA, "/device_0/sensor_0/option/Depth Units/value", 0},
    {BagLayout::kB, "/camera/depth/image", 0},
    {BagLayout::kB, "/camera/depth/image", 2},
    {BagLayout::kB, "/camera/rgb/image_color/compressed", 0},
    {BagLayout::kB, "/camera/pose", 4},
};
constexpr size_t kNumBagSlots = sizeof(kBagSlots) / sizeof(kBagSlots[0]);

// The messages of slot s's layout, with the slot's message replaced by `bytes` (when given).
inline std::vector<BagMessage> SlotMessages(size_t s, const std::string* bytes = nullptr) {
  static const std::vector<BagMessage> layouts[] = {BagMessages(BagLayout::kA),
                                                    BagMessages(BagLayout::kB)};
  std::vector<BagMessage> messages = layouts[int(kBagSlots[s].layout)];
  int seen = 0;
  for (BagMessage& m : messages)
    if (m.topic == kBagSlots[s].topic && seen++ == kBagSlots[s].n && bytes) m.bytes = *bytes;
  return messages;
}

// The slot's default message (what make_seeds writes as its seed).
inline std::string SlotDefault(size_t s) {
  int seen = 0;
  for (const BagMessage& m : BagMessages(kBagSlots[s].layout))
    if (m.topic == kBagSlots[s].topic && seen++ == kBagSlots[s].n) return m.bytes;
  std::abort();
}

// Writes the messages as a bag; aborts on failure, which is the harness's fault.
inline void WriteBagFile(const std::string& path, const std::vector<BagMessage>& messages) {
  Result<std::unique_ptr<RosBagWriter>> writer = RosBagWriter::Create(path);
  if (!writer.ok()) std::abort();
  for (const BagMessage& m : messages)
    if (!(*writer)->Write(m.topic, m.time_s, m.type.name, m.type.md5sum, m.bytes).ok())
      std::abort();
  if (!(*writer)->Close().ok()) std::abort();
}

}  // namespace voxplan::fuzz
