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
#include "io/dataset.h"
#include "io/frame_list.h"
#include "io/world_up.h"
#include "pipeline/fuse_dataset.h"

namespace voxplan {

struct FuseOutputPaths {
  std::string mesh, map, trajectory, frame_list;
  std::string points = {};  // initialised, so that four-path initialisers stay warning-free
  WorldUp map_up = WorldUp::kUnknown;  // the up axis the map records (FusedWorldUp)
};

// The up axis a run's map records: the dataset's (DatasetInfo::up) when the frames were fused at
// its poses; with tracking (whose world is the first frame's dataset pose, or that camera's own
// frame when it had none) the WorldUpEstimator's over the poses used.
WorldUp FusedWorldUp(const DatasetInfo& info, const FuseReport& report, bool tracked);

struct FuseOutputs {
  Mesh mesh;             // empty unless a mesh or points were asked for
  double mesh_ms = 0.0;  // its extraction time
};

// `list` carries the camera and parameters the frame list records. A failure names the file.
// `meshed`: a mesh made elsewhere (a split map's, distributed/), written instead of meshing
// `volume`, in `meshed_ms`.
Result<FuseOutputs> WriteFuseOutputs(const FuseOutputPaths& paths, const TsdfVolume& volume,
                                     const FuseReport& report, const MeshParams& mesh_params,
                                     const FrameListParams& list, const Mesh* meshed = nullptr,
                                     double meshed_ms = 0.0);

}  // namespace voxplan
