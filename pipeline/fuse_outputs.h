#pragma once
// The files a fusion run writes beside its stats: the mesh (extracted here), the map, the
// trajectory of the poses used, the frame list for reference pipelines and the surface points
// (the mesh's vertices: the TSDF's zero crossings, with colour and normals, as a PLY point
// cloud). Each is written through a temporary file and renamed; an empty path skips it.
#include <string>

#include "core/mesh.h"
#include "core/status.h"
#include "core/volume.h"
#include "fusion/mesh_extract.h"
#include "io/frame_list.h"
#include "pipeline/fuse_dataset.h"

namespace voxplan {

struct FuseOutputPaths {
  std::string mesh, map, trajectory, frame_list;
  std::string points = {};  // initialised, so that four-path initialisers stay warning-free
};

struct FuseOutputs {
  Mesh mesh;             // empty unless a mesh or points were asked for
  double mesh_ms = 0.0;  // its extraction time
};

// `list` carries the camera and parameters the frame list records. A failure names the file.
Result<FuseOutputs> WriteFuseOutputs(const FuseOutputPaths& paths, const TsdfVolume& volume,
                                     const FuseReport& report, const MeshParams& mesh_params,
                                     const FrameListParams& list);

}  // namespace voxplan
