#pragma once
// The few ROS 1 message types voxplan reads from bags, parsed from their serialized bytes by
// hand: Debian 12's generated message headers (libsensor-msgs-dev) do not compile as C++20, and
// ROS's own deserializers allocate a stated length before checking it. Every length and count
// here is checked against the bytes left first. Errors say what was cut short; the caller names
// the bag, topic and message.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/status.h"

namespace voxplan::ros1 {

// Type names and the MD5 sums of their definitions, as bags record them.
struct MessageType {
  const char* name;
  const char* md5sum;
};
inline constexpr MessageType kImage{"sensor_msgs/Image", "060021388200f6f0f447d0fcd9c64743"};
inline constexpr MessageType kCompressedImage{"sensor_msgs/CompressedImage",
                                              "8f7a12909da2c9d3332d540a0977563f"};
inline constexpr MessageType kCameraInfo{"sensor_msgs/CameraInfo",
                                         "c9a58c1b0b154e0e6da7578cb991d214"};
inline constexpr MessageType kTfMessage{"tf2_msgs/TFMessage", "94810edda583a504dfda3829e70d7eec"};
inline constexpr MessageType kPoseStamped{"geometry_msgs/PoseStamped",
                                          "d3812c3cbc69362b77dc0b19b345f8f5"};
// RealSense recordings state their depth units (metres per unit) as a Float32 option topic.
inline constexpr MessageType kFloat32{"std_msgs/Float32", "73fcbf46b49191e672908e50842a83d4"};

struct Header {
  uint32_t seq = 0;
  double stamp_s = 0.0;
  std::string frame_id;
};

struct Image {
  Header header;
  uint32_t height = 0, width = 0;
  std::string encoding;  // "16UC1", "mono16", "32FC1", "rgb8", "bgr8", ...
  bool big_endian = false;
  uint32_t step = 0;      // bytes per row
  std::string_view data;  // points into the parsed bytes
};

struct CompressedImage {
  Header header;
  std::string format;  // "jpeg", "png", "rgb8; jpeg compressed bgr8", ...
  std::string_view data;
};

struct CameraInfo {
  Header header;
  uint32_t height = 0, width = 0;
  double K[9] = {};  // row-major 3x3: fx 0 cx / 0 fy cy / 0 0 1
};

struct Transform {  // geometry_msgs/TransformStamped: T_parent_child, parent = header.frame_id
  Header header;
  std::string child_frame_id;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

struct PoseStamped {
  Header header;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

// Each parses one whole message; bytes left over are an error (a type mismatch).
Result<Image> ParseImage(std::string_view bytes);
Result<CompressedImage> ParseCompressedImage(std::string_view bytes);
Result<CameraInfo> ParseCameraInfo(std::string_view bytes);
Result<std::vector<Transform>> ParseTfMessage(std::string_view bytes);
Result<PoseStamped> ParsePoseStamped(std::string_view bytes);
Result<float> ParseFloat32(std::string_view bytes);

// The serialized form of the same messages, for writing bags (tests, fixtures).
std::string SerializeImage(const Image& m);
std::string SerializeCompressedImage(const CompressedImage& m);
std::string SerializeCameraInfo(const CameraInfo& m);
std::string SerializeTfMessage(const std::vector<Transform>& transforms);
std::string SerializePoseStamped(const PoseStamped& m);
std::string SerializeFloat32(float v);

}  // namespace voxplan::ros1
