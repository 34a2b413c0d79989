// The fusion / ray-casting / meshing benchmark loops: FuseDataset per repeat and thread count,
// the incremental mesher timed per frame, ray casts from spread poses, then Open3D if asked.
#include "bench/harness/fusion_bench.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "bench/harness/measure.h"
#include "bench/harness/open3d_runner.h"
#include "core/parallel.h"
#include "core/stopwatch.h"
#include "fusion/mesh_extract.h"

namespace voxplan::bench {

namespace {

using nlohmann::json;

// One benchmark run: the dataset, the parameters and what the first pass recorded.
class FusionBench {
 public:
  FusionBench(const Dataset& dataset, const std::vector<size_t>& indices,
              const FusionBenchParams& params, const ProgressText& progress)
      : dataset_(dataset),
        info_(dataset.info()),
        indices_(indices),
        p_(params),
        progress_(progress) {
    fuse_params_.integrate = p_.integrate;
    fuse_params_.prefetch = 0;  // decoding timed apart from integration, never beside it
  }

  Result<FusionBenchResult> Run();

 private:
  void Emit(const std::string& text) const {
    if (progress_) progress_(text);
  }
  Status Fuse(TsdfVolume& volume, std::vector<double>* integrate_ms, std::vector<double>* load_ms,
              IncrementalMesher* mesher = nullptr, std::vector<double>* mesh_update_ms = nullptr);
  void TimeRaycasts(const TsdfVolume& volume, int rounds, FusionBenchRow& row) const;
  static void RecordMap(const TsdfVolume& volume, FusionBenchRow& row);
  Status RunFusionRow(FusionBenchRow& row);
  Status RunUntimedFuseRow(FusionBenchRow& row);
  Status RunOpen3dRows(const std::vector<size_t>& raycast_poses);

