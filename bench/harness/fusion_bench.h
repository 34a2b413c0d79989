#pragma once
// The benchmark behind `voxplan bench fusion|raycast|mesh`: per thread count, repeated runs of
// integration, ray casting and meshing over a dataset, timed, with the map's size, and
// optionally Open3D on the same frames. It measures; front ends print (progress comes as text
// to a callback).
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bench/harness/measure.h"
#include "core/raycast.h"
#include "core/status.h"
#include "core/volume.h"
#include "fusion/integrate.h"
#include "io/dataset.h"
#include "io/frame_list.h"
#include "pipeline/fuse_dataset.h"

namespace voxplan::bench {

// kFusion times everything; kRaycast and kMesh fuse once per thread count (untimed) and time
// only the part under test.
enum class BenchMode { kFusion, kRaycast, kMesh };
const char* BenchModeName(BenchMode mode);  // "fusion", "raycast", "mesh"

inline constexpr int kRaycastViews = 10;  // poses spread over the sequence
inline constexpr int kRaycastRounds = 3;  // each pose cast this many times

// Indexes (into the integrated frames) of up to kRaycastViews poses spread over the sequence.
std::vector<size_t> RaycastPoseIndexes(size_t n);

struct FusionBenchParams {
  BenchMode mode = BenchMode::kFusion;
  VolumeParams volume;
  IntegrateParams integrate;
  RaycastParams raycast;
  std::vector<int> threads;  // one row each, in this order
  int repeat = 3;
  // Set: also run Open3D (bench/open3d_fusion.py) per row on exactly the frames voxplan
  // integrated; the frame list carries these parameters (a VBG capacity is added from the map).
  std::optional<FrameListParams> open3d;
  std::string dataset_name;  // how errors name the dataset (the path as given)
};

// One thread count. Timings are medians in ms; absent where the mode does not time them.
struct FusionBenchRow {
  int threads = 0;
  std::optional<double> integrate_median, integrate_p90, load_median, raycast_median, mesh_ms;
  std::optional<double> mesh_update_median;  // incremental meshing of one frame's changes
  std::vector<double> integrate_repeat_medians;
  double raycast_hit_fraction = 0.0;
  size_t mesh_triangles = 0, blocks = 0, voxels = 0;
  double bytes_per_voxel = 0.0, map_mb = 0.0, peak_rss_mb = 0.0;
  nlohmann::json open3d_legacy, open3d_vbg;  // the script's JSON per path, null when not run
};

struct FusionBenchResult {
  // Recorded on the first pass only: the frames integrated, in order, and the skipped ones.
  std::vector<FusedFrame> frames;
  size_t skipped_no_pose = 0, skipped_no_depth = 0;
  std::vector<size_t> raycast_poses;  // RaycastPoseIndexes(frames.size())
  std::vector<FusionBenchRow> rows;   // one per params.threads entry
};

// Runs the benchmark over dataset frames `indices`. Fails when a frame cannot be fused, when no
// frame is integrated, or when Open3D fails.
Result<FusionBenchResult> RunFusionBench(const Dataset& dataset, const std::vector<size_t>& indices,
                                         const FusionBenchParams& params,
                                         const ProgressText& progress = {});

}  // namespace voxplan::bench
