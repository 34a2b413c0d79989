#include "pipeline/fuse_outputs.h"

#include <vector>

#include "core/stopwatch.h"
#include "io/map_io.h"
#include "io/mesh_io.h"
#include "io/point_cloud_io.h"
#include "io/tum_trajectory.h"

namespace voxplan {

WorldUp FusedWorldUp(const DatasetInfo& info, const FuseReport& report, bool tracked) {
  if (!tracked) return info.up;
  WorldUpEstimator votes(info.camera.fy);
  for (const FusedFrame& f : report.frames) votes.Add(f.T_W_C.linear().cast<double>());
  return votes.Result().up;
}

Result<FuseOutputs> WriteFuseOutputs(const FuseOutputPaths& paths, const TsdfVolume& volume,
                                     const FuseReport& report, const MeshParams& mesh_params,
                                     const FrameListParams& list, const Mesh* meshed,
                                     double meshed_ms) {
  FuseOutputs out;
  if (meshed) {
    out.mesh = *meshed;
    out.mesh_ms = meshed_ms;
  } else if (!paths.mesh.empty() || !paths.points.empty()) {
    const Stopwatch mesh_clock;
    out.mesh = ExtractMesh(volume, mesh_params);
    out.mesh_ms = mesh_clock.ElapsedMs();
  }
  if (!paths.mesh.empty()) {
    if (Status s = WriteMesh(out.mesh, paths.mesh); !s.ok()) return s.Naming(paths.mesh);
  }
  if (!paths.points.empty()) {
    if (Status s = WritePointCloudPly(out.mesh, paths.points); !s.ok()) return s;
  }
  if (!paths.map.empty()) {
    if (Status s = SaveMap(volume, paths.map, paths.map_up); !s.ok()) return s.Naming(paths.map);
  }
  if (!paths.trajectory.empty()) {
    std::vector<double> timestamps_s;
    std::vector<Pose3f> poses;
    for (const FusedFrame& f : report.frames) {
      timestamps_s.push_back(f.timestamp_s);
      poses.push_back(f.T_W_C);
    }
    if (Status s = WriteTumTrajectory(paths.trajectory, timestamps_s, poses); !s.ok())
      return s.Naming(paths.trajectory);
  }
  if (!paths.frame_list.empty()) {
    // Exactly the frames integrated, with the parameters, for reference runs of other
    // pipelines (bench/open3d_fusion.py) on identical input.
    std::vector<FrameListEntry> entries;
    for (const FusedFrame& f : report.frames)
      entries.push_back({f.depth_path, f.color_path, f.T_W_C.matrix().cast<double>()});
    if (Status s = WriteFrameList(paths.frame_list, list, entries); !s.ok())
      return s.Naming(paths.frame_list);
  }
  return out;
}

}  // namespace voxplan
