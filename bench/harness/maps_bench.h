#pragma once
// The benchmark behind `voxplan bench maps`: the planning-map update per frame (TSDF
// integration with free-space carving at the planning resolution, then the derived maps) and,
// optionally, OctoMap's insertPointCloud on the same frames at the same resolution and range.
// Frames are decoded (and OctoMap's world-frame point clouds built) before each timed call.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench/harness/measure.h"
#include "core/status.h"
#include "core/volume.h"
#include "io/dataset.h"

namespace voxplan::bench {

struct MapsBenchParams {
  double resolution_m = 0.05;
  double trunc_vox = 3.0;  // truncation distance in voxels
  double min_depth_m = 0.1, max_depth_m = 3.0;
  int threads = 2;  // for the planning map
  bool vs_octomap = false;
  std::string dataset_name;  // how errors name the dataset (the path as given)
};

struct OctomapBenchResult {
  TimingSummary insert_ms;  // insertPointCloud per frame
  double speedup = 0.0;     // its median over the planning map's (0 when that is 0)
  size_t leaves = 0;
  // Of OctoMap's occupied / free cells (pruned leaves split into cells of the resolution), the
  // fraction the planning map calls the same; 0 without such cells.
  double occupied_agreement = 0.0, free_agreement = 0.0;
};

struct MapsBenchResult {
  size_t frames = 0;      // decoded and timed
  size_t skipped = 0;     // without a pose or without depth
  TimingSummary maps_ms;  // the whole planning-map update per frame
  double integrate_ms_median = 0.0, derived_ms_median = 0.0, touched_blocks_median = 0.0;
  size_t frontier_voxels = 0, surface_voxels = 0;
  std::unique_ptr<TsdfVolume> volume;         // the final map
  std::optional<OctomapBenchResult> octomap;  // with params.vs_octomap
};

// Runs the benchmark over dataset frames `indices`; progress lines (the run's summary lines)
// go to `progress`. Fails when a frame cannot be loaded or integrated, or none has depth and a
// pose.
Result<MapsBenchResult> RunMapsBench(const Dataset& dataset, const std::vector<size_t>& indices,
                                     const MapsBenchParams& params,
                                     const ProgressText& progress = {});

}  // namespace voxplan::bench
