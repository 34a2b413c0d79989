#pragma once
// The demo's world, built in code: a closed room (floor, walls, ceiling) with a few coloured
// furniture boxes, and a camera trajectory that looks around it.
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/camera.h"
#include "core/mesh.h"
#include "core/pose.h"

namespace voxplan {

struct DemoRoomParams {
  float size_x_m = 4.0f, size_y_m = 3.0f, height_m = 2.5f;  // Z-up, floor at z = 0
};
// The room spans x in [-size_x_m / 2, size_x_m / 2], y likewise, z in [0, height_m].

// Axis-aligned furniture boxes (table top and legs, cabinet, sofa, shelf), each a closed box on
// the floor or on its legs, kept 2 cm off the walls. Ground truth for occupancy checks.
std::vector<Eigen::AlignedBox3f> DemoFurnitureBoxes(const DemoRoomParams& params = {});

// The room shell (inward-facing) as triangles [0, 12), then box k of DemoFurnitureBoxes as
// triangles [12 (k + 1), 12 (k + 2)) (outward-facing). Every face has its own four vertices so
// flat per-face colours and normals do not bleed across edges.
Mesh BuildDemoRoom(const DemoRoomParams& params = {});
// `frames` camera-to-world poses (OpenCV axes) on one elliptic loop inside the room at 1.4 m,
// looking outwards and ahead, pitched down; frame i at angle 2 pi i / frames.
std::vector<Pose3d> DemoTrajectory(const DemoRoomParams& params, int frames);
PinholeCamera DemoCamera();  // 640x480, Kinect-like intrinsics

}  // namespace voxplan
