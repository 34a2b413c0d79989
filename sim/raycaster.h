#pragma once
// Embree 3 ray casting of a triangle mesh into depth, colour, instance-label and normal images,
// parallel over tiles of 16-ray packets.
#include <Eigen/Core>
#include <memory>

#include "core/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "core/pose.h"
#include "core/status.h"
#include "sim/world.h"

namespace voxplan {

struct RenderParams {
  float max_range_m = 0.0f;  // 0: unlimited; farther hits give depth 0
  bool color = true;         // fill RenderOutput::color
  bool labels = false;       // fill RenderOutput::labels
  bool normals = false;      // fill RenderOutput::normals_C
};

struct RenderOutput {
  DepthImage depth;  // z along the optical axis, metres; 0 where no hit
  // Interpolated vertex colour (grey when the mesh has none); black on a miss. Empty unless
  // RenderParams::color.
  ColorImage color;
  // Instance id of the hit triangle (World::triangle_instance); kNoInstance on a miss, and
  // everywhere for a raycaster made from a bare Mesh. Empty unless RenderParams::labels.
  LabelImage labels;
  // Unit geometric normal of the hit triangle in the camera frame, turned towards the camera
  // (n . ray < 0); zero on a miss. Empty unless RenderParams::normals.
  Image<Eigen::Vector3f> normals_C;
};

// What a viewer may cut away (a dollhouse view of an indoor mesh; the sensors use neither): hits
// on the back of a triangle (the ray along its outward normal: walls and ceilings of a room seen
// from outside, as a fused mesh's normals face the free space it was seen from), and hits
// farther than max_height_m along up_W.
struct MeshCutaway {
  bool cull_back_faces = false;
  bool cut_above = false;
  Eigen::Vector3f up_W = Eigen::Vector3f::UnitZ();  // unit
  float max_height_m = 0.0f;                        // of p . up_W
  bool any() const { return cull_back_faces || cut_above; }
};

class MeshRaycaster {
 public:
  // Builds the Embree scene; Embree errors become a Status. A cutaway makes Embree filter every
  // candidate hit (slower): only viewers ask for one.
  static Result<std::unique_ptr<MeshRaycaster>> Create(const Mesh& mesh,
                                                       const MeshCutaway& cutaway = {});
  // As above, and labels pixels with the world's per-triangle instance ids; refuses a world
  // whose triangle_instance does not have one entry per triangle.
  static Result<std::unique_ptr<MeshRaycaster>> Create(const World& world);
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
