#pragma once
// A TSDF map as a SurfaceScene: core's ray caster, tuned for views from outside the map (rays
// pass through back faces, the far limit reaches every block), and its zero crossings as the
// surface samples orbits are framed on.
#include <vector>

#include "core/raycast.h"
#include "core/volume.h"
#include "viewer_offscreen/surface_scene.h"

namespace voxplan {

struct MapSceneParams {
  float min_weight = 0.5f;  // voxels with less weight count as unobserved
  float near_m = 0.0f;      // rays start this far out (cuts away near walls); 0: 0.01 m
  bool simd = true;         // false: the scalar reference march (same images)
};

// The map's surface as points: the centre of every voxel observed with at least `min_weight`
// (and a weight above 0) whose next voxel along x, y or z is observed too with the other sign of
// the distance, the zero crossings the ray caster shows. In sorted block order; where there are
// more than `max_samples` (0: no limit), every k-th of them for the smallest k that leaves at
// most that many. Deterministic for any thread count.
std::vector<Eigen::Vector3f> SurfaceCrossings(const TsdfVolume& volume, float min_weight,
                                              size_t max_samples = 65536);

class MapScene : public SurfaceScene {
 public:
  MapScene(TsdfVolume volume, const MapSceneParams& params);
  // The union of the allocated blocks.
  Eigen::AlignedBox3f Bounds() const override { return bounds_; }
  // SurfaceCrossings at the min_weight the rays see: stray blocks (the truncation band's shell,
  // free space, far noise) hold none or few, so orbits frame the surface, not the blocks.
  std::vector<Eigen::Vector3f> SurfaceSamples() const override;
  // Depth, vertices and normals; colour only when the map stores some (else it shades grey).
  SurfaceImages Render(const PinholeCamera& camera, const Pose3f& T_W_C) const override;

 private:
  TsdfVolume volume_;
  RaycastParams params_;
  Eigen::AlignedBox3f bounds_;
};

}  // namespace voxplan
