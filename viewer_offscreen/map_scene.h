#pragma once
// A TSDF map as a SurfaceScene: core's ray caster, tuned for views from outside the map (rays
// pass through back faces, the far limit reaches every block).
#include "core/raycast.h"
#include "core/volume.h"
#include "viewer_offscreen/surface_scene.h"

namespace voxplan {

struct MapSceneParams {
  float min_weight = 0.5f;  // voxels with less weight count as unobserved
  float near_m = 0.0f;      // rays start this far out (cuts away near walls); 0: 0.01 m
  bool simd = true;         // false: the scalar reference march (same images)
};

class MapScene : public SurfaceScene {
 public:
  MapScene(TsdfVolume volume, const MapSceneParams& params);
  // The union of the allocated blocks.
  Eigen::AlignedBox3f Bounds() const override { return bounds_; }
  // Depth, vertices and normals; colour only when the map stores some (else it shades grey).
  SurfaceImages Render(const PinholeCamera& camera, const Pose3f& T_W_C) const override;

 private:
  TsdfVolume volume_;
  RaycastParams params_;
  Eigen::AlignedBox3f bounds_;
};

}  // namespace voxplan
