#pragma once
// Embree 3 ray casting of a triangle mesh into depth and colour images, parallel over tiles.
#include <memory>

#include "core/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "core/pose.h"
#include "core/status.h"

namespace voxplan {

struct RenderParams {
  float max_range_m = 0.0f;  // 0: unlimited; farther hits give depth 0
};

struct RenderOutput {
  DepthImage depth;  // z along the optical axis, metres; 0 where no hit
  ColorImage color;  // interpolated vertex colour (grey when the mesh has none); black on miss
};

class MeshRaycaster {
 public:
  // Builds the Embree scene; Embree errors become a Status.
  static Result<std::unique_ptr<MeshRaycaster>> Create(const Mesh& mesh);
  ~MeshRaycaster();
  MeshRaycaster(const MeshRaycaster&) = delete;
  MeshRaycaster& operator=(const MeshRaycaster&) = delete;

  RenderOutput Render(const PinholeCamera& camera, const Pose3f& T_W_C,
                      const RenderParams& params = {}) const;

 private:
  MeshRaycaster() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voxplan
