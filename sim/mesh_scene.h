#pragma once
// A mesh as a SurfaceScene (viewer_offscreen/surface_scene.h) through the Embree renderer, and
// the loader that opens a map or a mesh file as one, so `voxplan render` draws both alike.
#include <memory>
#include <string>

#include "core/mesh.h"
#include "core/status.h"
#include "sim/raycaster.h"
#include "viewer_offscreen/map_scene.h"
#include "viewer_offscreen/surface_scene.h"

namespace voxplan {

class MeshScene : public SurfaceScene {
 public:
  // Fails where Embree refuses the mesh.
  static Result<std::unique_ptr<MeshScene>> Create(const Mesh& mesh);
  MeshScene(const Mesh& mesh, std::unique_ptr<MeshRaycaster> raycaster);
  // The box around the mesh's vertices.
  Eigen::AlignedBox3f Bounds() const override { return bounds_; }
  // Depth, and colour when the mesh has vertex colours; Shade derives vertices and normals.
  SurfaceImages Render(const PinholeCamera& camera, const Pose3f& T_W_C) const override;

 private:
  std::unique_ptr<MeshRaycaster> raycaster_;
  bool has_colour_;
  Eigen::AlignedBox3f bounds_;
};

// A map (IsMapPath, io/map_io.h: a MapScene with `map_params`; one without blocks is refused) or a
// mesh file (ReadMesh, then a MeshScene). Errors are the readers' and Embree's.
Result<std::unique_ptr<SurfaceScene>> LoadSurfaceScene(const std::string& path,
                                                       const MapSceneParams& map_params);

}  // namespace voxplan
