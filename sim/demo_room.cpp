#include "sim/demo_room.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace voxplan {

namespace {

using Rgb = std::array<uint8_t, 3>;

constexpr float kWallGap_m = 0.02f;  // furniture stays off the walls: no coplanar faces
constexpr float kCameraHeight_m = 1.4f;
constexpr double kPi = 3.14159265358979323846;

Rgb Shade(const Rgb& c, float factor) {
  Rgb out;
  for (int k = 0; k < 3; ++k) out[k] = uint8_t(std::clamp(std::lround(c[k] * factor), 0l, 255l));
  return out;
}

// Appends the six faces of an axis-aligned box, 12 triangles, four own vertices per face.
// face_colors order: -x, +x, -y, +y, -z (bottom), +z (top). `inward` flips winding and
// normals so the faces look into the box (the room shell).
void AddBox(const Eigen::AlignedBox3f& box, const std::array<Rgb, 6>& face_colors, bool inward,
            Mesh& mesh) {
  for (int axis = 0; axis < 3; ++axis) {
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;  // e_b x e_c = e_axis
    for (int side = 0; side < 2; ++side) {
      const float sign = side == 1 ? 1.f : -1.f;
      // Corners CCW seen from +e_axis; reversed for the -e_axis face.
      std::array<Eigen::Vector3f, 4> corners;
      const float ub[4] = {box.min()[b], box.max()[b], box.max()[b], box.min()[b]};
      const float uc[4] = {box.min()[c], box.min()[c], box.max()[c], box.max()[c]};
      for (int i = 0; i < 4; ++i) {
        corners[i][axis] = side == 1 ? box.max()[axis] : box.min()[axis];
        corners[i][b] = ub[i];
        corners[i][c] = uc[i];
      }
      const bool reverse = (side == 0) != inward;
      if (reverse) std::reverse(corners.begin(), corners.end());
      Eigen::Vector3f normal = Eigen::Vector3f::Zero();
      normal[axis] = inward ? -sign : sign;

      const uint32_t base = uint32_t(mesh.positions.size());
      for (const auto& p : corners) {
        mesh.positions.push_back(p);
        mesh.normals.push_back(normal);
        mesh.colors.push_back(face_colors[axis * 2 + side]);
      }
      mesh.triangles.push_back({base, base + 1, base + 2});
      mesh.triangles.push_back({base, base + 2, base + 3});
    }
  }
}

// Flat-shaded furniture: top brightest, sides by direction, bottom darkest, so edges show.
std::array<Rgb, 6> FurnitureColors(const Rgb& c) {
  return {Shade(c, 0.80f), Shade(c, 0.90f), Shade(c, 0.85f),
          Shade(c, 0.75f), Shade(c, 0.60f), Shade(c, 1.00f)};
}

struct FurniturePiece {
  Eigen::AlignedBox3f box;
  Rgb color;
};

std::vector<FurniturePiece> Furniture(const DemoRoomParams& params) {
  const float hx = 0.5f * params.size_x_m, hy = 0.5f * params.size_y_m;
  const float top = params.height_m;
  auto box = [](float x0, float y0, float z0, float x1, float y1, float z1) {
    return Eigen::AlignedBox3f(Eigen::Vector3f(x0, y0, z0), Eigen::Vector3f(x1, y1, z1));
  };
  std::vector<FurniturePiece> pieces;
  // Table near the -y wall: a top slab on four legs, so there is free space beneath it.
  const float tx0 = -0.9f, tx1 = 0.3f, ty0 = -hy + 0.25f, ty1 = -hy + 1.05f;
  const float leg = 0.06f, table_h = 0.75f, slab = 0.04f;
  pieces.push_back({box(tx0, ty0, table_h - slab, tx1, ty1, table_h), {205, 155, 100}});
  const Rgb leg_color = {95, 65, 40};
  for (int i = 0; i < 4; ++i) {
    const float x0 = (i & 1) ? tx1 - 0.05f - leg : tx0 + 0.05f;
    const float y0 = (i & 2) ? ty1 - 0.05f - leg : ty0 + 0.05f;
    pieces.push_back({box(x0, y0, 0.f, x0 + leg, y0 + leg, table_h - slab), leg_color});
  }
  // Cabinet against the +x wall.
  pieces.push_back({box(hx - kWallGap_m - 0.5f, -hy + 0.3f, 0.f, hx - kWallGap_m, -hy + 1.2f,
                        std::min(1.0f, 0.6f * top)),
                    {125, 75, 45}});
  // Sofa against the -x wall.
  pieces.push_back(
      {box(-hx + kWallGap_m, -0.2f, 0.f, -hx + kWallGap_m + 0.9f, hy - kWallGap_m - 0.1f, 0.45f),
       {40, 120, 145}});
  // Tall shelf against the +y wall.
  pieces.push_back(
      {box(-0.2f, hy - kWallGap_m - 0.35f, 0.f, 0.7f, hy - kWallGap_m, std::min(2.0f, top - 0.2f)),
       {150, 95, 165}});
  return pieces;
}

}  // namespace

