// MeshScene: bounds from the vertices, one Embree render per view; LoadSurfaceScene picks the
// scene by the file's extension.
#include "sim/mesh_scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <utility>

#include "io/map_io.h"
#include "io/mesh_io.h"
#include "io/sharded_map.h"

namespace voxplan {

MeshCutaway DollhouseCutaway(const Mesh& mesh, const DollhouseParams& params) {
  MeshCutaway cut;
  if (!params.enabled || mesh.positions.empty()) return cut;
  cut.cull_back_faces = true;
  const Eigen::Vector3f up = params.up_W.normalized();
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const Eigen::Vector3f& p : mesh.positions) {
    lo = std::min(lo, p.dot(up));
    hi = std::max(hi, p.dot(up));
  }
  const float extent = hi - lo;
  if (!(extent > 0.0f)) return cut;
  // Footprint: the bounding box's area across up (the box's volume over its extent along up is
  // not it for a tilted up; the box of the projected points is).
  Eigen::Vector3f a = up.unitOrthogonal(), b = up.cross(a);
  Eigen::AlignedBox2f footprint;
  for (const Eigen::Vector3f& p : mesh.positions)
    footprint.extend(Eigen::Vector2f(p.dot(a), p.dot(b)));
  const Eigen::Vector2f centre = footprint.center();
  double roof_m2 = 0.0, wall_m2 = 0.0, outward_wall_m2 = 0.0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f& p0 = mesh.positions[t[0]];
    const Eigen::Vector3f n = (mesh.positions[t[1]] - p0).cross(mesh.positions[t[2]] - p0);
    const float len = n.norm();
    if (!(len > 0.0f)) continue;
    const double area = 0.5 * double(len);
    if (n.dot(up) >= 0.9f * len) {                            // upward-facing within ~26°
      if (p0.dot(up) >= hi - 0.1f * extent) roof_m2 += area;  // in the top tenth
    } else if (std::abs(n.dot(up)) < 0.3f * len) {            // a wall
      wall_m2 += area;
      const Eigen::Vector2f from_centre = Eigen::Vector2f(p0.dot(a), p0.dot(b)) - centre;
      if (Eigen::Vector2f(n.dot(a), n.dot(b)).dot(from_centre) > 0.0f) outward_wall_m2 += area;
    }
  }
  // Walls that also face outwards (closed boxes, not surfaces seen from inside) hide the rooms
  // whatever the culling: cut them down too.
  if (roof_m2 >= 0.2 * double(footprint.volume()) ||
      (wall_m2 > 0.0 && outward_wall_m2 >= 0.3 * wall_m2)) {
    cut.cut_above = true;
    cut.up_W = up;
    cut.max_height_m = lo + params.cut_fraction * extent;
  }
  return cut;
}

Result<std::unique_ptr<MeshScene>> MeshScene::Create(const Mesh& mesh, const MeshCutaway& cutaway) {
  Result<std::unique_ptr<MeshRaycaster>> raycaster = MeshRaycaster::Create(mesh, cutaway);
  if (!raycaster.ok()) return raycaster.status();
  return std::make_unique<MeshScene>(mesh, std::move(*raycaster));
}

MeshScene::MeshScene(const Mesh& mesh, std::unique_ptr<MeshRaycaster> raycaster)
    : raycaster_(std::move(raycaster)),
      // A mesh from a map fused without colour stores black: shade it neutral grey instead.
      has_colour_(std::any_of(mesh.colors.begin(), mesh.colors.end(),
                              [](const auto& c) { return c[0] || c[1] || c[2]; })) {
  for (const Eigen::Vector3f& p : mesh.positions) bounds_.extend(p);
}

SurfaceImages MeshScene::Render(const PinholeCamera& camera, const Pose3f& T_W_C) const {
  RenderOutput r = raycaster_->Render(camera, T_W_C);
  SurfaceImages s;
  s.depth = std::move(r.depth);  // vertices and normals follow from depth in Shade
  if (has_colour_) s.color = std::move(r.color);
  return s;
}

Result<std::unique_ptr<SurfaceScene>> LoadSurfaceScene(const std::string& path,
                                                       const MapSceneParams& map_params,
                                                       const DollhouseParams& dollhouse) {
  if (IsMapPath(path)) {
    Result<TsdfVolume> volume = LoadAnyMap(path);  // plain or sharded (io/sharded_map.h)
    if (!volume.ok()) return volume.status();
    if (volume->num_blocks() == 0) return InvalidArgument("the map holds no blocks: " + path);
    return std::unique_ptr<SurfaceScene>(new MapScene(std::move(*volume), map_params));
  }
  Result<Mesh> mesh = ReadMesh(path);
  if (!mesh.ok()) return mesh.status();
  Result<std::unique_ptr<MeshScene>> scene =
      MeshScene::Create(*mesh, DollhouseCutaway(*mesh, dollhouse));
  if (!scene.ok()) return scene.status();
  return std::unique_ptr<SurfaceScene>(std::move(*scene));
}

}  // namespace voxplan
