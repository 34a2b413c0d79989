// The planning-map timing loop and OctoMap's insertPointCloud beside it, with the agreement of
// the two final maps. The only OctoMap user among the benchmarks.
#include "bench/harness/maps_bench.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/parallel.h"
#include "core/stopwatch.h"
#include "fusion/integrate.h"
#include "planning/integrate_planning.h"
#include "planning/planning_map.h"

namespace voxplan::bench {

namespace {

struct LoadedFrame {
  DepthImage depth;
  Pose3f T_W_C;
};

// The valid pixels of a frame as world points: what OctoMap's insertPointCloud takes.
octomap::Pointcloud WorldCloud(const LoadedFrame& f, const PinholeCamera& cam, float min_depth_m,
                               float max_depth_m) {
  octomap::Pointcloud cloud;
  cloud.reserve(f.depth.data.size());
  for (int v = 0; v < f.depth.height; ++v)
    for (int u = 0; u < f.depth.width; ++u) {
      const float d = f.depth.at(u, v);
      if (!(d >= min_depth_m && d <= max_depth_m)) continue;
      const Eigen::Vector3f p_W = f.T_W_C * cam.Unproject(float(u), float(v), d);
      cloud.push_back(p_W.x(), p_W.y(), p_W.z());
    }
  return cloud;
}

// OctoMap on the same frames, then the agreement on the final maps from OctoMap's side.
OctomapBenchResult RunOctomap(const std::vector<LoadedFrame>& frames, const PinholeCamera& camera,
                              const IntegrateParams& params, double resolution_m,
                              const PlanningMap& map, double maps_median_ms) {
  octomap::OcTree tree(resolution_m);
  std::vector<double> octo_ms;
  for (const LoadedFrame& f : frames) {
    const octomap::Pointcloud cloud = WorldCloud(f, camera, params.min_depth_m, params.max_depth_m);
    const Eigen::Vector3f o_W = f.T_W_C.translation();
    const Stopwatch clock;
    // Points are already inside the depth range, so no max range clipping here.
    tree.insertPointCloud(cloud, octomap::point3d(o_W.x(), o_W.y(), o_W.z()));
    octo_ms.push_back(clock.ElapsedMs());
  }
  OctomapBenchResult result;
  result.insert_ms = Summarize(octo_ms);
  // Agreement on the final maps, from OctoMap's side: of its occupied / free cells (pruned
  // leaves split into cells of the resolution), the fraction we call the same. Ours also
  // marks voxels up to the truncation behind a surface occupied, which OctoMap leaves
  // unknown, so the comparison starts from OctoMap's cells.
  size_t occ = 0, occ_match = 0, fre = 0, fre_match = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::point3d c = it.getCoordinate();
    const double size = it.getSize();
    const int n = std::max(1, int(std::lround(size / resolution_m)));
    const bool occupied = tree.isNodeOccupied(*it);
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const Eigen::Vector3f p(float(c.x() - 0.5 * size + (x + 0.5) * resolution_m),
                                  float(c.y() - 0.5 * size + (y + 0.5) * resolution_m),
                                  float(c.z() - 0.5 * size + (z + 0.5) * resolution_m));
          const VoxelState s = map.StateAt(p);
          if (occupied) {
            ++occ;
            occ_match += s == VoxelState::kOccupied;
          } else {
            ++fre;
            fre_match += s == VoxelState::kFree;
          }
        }
  }
  result.speedup = maps_median_ms > 0 ? result.insert_ms.median / maps_median_ms : 0.0;
  result.leaves = tree.getNumLeafNodes();
  result.occupied_agreement = occ ? double(occ_match) / double(occ) : 0.0;
  result.free_agreement = fre ? double(fre_match) / double(fre) : 0.0;
  return result;
}

}  // namespace