std::vector<Eigen::AlignedBox3f> DemoFurnitureBoxes(const DemoRoomParams& params) {
  std::vector<Eigen::AlignedBox3f> boxes;
  for (const auto& piece : Furniture(params)) boxes.push_back(piece.box);
  return boxes;
}

Mesh BuildDemoRoom(const DemoRoomParams& params) {
  Mesh mesh;
  const float hx = 0.5f * params.size_x_m, hy = 0.5f * params.size_y_m;
  const Eigen::AlignedBox3f room(Eigen::Vector3f(-hx, -hy, 0.f),
                                 Eigen::Vector3f(hx, hy, params.height_m));
  // Walls -x, +x, -y, +y, floor, ceiling: each its own colour.
  const std::array<Rgb, 6> room_colors = {Rgb{200, 85, 70},  Rgb{85, 165, 95},  Rgb{75, 115, 205},
                                          Rgb{225, 205, 85}, Rgb{150, 120, 90}, Rgb{235, 235, 228}};
  AddBox(room, room_colors, /*inward=*/true, mesh);
  for (const auto& piece : Furniture(params))
    AddBox(piece.box, FurnitureColors(piece.color), /*inward=*/false, mesh);
  return mesh;
}

std::vector<Pose3d> DemoTrajectory(const DemoRoomParams& params, int frames) {
  std::vector<Pose3d> poses;
  if (frames <= 0) return poses;
  poses.reserve(size_t(frames));
  // An ellipse a quarter of the room's size out from the centre keeps walls >= 0.7 m away,
  // above the furniture (all but the shelf are lower than the camera; the shelf is outside it).
  const double a = 0.25 * params.size_x_m, b = 0.25 * params.size_y_m;
  const double z = std::min<double>(kCameraHeight_m, 0.6 * params.height_m);
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  for (int i = 0; i < frames; ++i) {
    const double theta = 2.0 * kPi * double(i) / double(frames);
    // The heading swings between outwards (theta + 0.5) and ahead along the loop
    // (theta + 1.9): looking only outwards sees the furniture near the path from above and
    // never under the table. The pitch dips from 9 to 37 degrees down, so the floor shows.
    const double yaw = theta + 1.2 + 0.7 * std::sin(2.0 * theta);
    const double pitch_down = 0.4 + 0.25 * std::sin(2.0 * theta + 0.5);
    const Eigen::Vector3d forward(std::cos(yaw) * std::cos(pitch_down),
                                  std::sin(yaw) * std::cos(pitch_down), -std::sin(pitch_down));
    const Eigen::Vector3d right = forward.cross(up).normalized();
    const Eigen::Vector3d down = forward.cross(right);
    Pose3d T_W_C = Pose3d::Identity();
    T_W_C.linear().col(0) = right;
    T_W_C.linear().col(1) = down;
    T_W_C.linear().col(2) = forward;
    T_W_C.translation() = Eigen::Vector3d(a * std::cos(theta), b * std::sin(theta), z);
    poses.push_back(T_W_C);
  }
  return poses;
}

PinholeCamera DemoCamera() {
  PinholeCamera camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = camera.fy = 525.f;
  camera.cx = 319.5f;
  camera.cy = 239.5f;
  return camera;
}

}  // namespace voxplan
