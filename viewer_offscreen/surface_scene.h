#pragma once
// What `voxplan render` draws: anything that ray casts to SurfaceImages (a TSDF map here, an
// Embree mesh in sim/mesh_scene.h), so framing, shading and file writing are written once.
#include <Eigen/Geometry>
#include <vector>

#include "core/camera.h"
#include "core/pose.h"
#include "viewer_offscreen/shading.h"

namespace voxplan {

class SurfaceScene {
 public:
  virtual ~SurfaceScene() = default;
  // World box around everything the scene can show; orbits are framed on it unless the scene
  // gives SurfaceSamples.
  virtual Eigen::AlignedBox3f Bounds() const = 0;
  // Points spread over the surface the scene shows (about one per unit of area), to frame orbits
  // on what is drawn rather than on the box (FrameSurface, orbit.h); empty: frame on Bounds().
  virtual std::vector<Eigen::Vector3f> SurfaceSamples() const { return {}; }
  virtual SurfaceImages Render(const PinholeCamera& camera, const Pose3f& T_W_C) const = 0;
};

}  // namespace voxplan
