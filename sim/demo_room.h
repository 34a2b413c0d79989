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

// Axis-aligned solid furniture boxes standing on the floor (low table in the middle, cabinet,
// sofa, tall shelf, footstool), each flush against a wall or >= 0.4 m from it; no overhangs, so
// every hidden surface is a contact (box bottoms, the floor under them, wall behind a flush
// back). Ground truth for occupancy checks.
std::vector<Eigen::AlignedBox3f> DemoFurnitureBoxes(const DemoRoomParams& params = {});

// The room shell (inward-facing) as triangles [0, 12), then box k of DemoFurnitureBoxes as
// triangles [12 (k + 1), 12 (k + 2)) (outward-facing). Every face has its own four vertices so
// flat per-face colours and normals do not bleed across edges.
Mesh BuildDemoRoom(const DemoRoomParams& params = {});
// `frames` camera-to-world poses (OpenCV axes, no roll) on two laps of an ellipse around the
// middle table at 1.3-1.5 m, frame i at angle 4 pi i / frames; the sequence closes on itself.
// The heading swings around "inwards" (across the room) and the pitch between 45 degrees down
// and 30 degrees up, so the two laps see the floor, the ceiling, every wall and every furniture
// face not hidden against a wall or the floor. At kDemoFrames frames consecutive poses are
// < 6 cm and < 0.17 rad apart.
constexpr int kDemoFrames = 240;
std::vector<Pose3d> DemoTrajectory(const DemoRoomParams& params, int frames);
PinholeCamera DemoCamera();  // 640x480, Kinect-like intrinsics

}  // namespace voxplan
