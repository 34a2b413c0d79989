// MeshScene: bounds from the vertices, one Embree render per view; LoadSurfaceScene picks the
// scene by the file's extension.
#include "sim/mesh_scene.h"

#include <utility>

#include "io/map_io.h"
#include "io/mesh_io.h"

namespace voxplan {

Result<std::unique_ptr<MeshScene>> MeshScene::Create(const Mesh& mesh) {
  Result<std::unique_ptr<MeshRaycaster>> raycaster = MeshRaycaster::Create(mesh);
  if (!raycaster.ok()) return raycaster.status();
  return std::make_unique<MeshScene>(mesh, std::move(*raycaster));
}

MeshScene::MeshScene(const Mesh& mesh, std::unique_ptr<MeshRaycaster> raycaster)
    : raycaster_(std::move(raycaster)), has_colour_(!mesh.colors.empty()) {
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
                                                       const MapSceneParams& map_params) {
  if (IsMapPath(path)) {
    Result<TsdfVolume> volume = LoadMap(path);
    if (!volume.ok()) return volume.status();
    if (volume->num_blocks() == 0) return InvalidArgument("the map holds no blocks: " + path);
    return std::unique_ptr<SurfaceScene>(new MapScene(std::move(*volume), map_params));
  }
  Result<Mesh> mesh = ReadMesh(path);
  if (!mesh.ok()) return mesh.status();
  Result<std::unique_ptr<MeshScene>> scene = MeshScene::Create(*mesh);
  if (!scene.ok()) return scene.status();
  return std::unique_ptr<SurfaceScene>(std::move(*scene));
}

}  // namespace voxplan
