// voxplan bench maps: times the planning-map update per frame (TSDF integration with free-space
// carving at the planning resolution, then the derived maps) and, with --vs-octomap, OctoMap's
// insertPointCloud on the same frames at the same resolution and range, in one run. The runs are
// bench/harness's RunMapsBench; here: options, the JSON and the optional .bt export.
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "bench/harness/maps_bench.h"
#include "core/bounds.h"
#include "io/dataset.h"
#include "io/text_file.h"
#include "planning/octomap_export.h"

namespace voxplan::cli {

namespace {

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

int RunBenchMaps(const MapsOptions& o) {
  OpenedDataset opened;
  if (int code = OpenDatasetInput(o.in, {}, &opened); code != kExitOk) return code;
  std::vector<PathUse> inputs;
  AddInputs(inputs, "the dataset", opened.dataset->InputFiles());
  if (int code =
          RefusePathCollisions({{"--json", o.json_path}, {"--export-bt", o.bt_path}}, inputs);
      code != kExitOk)
    return code;
  const DatasetInfo& info = opened.dataset->info();

  bench::MapsBenchParams params;
  params.resolution_m = o.resolution_m;
  params.trunc_vox = o.trunc_vox;
  params.min_depth_m = o.in.min_depth_m;
  params.max_depth_m = o.in.max_depth_m;
  params.threads = o.threads;
  params.vs_octomap = o.vs_octomap;
  params.dataset_name = o.in.dataset;
  Result<bench::MapsBenchResult> result =
      bench::RunMapsBench(*opened.dataset, opened.indices, params,
                          [](const std::string& text) { std::cerr << text << std::flush; });
  if (!result.ok()) return Fail(result.status().message());
  const TsdfVolume& volume = *result->volume;
  const TimingSummary& maps = result->maps_ms;

  json j;
  j["command"] = "bench maps";
  j["dataset"] = info.root;
  j["format"] = DatasetFormatName(info.format);
  j["resolution"] = o.resolution_m;
  j["trunc_m"] = ShortestDouble(volume.params().trunc_m);
  j["min_depth_m"] = o.in.min_depth_m;
  j["max_depth_m"] = o.in.max_depth_m;
  j["frames"] = result->frames;
  j["threads"] = o.threads;
  j["width"] = info.camera.width;
  j["height"] = info.camera.height;
  j["maps_ms_median"] = RoundTo(maps.median, 3);
  j["maps_ms_p90"] = RoundTo(maps.p90, 3);
  j["maps_ms_mean"] = RoundTo(maps.mean, 3);
  j["integrate_ms_median"] = RoundTo(result->integrate_ms_median, 3);
  j["derived_ms_median"] = RoundTo(result->derived_ms_median, 3);
  j["touched_blocks_median"] = result->touched_blocks_median;
  j["blocks"] = volume.num_blocks();
  j["frontier_voxels"] = result->frontier_voxels;
  j["surface_voxels"] = result->surface_voxels;
  j["map_mb"] = RoundTo(Mib(volume.MemoryBytes()), 2);
  j["octomap_ms_median"] = nullptr;
  j["speedup"] = nullptr;

  if (result->octomap) {
    const bench::OctomapBenchResult& octo = *result->octomap;
    j["octomap_ms_median"] = RoundTo(octo.insert_ms.median, 3);
    j["octomap_ms_p90"] = RoundTo(octo.insert_ms.p90, 3);
    j["speedup"] = RoundTo(octo.speedup, 2);
    j["octomap_leaves"] = octo.leaves;
    j["occupied_agreement"] = RoundTo(octo.occupied_agreement, 4);
    j["free_agreement"] = RoundTo(octo.free_agreement, 4);
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
      ->check(InRange(0.005, 1.0, "m"))
      ->capture_default_str();
  sub->add_option("--trunc-vox", o->trunc_vox, "Truncation distance in voxels")
      ->check(InRange(bounds::kTruncMinVoxels, bounds::kTruncMaxVoxels, "voxels"))
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Threads for the planning map")
      ->check(IntInRange(1, bounds::kThreadsMax))
      ->capture_default_str();
  sub->add_flag("--vs-octomap", o->vs_octomap,
                "Also time OctoMap's insertPointCloud on the same frames");
  sub->add_option("--json", o->json_path, "Write the result JSON")->check(OutputFileValidator());
  sub->add_option("--export-bt", o->bt_path, "Write the final occupancy as an OctoMap .bt")
      ->check(OutputFileValidator());
  return {sub, [o] { return RunBenchMaps(*o); }};
}

}  // namespace voxplan::cli
