#pragma once
// Small ROS 1 bags for the tests, written with rosbag's own writer (io/rosbag_file.h) from
// messages serialized by io/ros_messages.h: a wall 2 m in front of a camera stepping 5 cm
// sideways per frame at 30 Hz, depth 32 x 24, colour 64 x 48 of the same view.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "core/camera.h"
#include "io/image_io.h"
#include "io/ros_messages.h"
#include "io/rosbag_file.h"
#include "tests/io/sens_fixture.h"
#include "tests/support/test_support.h"

namespace voxplan::test {

struct BagScene {
  int frames = 6;
  bool float_depth = true;  // 32FC1 metres, else 16UC1 millimetres
  bool compressed = false;  // colour as a JPEG CompressedImage, else raw bgr8
  bool color = true;
  bool color_info = true;  // a CameraInfo for the colour camera
  bool tf = true;          // poses on /tf (+ /tf_static), else a PoseStamped topic /camera/pose
  double color_offset_s = 0.005;  // colour stamps after depth's
  int color_every = 1;            // colour for every n-th frame only
  double color_camera_x = 0.0;    // != 0: colour in its own TF frame "/rgb_optical", this far right
  double pose_gap_after_s = 0.0;  // > 0: no poses between this time and the last frame's
  std::string depth_topic = "/camera/depth/image";
};

inline double FrameTime(int i) { return 10.0 + i / 30.0; }
inline double FrameX(double t) { return 0.05 * (t - 10.0) * 30.0; }  // 5 cm per frame

inline std::string DepthBytes(const DepthImage& depth, bool float_depth) {
  std::string out;
  for (float d : depth.data) {
    if (float_depth) {
      char b[4];
      std::memcpy(b, &d, 4);
      out.append(b, 4);
    } else {
      const unsigned v = unsigned(std::lround(d * 1000.f));
      out.push_back(char(v & 0xff));
      out.push_back(char(v >> 8));
    }
  }
  return out;
}

inline std::string BgrBytes(const ColorImage& c) {
  std::string out;
  for (uint32_t p : c.data) {
    out.push_back(char(Blue(p)));
    out.push_back(char(Green(p)));
    out.push_back(char(Red(p)));
  }
  return out;
}

inline ros1::Transform MakeTransform(const std::string& parent, const std::string& child, double t,
                                     const Eigen::Vector3d& translation) {
  ros1::Transform tr;
  tr.header.stamp_s = t;
  tr.header.frame_id = parent;
  tr.child_frame_id = child;
  tr.translation = translation;
  return tr;
}

// Writes the scene's bag; returns the depth camera.
inline PinholeCamera WriteBag(const std::string& path, const BagScene& s) {
  auto writer = RosBagWriter::Create(path).value();
  const PinholeCamera cam{32, 24, 24.f, 24.f, 15.5f, 11.5f};
  const Plane wall{Eigen::Vector3f(0, 0, -1), -2.f};
  const ColorImage color = GradientColor(64, 48);
  const std::string jpeg = EncodeJpeg(color, 95).value();
  const auto write = [&](const std::string& topic, double t, const ros1::MessageType& type,
                         const std::string& bytes) {
    if (!writer->Write(topic, t, type.name, type.md5sum, bytes).ok()) std::abort();
  };
  ros1::CameraInfo info;
  info.header.stamp_s = FrameTime(0);
  info.header.frame_id = "depth_optical";
  info.width = 32, info.height = 24;
  const double k[9] = {24, 0, 15.5, 0, 24, 11.5, 0, 0, 1};
  std::copy(k, k + 9, info.K);
  write("/camera/depth/camera_info", FrameTime(0), ros1::kCameraInfo,
        ros1::SerializeCameraInfo(info));
  if (s.color && s.color_info) {
    ros1::CameraInfo ci = info;
    ci.header.frame_id = "depth_optical";  // the same optical frame: registered, a resize
    ci.width = 64, ci.height = 48;
    const double kc[9] = {48, 0, 31.5, 0, 48, 23.5, 0, 0, 1};
    std::copy(kc, kc + 9, ci.K);
    write("/camera/rgb/camera_info", FrameTime(0), ros1::kCameraInfo,
          ros1::SerializeCameraInfo(ci));
  }
  const std::string color_frame = s.color_camera_x != 0.0 ? "/rgb_optical" : "depth_optical";
  if (s.tf) {
    std::vector<ros1::Transform> fixed = {
        MakeTransform("camera_link", "depth_optical", 0.0, Eigen::Vector3d(0, 0, 0.1))};
    if (s.color_camera_x != 0.0)
      fixed.push_back(MakeTransform("camera_link", "rgb_optical", 0.0,
                                    Eigen::Vector3d(s.color_camera_x, 0, 0.1)));
    write("/tf_static", FrameTime(0), ros1::kTfMessage, ros1::SerializeTfMessage(fixed));
  }
  // Poses at 100 Hz from before the first frame to after the last, as mocap would.
  for (double t = FrameTime(0) - 0.05; t <= FrameTime(s.frames - 1) + 0.05; t += 0.01) {
    if (s.pose_gap_after_s > 0.0 && t > s.pose_gap_after_s && t < FrameTime(s.frames - 1) - 0.02)
      continue;
    if (s.tf) {
      // world -> camera_link, which sits 0.1 m behind the optical frame (the static link).
      write("/tf", t, ros1::kTfMessage,
            ros1::SerializeTfMessage(
                {MakeTransform("world", "camera_link", t, Eigen::Vector3d(FrameX(t), 0, -0.1))}));
    } else {
      ros1::PoseStamped p;
      p.header.stamp_s = t;
      p.header.frame_id = "world";
      p.position = Eigen::Vector3d(FrameX(t), 0, 0);
      write("/camera/pose", t, ros1::kPoseStamped, ros1::SerializePoseStamped(p));
    }
  }
  for (int i = 0; i < s.frames; ++i) {
    const double t = FrameTime(i);
    Pose3f T_W_C = Pose3f::Identity();
    T_W_C.translation().x() = float(FrameX(t));
    ros1::Image depth;
    depth.header.stamp_s = t;
    depth.header.frame_id = "depth_optical";
    depth.width = 32, depth.height = 24;
    depth.encoding = s.float_depth ? "32FC1" : "16UC1";
    depth.step = 32 * (s.float_depth ? 4 : 2);
    const std::string depth_bytes = DepthBytes(RenderDepth(wall, cam, T_W_C), s.float_depth);
    depth.data = depth_bytes;
    write(s.depth_topic, t, ros1::kImage, ros1::SerializeImage(depth));
    if (!s.color || i % s.color_every != 0) continue;
    const double tc = t + s.color_offset_s;
    if (s.compressed) {
      ros1::CompressedImage c;
      c.header.stamp_s = tc;
      c.header.frame_id = color_frame;
      c.format = "jpeg";
      c.data = jpeg;
      write("/camera/rgb/image_color/compressed", tc, ros1::kCompressedImage,
            ros1::SerializeCompressedImage(c));
    } else {
      ros1::Image c;
      c.header.stamp_s = tc;
      c.header.frame_id = color_frame;
      c.width = 64, c.height = 48;
      c.encoding = "bgr8";
      c.step = 64 * 3;
      const std::string bgr = BgrBytes(color);
      c.data = bgr;
      write("/camera/rgb/image_color", tc, ros1::kImage, ros1::SerializeImage(c));
    }
  }
  if (!writer->Close().ok()) std::abort();
  return cam;
}

}  // namespace voxplan::test
