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

// A dollhouse view of an indoor mesh from outside: what hides the rooms cut away.
struct DollhouseParams {
  bool enabled = false;
  Eigen::Vector3f up_W = Eigen::Vector3f::UnitZ();
  float cut_fraction = 0.6f;  // a roofed mesh is cut this far up its extent along up_W
};

// The cutaway a dollhouse view of `mesh` takes (none unless enabled): back faces culled, so a
// fused mesh's walls facing the camera and its ceilings (their normals face the rooms) vanish;
// and for a mesh with a roof (upward-facing area within the top tenth of its extent along up_W,
// at least a fifth of its footprint: a world's closed ceiling slabs) or with walls that face
// outwards too (at least 30 % of the wall area facing away from the centre: closed boxes)
// everything above cut_fraction of that extent.
MeshCutaway DollhouseCutaway(const Mesh& mesh, const DollhouseParams& params);

class MeshScene : public SurfaceScene {
 public:
  // Fails where Embree refuses the mesh.
  static Result<std::unique_ptr<MeshScene>> Create(const Mesh& mesh,
                                                   const MeshCutaway& cutaway = {});
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

// A map (IsMapPath, io/map_io.h: a MapScene with `map_params`; one without blocks is refused;
// its rays always pass back faces, the map's dollhouse) or a mesh file (ReadMesh, then a MeshScene
// with DollhouseCutaway). Errors are the readers' and Embree's.
Result<std::unique_ptr<SurfaceScene>> LoadSurfaceScene(const std::string& path,
                                                       const MapSceneParams& map_params,
                                                       const DollhouseParams& dollhouse = {});

}  // namespace voxplan
