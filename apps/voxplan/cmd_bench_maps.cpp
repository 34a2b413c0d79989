// voxplan bench maps: times the planning-map update per frame (TSDF integration with free-space
// carving at the planning resolution, then the derived maps) and, with --vs-octomap, OctoMap's
// insertPointCloud on the same frames at the same resolution and range, in one run. Frames are
// decoded (and OctoMap's world-frame point clouds built) before each timed call.
#include <octomap/OcTree.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "apps/voxplan/cli_common.h"
#include "core/parallel.h"
#include "io/dataset.h"
#include "planning/integrate_planning.h"
#include "planning/octomap_export.h"
#include "planning/planning_map.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct MapsOptions {
  DatasetInput in;  // 30 frames unless told otherwise (set where the options are added)
  double resolution_m = 0.05;
  double trunc_vox = 3.0;
  int threads = 2;
  bool vs_octomap = false;
  std::string json_path;
  std::string bt_path;
};

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

int RunBenchMaps(const MapsOptions& o) {
  OpenedDataset opened;
  if (int code = OpenDatasetInput(o.in, {}, &opened); code != kExitOk) return code;
  const Dataset& dataset = *opened.dataset;
  const DatasetInfo& info = dataset.info();

  // Decode once, untimed; frames without a pose or without depth are skipped.
  std::vector<LoadedFrame> frames;
  size_t skipped = 0;
  for (size_t i : opened.indices) {
    Result<Frame> frame = dataset.Load(i);
    if (!frame.ok()) return Fail(MessageNaming(frame.status(), o.in.dataset));
    const bool has_depth = std::any_of(frame->depth.data.begin(), frame->depth.data.end(),
                                       [](float z) { return z > 0.f; });
    if (!frame->T_W_C || !has_depth) {
      ++skipped;
      continue;
    }
    frames.push_back({std::move(frame->depth), frame->T_W_C->cast<float>()});
  }
  if (frames.empty()) return Fail("no frame with depth and a pose in " + o.in.dataset);

  const float resolution = float(o.resolution_m);
  const VolumeParams volume_params{resolution, float(o.trunc_vox * o.resolution_m)};
  IntegrateParams params;
  params.min_depth_m = float(o.in.min_depth_m);
  params.max_depth_m = float(o.in.max_depth_m);
  params.integrate_color = false;  // a planning map needs no colour
  std::cerr << "bench maps: " << info.root << " (" << DatasetFormatName(info.format) << "), "
            << frames.size() << " frames (" << skipped << " skipped), " << info.camera.width << "x"
            << info.camera.height << ", resolution " << o.resolution_m << " m, trunc "
            << volume_params.trunc_m << " m, depth [" << o.in.min_depth_m << ", "
            << o.in.max_depth_m << "] m, " << o.threads << " threads" << std::endl;

  TsdfVolume volume(volume_params);
  PlanningMap map(volume);
  std::vector<double> total_ms, integrate_ms, map_ms;
  std::vector<double> touched;
  {
    ThreadLimit limit(o.threads);
    for (const LoadedFrame& f : frames) {
      const Stopwatch clock;
      Result<PlanningFrameStats> stats =
          IntegratePlanningFrame(f.depth, {}, nullptr, info.camera, f.T_W_C, params, volume, map);
      const double ms = clock.ElapsedMs();
      if (!stats.ok()) return Fail(stats.status().message());
      total_ms.push_back(ms);
      integrate_ms.push_back(stats->integrate_ms);
      map_ms.push_back(stats->map_ms);
      touched.push_back(double(stats->integrate.touched_blocks.size()));
    }
  }
  const TimingSummary maps = Summarize(total_ms);
  std::cerr << "planning map: " << RoundTo(maps.median, 3) << " ms/frame median (integrate "
            << RoundTo(Summarize(integrate_ms).median, 3) << ", derived maps "
            << RoundTo(Summarize(map_ms).median, 3) << "), p90 " << RoundTo(maps.p90, 3) << " ms, "
            << volume.num_blocks() << " blocks, " << map.CountFrontier() << " frontier and "
            << map.CountSurface() << " surface voxels" << std::endl;

  json j;
  j["command"] = "bench maps";
  j["dataset"] = info.root;
  j["format"] = DatasetFormatName(info.format);
  j["resolution"] = o.resolution_m;
  j["trunc_m"] = ShortestDouble(volume_params.trunc_m);
  j["min_depth_m"] = o.in.min_depth_m;
  j["max_depth_m"] = o.in.max_depth_m;
  j["frames"] = frames.size();
  j["threads"] = o.threads;
  j["width"] = info.camera.width;
  j["height"] = info.camera.height;
  j["maps_ms_median"] = RoundTo(maps.median, 3);
  j["maps_ms_p90"] = RoundTo(maps.p90, 3);
  j["maps_ms_mean"] = RoundTo(maps.mean, 3);
  j["integrate_ms_median"] = RoundTo(Summarize(integrate_ms).median, 3);
  j["derived_ms_median"] = RoundTo(Summarize(map_ms).median, 3);
  j["touched_blocks_median"] = Summarize(touched).median;
  j["blocks"] = volume.num_blocks();
  j["frontier_voxels"] = map.CountFrontier();
  j["surface_voxels"] = map.CountSurface();
  j["map_mb"] = RoundTo(Mib(volume.MemoryBytes()), 2);
  j["octomap_ms_median"] = nullptr;
  j["speedup"] = nullptr;

  if (o.vs_octomap) {
    octomap::OcTree tree(o.resolution_m);
    std::vector<double> octo_ms;
    for (const LoadedFrame& f : frames) {
      const octomap::Pointcloud cloud =
          WorldCloud(f, info.camera, params.min_depth_m, params.max_depth_m);
      const Eigen::Vector3f o_W = f.T_W_C.translation();
      const Stopwatch clock;
      // Points are already inside the depth range, so no max range clipping here.
      tree.insertPointCloud(cloud, octomap::point3d(o_W.x(), o_W.y(), o_W.z()));
      octo_ms.push_back(clock.ElapsedMs());
    }
    const TimingSummary octo = Summarize(octo_ms);
    // Agreement on the final maps, from OctoMap's side: of its occupied / free cells (pruned
    // leaves split into cells of the resolution), the fraction we call the same. Ours also
    // marks voxels up to the truncation behind a surface occupied, which OctoMap leaves
    // unknown, so the comparison starts from OctoMap's cells.
    size_t occ = 0, occ_match = 0, fre = 0, fre_match = 0;
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      const octomap::point3d c = it.getCoordinate();
      const double size = it.getSize();
      const int n = std::max(1, int(std::lround(size / o.resolution_m)));
      const bool occupied = tree.isNodeOccupied(*it);
      for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) {
            const Eigen::Vector3f p(float(c.x() - 0.5 * size + (x + 0.5) * o.resolution_m),
                                    float(c.y() - 0.5 * size + (y + 0.5) * o.resolution_m),
                                    float(c.z() - 0.5 * size + (z + 0.5) * o.resolution_m));
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
    const double speedup = maps.median > 0 ? octo.median / maps.median : 0.0;
    std::cerr << "octomap insertPointCloud: " << RoundTo(octo.median, 3) << " ms/frame median, p90 "
              << RoundTo(octo.p90, 3) << " ms, " << tree.getNumLeafNodes() << " leaves; speedup "
              << RoundTo(speedup, 1) << "x; "
              << "agreement: occupied " << RoundTo(occ ? double(occ_match) / double(occ) : 0, 3)
              << ", free " << RoundTo(fre ? double(fre_match) / double(fre) : 0, 3) << std::endl;
    j["octomap_ms_median"] = RoundTo(octo.median, 3);
    j["octomap_ms_p90"] = RoundTo(octo.p90, 3);
    j["speedup"] = RoundTo(speedup, 2);
    j["octomap_leaves"] = tree.getNumLeafNodes();
    j["occupied_agreement"] = RoundTo(occ ? double(occ_match) / double(occ) : 0.0, 4);
    j["free_agreement"] = RoundTo(fre ? double(fre_match) / double(fre) : 0.0, 4);
  }

  if (!o.bt_path.empty()) {
    Result<OctomapExportStats> bt = ExportOctomap(volume, o.bt_path);
    if (!bt.ok()) return Fail(bt.status().message());
    std::cerr << "octomap: " << o.bt_path << " (" << bt->occupied_voxels << " occupied, "
              << bt->free_voxels << " free voxels)" << std::endl;
    j["bt"] = o.bt_path;
  }
  if (!o.json_path.empty()) {
    if (Status s = WriteJsonFile(j, o.json_path); !s.ok()) return Fail(s.message());
    std::cerr << "json: " << o.json_path << "\n";
  }
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddBenchMapsCommand(CLI::App& bench) {
  auto o = std::make_shared<MapsOptions>();
  CLI::App* sub = bench.add_subcommand(
      "maps", "Time the planning-map update per frame, optionally beside OctoMap");
  o->in.frames = 30;
  AddDatasetInputOptions(sub, o->in);
  sub->add_option("--resolution", o->resolution_m, "Planning voxel size in metres")
      ->check(CLI::Range(0.005, 1.0))
      ->capture_default_str();
  sub->add_option("--trunc-vox", o->trunc_vox, "Truncation distance in voxels")
      ->check(CLI::Range(1.0, 64.0))
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Threads for the planning map")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  sub->add_flag("--vs-octomap", o->vs_octomap,
                "Also time OctoMap's insertPointCloud on the same frames");
  sub->add_option("--json", o->json_path, "Write the result JSON")->check(OutputFileValidator());
  sub->add_option("--export-bt", o->bt_path, "Write the final occupancy as an OctoMap .bt")
      ->check(OutputFileValidator());
  return {sub, [o] { return RunBenchMaps(*o); }};
}

}  // namespace voxplan::cli
