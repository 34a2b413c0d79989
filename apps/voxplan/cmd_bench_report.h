#pragma once
// The output of `voxplan bench fusion|raycast|mesh`: the result JSON and the stderr table, built
// from bench/harness's rows (cmd_bench_report.cpp), apart from the options and the run
// (cmd_bench.cpp), so that each file keeps one job.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/voxplan/cli_common.h"
#include "bench/harness/fusion_bench.h"
#include "core/raycast.h"
#include "io/dataset.h"

namespace voxplan::cli {

struct BenchOptions {
  DatasetInput in;
  double voxel_size_m = 0.01;
  double trunc_m = 0.04;
  std::string threads;  // "1,2"; empty: 1 and all hardware threads
  int repeat = 3;
  std::string kernel = "auto";
  bool vs_open3d = false;
  std::string json_path;
  MemoryBudgetOptions memory;  // --max-memory of the volume
};

// "avx2" or "scalar": the ray-casting kernel `params` gets on this CPU.
const char* RaycastKernelName(const RaycastParams& params);

// The result: the run's settings, the largest thread count's numbers again at the top, the
// thread scaling, then the rows; the same keys whether or not Open3D ran.
nlohmann::json BenchJson(const BenchOptions& o, const bench::FusionBenchParams& fp,
                         const DatasetInfo& info, size_t frames_selected,
                         const bench::FusionBenchResult& result);

// The human table of BenchJson's result: a line per thread count, then the largest one's map.
std::string BenchTable(const nlohmann::json& j, bool vs_open3d);

}  // namespace voxplan::cli
