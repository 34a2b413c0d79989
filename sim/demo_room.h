#pragma once
// The demo's world, built in code: a closed room (floor, walls, ceiling) with a few coloured
// furniture boxes, and a camera trajectory that looks around it.
#include <cstdint>
#include <vector>

#include "core/camera.h"
#include "core/mesh.h"
#include "core/pose.h"

namespace voxplan {

struct DemoRoomParams {
  float size_x_m = 4.0f, size_y_m = 3.0f, height_m = 2.5f;  // Z-up, floor at z = 0
};

Mesh BuildDemoRoom(const DemoRoomParams& params = {});
// `frames` camera-to-world poses (OpenCV axes) on a loop inside the room, looking outwards.
std::vector<Pose3d> DemoTrajectory(const DemoRoomParams& params, int frames);
PinholeCamera DemoCamera();  // 640x480, Kinect-like intrinsics

}  // namespace voxplan
