#include "sim/demo_room.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace voxplan {

namespace {

using Rgb = std::array<uint8_t, 3>;

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
  // Solid boxes only: a table top on legs has an underside no camera above it can see. Each
  // piece stands free in the middle, seen from all around, or flush in a corner or against a
  // wall: the faces it hides against the walls and the floor are hidden in a real room too, and
  // no gap between furniture and wall hides a face that only a camera in the gap could see.
  std::vector<FurniturePiece> pieces;
  // Coffee table in the middle of the room: the trajectory circles it, so all four sides show;
  // low, so the floor behind it shows from across the room.
  pieces.push_back({box(-0.4f, -0.25f, 0.f, 0.3f, 0.25f, 0.45f), {205, 155, 100}});
  // Cabinet in the +x -y corner.
  pieces.push_back(
      {box(hx - 0.45f, -hy, 0.f, hx, -hy + 0.9f, std::min(1.0f, 0.6f * top)), {125, 75, 45}});
  // Sofa in the -x +y corner.
  pieces.push_back({box(-hx, hy - 1.4f, 0.f, -hx + 0.8f, hy, 0.45f), {40, 120, 145}});
  // Shelf against the +y wall, lower than the camera so its top shows.
  pieces.push_back(
      {box(-0.2f, hy - 0.3f, 0.f, 0.7f, hy, std::min(1.1f, 0.6f * top)), {150, 95, 165}});
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
  // Two laps of an ellipse around the middle table, 0.3 and 0.27 of the room's size out from
  // the centre: the walls stay >= 0.69 m away, the path passes above the sofa and clear of the
  // cabinet and shelf.
  const double a = 0.3 * params.size_x_m, b = 0.27 * params.size_y_m;
  const double z_mid = std::min<double>(kCameraHeight_m, 0.56 * params.height_m);
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  for (int i = 0; i < frames; ++i) {
    const double theta = 4.0 * kPi * double(i) / double(frames);
    // The heading swings around "inwards" (theta + pi), across the room past the table, to
    // nearly along the loop either way, so every wall and furniture face is seen from the far
    // side and obliquely from near it. The pitch goes smoothly between 45 degrees down (the
    // floor near the path and behind the table) and 30 degrees up (ceiling). Both run at
    // half-integer rates per lap, so the second lap passes each place looking the other way up and
    // at another heading; the height bobs by 10 cm, once over the two laps.
    const double yaw = theta + kPi + 1.1 * std::sin(1.5 * theta + 0.3);
    const double pitch_up = kPi / 180.0 * (-7.5 + 37.5 * std::sin(2.5 * theta + 1.0));
    const double z = z_mid + 0.1 * std::sin(0.5 * theta);
    const Eigen::Vector3d forward(std::cos(yaw) * std::cos(pitch_up),
                                  std::sin(yaw) * std::cos(pitch_up), std::sin(pitch_up));
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
