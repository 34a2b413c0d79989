#pragma once
// A closed box room seen from inside: exact depth of the walls from any camera inside, and the
// six axis views from one point that together see every wall (96 degree field of view).
#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"

namespace voxplan::test {

struct BoxRoom {
  Eigen::Vector3f lo, hi;  // inner faces of the walls
  // Signed distance to the nearest wall, positive inside the room.
  float Sdf(const Eigen::Vector3f& p) const { return (p - lo).cwiseMin(hi - p).minCoeff(); }
};

inline PinholeCamera RoomCamera(int side = 96) {
  PinholeCamera cam;
  cam.width = cam.height = side;
  cam.fx = cam.fy = 0.45f * float(side);
  cam.cx = cam.cy = 0.5f * float(side) - 0.5f;
  return cam;
}

// z-depth of the wall each pixel sees, for a camera inside the room.
inline DepthImage RenderRoomDepth(const BoxRoom& room, const PinholeCamera& cam,
                                  const Pose3f& T_W_C) {
  DepthImage depth(cam.width, cam.height, 0.f);
  const Eigen::Vector3f o = T_W_C.translation();
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3f ray_C = cam.Unproject(float(u), float(v), 1.f);
      const Eigen::Vector3f dir = T_W_C.linear() * ray_C;  // z-component 1 in the camera
      float t = std::numeric_limits<float>::infinity();
      for (int a = 0; a < 3; ++a) {
        if (dir[a] > 0) t = std::min(t, (room.hi[a] - o[a]) / dir[a]);
        if (dir[a] < 0) t = std::min(t, (room.lo[a] - o[a]) / dir[a]);
      }
      depth.at(u, v) = t;  // dir has unit camera z, so t is the z-depth
    }
  return depth;
}

// Looking along +x, -x, +y, -y, +z, -z from `eye`.
inline std::vector<Pose3f> AxisViews(const Eigen::Vector3f& eye) {
  std::vector<Pose3f> poses;
  for (int a = 0; a < 3; ++a)
    for (float sign : {1.f, -1.f}) {
      Eigen::Vector3f target = eye;
      target[a] += sign;
      poses.push_back(LookAt(eye, target));
    }
  return poses;
}

}  // namespace voxplan::test