  const Dataset& dataset_;
  const DatasetInfo& info_;
  const std::vector<size_t>& indices_;
  const FusionBenchParams& p_;
  const ProgressText& progress_;
  FuseParams fuse_params_;
  // Recorded on the first pass only: the frames integrated, in order, and the skipped ones.
  std::vector<FusedFrame> records_;
  size_t skipped_no_pose_ = 0, skipped_no_depth_ = 0;
  bool first_pass_ = true;
  std::vector<FusionBenchRow> rows_;
};

// Streams every selected frame into `volume` (decode timed apart from integration).
// With `mesher`, each frame's changed blocks (found untimed) are meshed again, timed.
Status FusionBench::Fuse(TsdfVolume& volume, std::vector<double>* integrate_ms,
                         std::vector<double>* load_ms, IncrementalMesher* mesher,
                         std::vector<double>* mesh_update_ms) {
  FuseObserver observer;
  if (mesher) {
    observer.integrated = [&](const Frame& frame, const Pose3f& T_W_C, TsdfVolume& v) {
      const std::vector<BlockIndex> changed =
          BlocksInTruncationBand(frame.depth, info_.camera, T_W_C, p_.integrate, v.params());
      const Stopwatch mesh_clock;
      mesher->Update(v, changed);
      mesh_update_ms->push_back(mesh_clock.ElapsedMs());
      return Status::Ok();
    };
  }
  Result<FuseReport> report = FuseDataset(dataset_, indices_, fuse_params_, volume, observer);
  if (!report.ok()) return report.status();
  if (integrate_ms)
    integrate_ms->insert(integrate_ms->end(), report->integrate_ms.begin(),
                         report->integrate_ms.end());
  if (load_ms) load_ms->insert(load_ms->end(), report->load_ms.begin(), report->load_ms.end());
  if (first_pass_) {
    records_ = report->frames;
    skipped_no_pose_ = report->skipped_no_pose;
    skipped_no_depth_ = report->skipped_no_depth;
  }
  first_pass_ = false;
  return Status::Ok();
}

void FusionBench::TimeRaycasts(const TsdfVolume& volume, int rounds, FusionBenchRow& row) const {
  std::vector<double> ms;
  RaycastImages images;
  size_t hits = 0, pixels = 0;
  const std::vector<size_t> poses = RaycastPoseIndexes(records_.size());
  for (int r = 0; r < rounds; ++r) {
    for (size_t k : poses) {
      const Stopwatch clock;
      Raycast(volume, info_.camera, records_[k].T_W_C, p_.raycast, images);
      ms.push_back(clock.ElapsedMs());
      if (r == 0) {
        pixels += images.status.data.size();
        hits += size_t(std::count(images.status.data.begin(), images.status.data.end(),
                                  uint8_t(RayStatus::kHit)));
      }
    }
  }
  row.raycast_median = Summarize(ms).median;
  row.raycast_hit_fraction = pixels ? double(hits) / double(pixels) : 0.0;
}

void FusionBench::RecordMap(const TsdfVolume& volume, FusionBenchRow& row) {
  row.blocks = volume.num_blocks();
  row.voxels = volume.num_voxels();
  row.bytes_per_voxel = row.voxels ? double(volume.MemoryBytes()) / double(row.voxels) : 0.0;
  row.map_mb = Mib(volume.MemoryBytes());
}

// kFusion: every repeat fuses and meshes, timed; the last also casts rays and sizes the map.
Status FusionBench::RunFusionRow(FusionBenchRow& row) {
  std::vector<double> p90s, load_all, mesh_ms, mesh_update_ms;
  for (int r = 0; r < p_.repeat; ++r) {
    auto volume = std::make_unique<TsdfVolume>(p_.volume);
    std::vector<double> integrate_ms;
    // The first repeat also keeps a mesh up to date frame by frame.
    IncrementalMesher mesher;
    if (Status s =
            Fuse(*volume, &integrate_ms, &load_all, r == 0 ? &mesher : nullptr, &mesh_update_ms);
        !s.ok()) {
      Emit("\n");
      return s;
    }
    if (integrate_ms.empty()) {
      Emit("\n");
      return NotFound("no frame was integrated (all skipped): " + p_.dataset_name);
    }
    const TimingSummary t = Summarize(integrate_ms);
    row.integrate_repeat_medians.push_back(t.median);
    p90s.push_back(t.p90);
    const Stopwatch mesh_clock;
    const Mesh mesh = ExtractMesh(*volume);
    mesh_ms.push_back(mesh_clock.ElapsedMs());
    row.mesh_triangles = mesh.num_triangles();
    Emit(" integrate " + Cell(t.median) + " ms");
    if (r + 1 == p_.repeat) {
      TimeRaycasts(*volume, kRaycastRounds, row);
      RecordMap(*volume, row);
    }
  }
  row.integrate_median = Summarize(row.integrate_repeat_medians).median;
  row.integrate_p90 = Summarize(p90s).median;
  row.load_median = Summarize(load_all).median;
  row.mesh_ms = Summarize(mesh_ms).median;
  row.mesh_update_median = Summarize(mesh_update_ms).median;
  return Status::Ok();
}

// kRaycast, kMesh: fused once per thread count, untimed; only the part under test is timed.
Status FusionBench::RunUntimedFuseRow(FusionBenchRow& row) {
  auto volume = std::make_unique<TsdfVolume>(p_.volume);
  if (Status s = Fuse(*volume, nullptr, nullptr); !s.ok()) {
    Emit("\n");
    return s;
  }
  if (records_.empty())
    return NotFound("no frame was integrated (all skipped): " + p_.dataset_name);
  RecordMap(*volume, row);
  if (p_.mode == BenchMode::kRaycast) {
    TimeRaycasts(*volume, std::max(p_.repeat, kRaycastRounds), row);
  } else {
    std::vector<double> mesh_ms;
    for (int r = 0; r < p_.repeat; ++r) {
      const Stopwatch mesh_clock;
      const Mesh mesh = ExtractMesh(*volume);
      mesh_ms.push_back(mesh_clock.ElapsedMs());
      row.mesh_triangles = mesh.num_triangles();
    }
    row.mesh_ms = Summarize(mesh_ms).median;
  }
  return Status::Ok();
}

Status FusionBench::RunOpen3dRows(const std::vector<size_t>& raycast_poses) {
  // Exactly the poses voxplan integrated, as `fuse --frame-list` writes them.
  std::vector<FrameListEntry> frames;
  for (const FusedFrame& r : records_)
    frames.push_back({r.depth_path, r.color_path, r.T_W_C.matrix().cast<double>()});
  // The layout of `fuse --frame-list`, plus a VBG capacity sized from voxplan's map: VBG
  // allocates and touches all of it up front, so a guess would decide its RSS.
  json list = json::parse(FrameListJson(*p_.open3d, frames, -1));
  list["vbg_block_count"] = std::max<size_t>(1024, rows_.back().blocks * 5 / 4);
  TempFrameList list_file;
  VOXPLAN_RETURN_IF_ERROR(list_file.Write(list));
  std::string poses_arg;
  for (size_t k : raycast_poses) {
    if (!poses_arg.empty()) poses_arg += ',';  // (not a ternary + to_string: GCC 12 -Wrestrict)
    poses_arg += std::to_string(k);
  }
  for (FusionBenchRow& row : rows_) {
    // Ray casting exists only on the VBG path; the legacy run would add nothing.
    const std::vector<std::string> paths = p_.mode == BenchMode::kRaycast
                                               ? std::vector<std::string>{"vbg"}
                                               : std::vector<std::string>{"legacy", "vbg"};
    for (const std::string& path : paths) {
      Emit("open3d " + path + ", " + std::to_string(row.threads) + " threads\n");
      Result<json> result = RunOpen3d(list_file.path(), path, row.threads, p_.repeat, poses_arg);
      if (!result.ok()) return result.status();
      (path == "legacy" ? row.open3d_legacy : row.open3d_vbg) = *result;
    }
  }
  return Status::Ok();
}

Result<FusionBenchResult> FusionBench::Run() {
  for (int threads : p_.threads) {
    ThreadLimit limit(threads);
    FusionBenchRow row;
    row.threads = threads;
    Emit("threads " + std::to_string(threads) + ":");
    VOXPLAN_RETURN_IF_ERROR(p_.mode == BenchMode::kFusion ? RunFusionRow(row)
                                                          : RunUntimedFuseRow(row));
    row.peak_rss_mb = PeakRssMb();
    Emit(" raycast " + Cell(row.raycast_median) + " ms, mesh " + Cell(row.mesh_ms) +
         " ms (incremental " + Cell(row.mesh_update_median) + " ms/frame)\n");
    rows_.push_back(std::move(row));
  }

  const std::vector<size_t> raycast_poses = RaycastPoseIndexes(records_.size());
  if (p_.open3d) VOXPLAN_RETURN_IF_ERROR(RunOpen3dRows(raycast_poses));

  FusionBenchResult result;
  result.frames = std::move(records_);
  result.skipped_no_pose = skipped_no_pose_;
  result.skipped_no_depth = skipped_no_depth_;
  result.raycast_poses = raycast_poses;
  result.rows = std::move(rows_);
  return result;
}

}  // namespace

const char* BenchModeName(BenchMode mode) {
  switch (mode) {
    case BenchMode::kFusion:
      return "fusion";
    case BenchMode::kRaycast:
      return "raycast";
    case BenchMode::kMesh:
      return "mesh";
  }
  return "?";
}

std::vector<size_t> RaycastPoseIndexes(size_t n) {
  std::vector<size_t> indexes;
  const size_t m = std::min<size_t>(kRaycastViews, n);
  for (size_t k = 0; k < m; ++k) {
    indexes.push_back(m == 1 ? 0 : size_t(std::llround(double(k) * double(n - 1) / double(m - 1))));
  }
  indexes.erase(std::unique(indexes.begin(), indexes.end()), indexes.end());
  return indexes;
}

Result<FusionBenchResult> RunFusionBench(const Dataset& dataset, const std::vector<size_t>& indices,
                                         const FusionBenchParams& params,
                                         const ProgressText& progress) {
  return FusionBench(dataset, indices, params, progress).Run();
}

}  // namespace voxplan::bench
