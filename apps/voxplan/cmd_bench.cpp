// voxplan bench fusion|raycast|mesh: times integration, ray casting and meshing on a dataset for
// a list of thread counts, optionally beside Open3D (bench/open3d_fusion.py) on identical frames.
// The runs are bench/harness's RunFusionBench; the JSON and table are cmd_bench_report.cpp's.
#include <algorithm>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/cmd_bench_report.h"
#include "apps/voxplan/path_check.h"
#include "bench/harness/fusion_bench.h"
#include "bench/harness/open3d_runner.h"
#include "core/bounds.h"
#include "core/parallel.h"
#include "fusion/integrate.h"
#include "io/dataset.h"
#include "io/frame_list.h"

namespace voxplan::cli {

namespace {

using bench::BenchMode;
using nlohmann::json;

constexpr int kMaxThreadCount = bounds::kThreadsMax;

Result<std::vector<int>> ParseThreadList(const std::string& text) {
  std::vector<int> threads;
  if (text.empty()) {
    threads = {1, HardwareThreads()};
  } else {
    std::stringstream stream(text);
    std::string item;
    while (std::getline(stream, item, ',')) {
      int value = 0;
      size_t used = 0;
      try {
        value = std::stoi(item, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (item.empty() || used != item.size() || value < 1 || value > kMaxThreadCount) {
        return InvalidArgument("--threads wants a comma-separated list of thread counts (1 to " +
                               std::to_string(kMaxThreadCount) + "), got '" + text + "'");
      }
      threads.push_back(value);
    }
    if (threads.empty() || text.back() == ',') {
      return InvalidArgument("--threads wants a comma-separated list of thread counts, got '" +
                             text + "'");
    }
  }
  // Ascending, so the last row is the largest count (the top-level numbers).
  std::sort(threads.begin(), threads.end());
  threads.erase(std::unique(threads.begin(), threads.end()), threads.end());
  return threads;
}

int RunBench(const BenchOptions& o, BenchMode mode) {
  // Everything the arguments alone can refuse is refused before the dataset is read.
  Result<std::vector<int>> thread_list = ParseThreadList(o.threads);
  if (!thread_list.ok()) return Fail(thread_list.status().message(), kExitUsage);
  if (std::string why = CheckVoxelAndTrunc(o.voxel_size_m, o.trunc_m); !why.empty())
    return Fail(why, kExitUsage);
  if (o.in.max_depth_m <= o.in.min_depth_m) {
    return Fail("--max-depth must be greater than --min-depth", kExitUsage);
  }
  if (o.vs_open3d) {
    if (Status s = bench::CheckOpen3d(); !s.ok()) return Fail("--vs-open3d: " + s.message());
  }

  OpenedDataset opened;
  if (int code = OpenDatasetInput(o.in, {}, &opened); code != kExitOk) return code;
  std::vector<PathUse> inputs;
  AddInputs(inputs, "the dataset", opened.dataset->InputFiles());
  if (int code = RefusePathCollisions({{"--json", o.json_path}}, inputs); code != kExitOk)
    return code;
  const Dataset& dataset = *opened.dataset;
  const DatasetInfo& info = dataset.info();
  const std::vector<size_t>& indices = opened.indices;

  IntegrateParams params;
  params.min_depth_m = float(o.in.min_depth_m);
  params.max_depth_m = float(o.in.max_depth_m);
  params.kernel = kIntegrationKernels.at(o.kernel);
  bench::FusionBenchParams fp;
  fp.mode = mode;
  fp.volume = {float(o.voxel_size_m), float(o.trunc_m), MemoryBudgetBytes(o.memory)};
  fp.integrate = params;
  fp.raycast.max_depth_m = float(o.in.max_depth_m);
  fp.raycast.simd = params.kernel != Kernel::kScalar;
  fp.threads = *thread_list;
  fp.repeat = o.repeat;
  fp.dataset_name = o.in.dataset;
  // The layout of `fuse --frame-list`, from the options as given.
  if (o.vs_open3d) {
    fp.open3d = FrameListParams{info.camera, info.depth_scale, o.voxel_size_m,
                                o.trunc_m,   o.in.min_depth_m, o.in.max_depth_m};
  }

  std::cerr << "bench " << bench::BenchModeName(mode) << ": " << info.root << " ("
            << DatasetFormatName(info.format) << "), " << indices.size() << " frames, voxel "
            << o.voxel_size_m << " m, trunc " << o.trunc_m << " m, threads " << o.threads
            << (o.threads.empty() ? "1,all" : "") << ", " << o.repeat << " repeats, kernel "
            << KernelName(ResolveKernel(params.kernel)) << " (raycast "
            << RaycastKernelName(fp.raycast) << ")" << std::endl;
  Result<bench::FusionBenchResult> result = bench::RunFusionBench(
      dataset, indices, fp, [](const std::string& text) { std::cerr << text << std::flush; });
  if (!result.ok()) return Fail(result.status().message());

  const json j = BenchJson(o, fp, info, indices.size(), *result);
  std::cerr << BenchTable(j, o.vs_open3d) << std::endl;
  if (!o.json_path.empty()) {
    if (Status s = WriteJsonFile(j, o.json_path); !s.ok()) {
      return Fail(MessageNaming(s, o.json_path));
    }
    std::cerr << "json: " << o.json_path << "\n";
  }
  PrintJsonLine(j);
  return kExitOk;
}

void AddBenchOptions(CLI::App* sub, BenchOptions& o) {
  AddDatasetInputOptions(sub, o.in);
  sub->add_option("--voxel-size", o.voxel_size_m, "Voxel size in metres")
      ->check(VoxelSize())
      ->capture_default_str();
  sub->add_option("--trunc", o.trunc_m, "Truncation distance in metres (1 to 64 voxels)")
      ->check(InRange(bounds::kVoxelSizeMinM * bounds::kTruncMinVoxels,
                      bounds::kVoxelSizeMaxM * bounds::kTruncMaxVoxels, "m"))
      ->capture_default_str();
  sub->add_option("--threads", o.threads,
                  "Comma-separated thread counts, one row each (default: 1 and all)");
  sub->add_option("--repeat", o.repeat, "Repeats per thread count (median reported)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  sub->add_option("--kernel", o.kernel,
                  "Integration and ray-casting kernels: scalar reference or SIMD (auto: SIMD "
                  "where the CPU has AVX2)")
      ->check(CLI::IsMember({"auto", "scalar", "simd"}))
      ->capture_default_str();
  sub->add_flag("--vs-open3d", o.vs_open3d,
                "Also run Open3D (legacy and VoxelBlockGrid) on the same frames");
  sub->add_option("--json", o.json_path, "Write the result JSON")->check(OutputFileValidator());
  AddMemoryBudgetOptions(sub, o.memory, /*with_on_limit=*/false);
}

}  // namespace

Command AddBenchCommand(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Benchmark fusion, ray casting and meshing");
  bench->require_subcommand(1);
  struct Parts {
    BenchOptions fusion, raycast, mesh;
    CLI::App *fusion_app = nullptr, *raycast_app = nullptr, *mesh_app = nullptr;
  };
  auto p = std::make_shared<Parts>();
  p->fusion_app = bench->add_subcommand(
      "fusion", "Time integration (per frame), ray casting and meshing per thread count");
  AddBenchOptions(p->fusion_app, p->fusion);
  p->raycast_app =
      bench->add_subcommand("raycast", "Fuse once per thread count (untimed), time ray casting");
  AddBenchOptions(p->raycast_app, p->raycast);
  p->mesh_app = bench->add_subcommand("mesh", "Fuse once per thread count (untimed), time meshing");
  AddBenchOptions(p->mesh_app, p->mesh);
  const Command maps = AddBenchMapsCommand(*bench);
  return {bench, [p, maps] {
            if (maps.app->parsed()) return maps.run();
            if (p->raycast_app->parsed()) return RunBench(p->raycast, BenchMode::kRaycast);
            if (p->mesh_app->parsed()) return RunBench(p->mesh, BenchMode::kMesh);
            return RunBench(p->fusion, BenchMode::kFusion);
          }};
}

}  // namespace voxplan::cli