Result<MapsBenchResult> RunMapsBench(const Dataset& dataset, const std::vector<size_t>& indices,
                                     const MapsBenchParams& p, const ProgressText& progress) {
  const DatasetInfo& info = dataset.info();
  auto emit = [&](const std::ostringstream& line) {
    if (progress) progress(line.str() + "\n");
  };

  // Decode once, untimed; frames without a pose or without depth are skipped.
  std::vector<LoadedFrame> frames;
  size_t skipped = 0;
  for (size_t i : indices) {
    Result<Frame> frame = dataset.Load(i);
    if (!frame.ok()) return frame.status().Naming(p.dataset_name);
    const bool has_depth = std::any_of(frame->depth.data.begin(), frame->depth.data.end(),
                                       [](float z) { return z > 0.f; });
    if (!frame->T_W_C || !has_depth) {
      ++skipped;
      continue;
    }
    frames.push_back({std::move(frame->depth), frame->T_W_C->cast<float>()});
  }
  if (frames.empty()) return NotFound("no frame with depth and a pose in " + p.dataset_name);

  const float resolution = float(p.resolution_m);
  const VolumeParams volume_params{resolution, float(p.trunc_vox * p.resolution_m)};
  IntegrateParams params;
  params.min_depth_m = float(p.min_depth_m);
  params.max_depth_m = float(p.max_depth_m);
  params.integrate_color = false;  // a planning map needs no colour
  std::ostringstream header;
  header << "bench maps: " << info.root << " (" << DatasetFormatName(info.format) << "), "
         << frames.size() << " frames (" << skipped << " skipped), " << info.camera.width << "x"
         << info.camera.height << ", resolution " << p.resolution_m << " m, trunc "
         << volume_params.trunc_m << " m, depth [" << p.min_depth_m << ", " << p.max_depth_m
         << "] m, " << p.threads << " threads";
  emit(header);

  MapsBenchResult result;
  result.volume = std::make_unique<TsdfVolume>(volume_params);
  TsdfVolume& volume = *result.volume;
  PlanningMap map(volume);
  std::vector<double> total_ms, integrate_ms, map_ms;
  std::vector<double> touched;
  {
    ThreadLimit limit(p.threads);
    for (const LoadedFrame& f : frames) {
      const Stopwatch clock;
      Result<PlanningFrameStats> stats =
          IntegratePlanningFrame(f.depth, {}, nullptr, info.camera, f.T_W_C, params, volume, map);
      const double ms = clock.ElapsedMs();
      if (!stats.ok()) return stats.status();
      total_ms.push_back(ms);
      integrate_ms.push_back(stats->integrate_ms);
      map_ms.push_back(stats->map_ms);
      touched.push_back(double(stats->integrate.touched_blocks.size()));
    }
  }
  result.frames = frames.size();
  result.skipped = skipped;
  result.maps_ms = Summarize(total_ms);
  result.integrate_ms_median = Summarize(integrate_ms).median;
  result.derived_ms_median = Summarize(map_ms).median;
  result.touched_blocks_median = Summarize(touched).median;
  result.frontier_voxels = map.CountFrontier();
  result.surface_voxels = map.CountSurface();
  const TimingSummary& maps = result.maps_ms;
  std::ostringstream planning;
  planning << "planning map: " << RoundTo(maps.median, 3) << " ms/frame median (integrate "
           << RoundTo(result.integrate_ms_median, 3) << ", derived maps "
           << RoundTo(result.derived_ms_median, 3) << "), p90 " << RoundTo(maps.p90, 3) << " ms, "
           << volume.num_blocks() << " blocks, " << result.frontier_voxels << " frontier and "
           << result.surface_voxels << " surface voxels";
  emit(planning);

  if (p.vs_octomap) {
    const OctomapBenchResult& octo = result.octomap.emplace(
        RunOctomap(frames, info.camera, params, p.resolution_m, map, maps.median));
    std::ostringstream line;
    line << "octomap insertPointCloud: " << RoundTo(octo.insert_ms.median, 3)
         << " ms/frame median, p90 " << RoundTo(octo.insert_ms.p90, 3) << " ms, " << octo.leaves
         << " leaves; speedup " << RoundTo(octo.speedup, 1) << "x; "
         << "agreement: occupied " << RoundTo(octo.occupied_agreement, 3) << ", free "
         << RoundTo(octo.free_agreement, 3);
    emit(line);
  }
  return result;
}

}  // namespace voxplan::bench
