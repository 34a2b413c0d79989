#pragma once
// A whole fusion run over a dataset: the frame loop that `voxplan fuse`, `voxplan bench`, the
// demo and the tests share. Per selected frame: load, skip a frame without valid depth, choose
// the pose (the dataset's, or with tracking the tracker's: the first frame starts from the
// dataset pose, else the identity; a frame that loses tracking is not integrated), integrate,
// record; the next frames are decoded meanwhile (FuseParams::prefetch). A dataset pose fails
// PoseProblem (pipeline/frame_checks.h) or the reader rejected it: skipped and counted; the first
// frames' depth is checked for a wrong depth scale. Counts and timings come back in the report;
// progress and warnings go to the observer, never printed here.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/status.h"
#include "core/volume.h"
#include "fusion/integrate.h"
#include "fusion/tracking.h"
#include "io/dataset.h"

namespace voxplan {

// What a run does once the volume's memory budget (VolumeParams::max_memory_bytes) is reached.
enum class OnMemoryLimit {
  kDrop,  // keep going without new blocks: warn once, count what was dropped
  kFail,  // stop with a ResourceExhausted status naming the budget
};

struct FuseParams {
  IntegrateParams integrate;
  OnMemoryLimit on_memory_limit = OnMemoryLimit::kDrop;
  // Frames decoded ahead, on worker tasks, while the caller's thread fuses the one before
  // (Dataset::Load is then called from several threads at once, for different frames). Any
  // value gives the same results: frames are fused in order on the calling thread, and the
  // observer is called there. 0: load, then fuse, one frame after the other.
  size_t prefetch = kDefaultPrefetch;
  static constexpr size_t kDefaultPrefetch = 3;
  static constexpr size_t kMaxPrefetch = 64;
  // Estimate poses by frame-to-model ICP instead of reading them from the dataset.
  bool track = false;
  TrackingParams tracking;
  // Per kind of skipped frame (no depth, no pose, lost tracking): this many frames are named in
  // a warning each; beyond, one warning at the end gives the count.
  int max_skip_warnings = 5;

  // A dataset pose translated further than this from the origin is not trusted (skipped and
  // counted, as are non-rigid ones and, always, ones whose view leaves the block index range).
  double max_pose_translation_m = 1e4;

  Status Validate() const {
    if (prefetch > kMaxPrefetch)
      return InvalidArgument("prefetch must be at most " + std::to_string(kMaxPrefetch) +
                             " frames, got " + std::to_string(prefetch));
    return integrate.Validate();
  }
};

struct FusedFrame {
  size_t index = 0;  // in the dataset
  double timestamp_s = 0.0;
  Pose3f T_W_C = Pose3f::Identity();  // the pose it was integrated at
  std::string depth_path, color_path;
};

struct FuseReport {
  std::vector<FusedFrame> frames;  // the integrated frames, in order
  size_t frames_selected = 0;
  size_t skipped_no_pose = 0, skipped_no_depth = 0;
  size_t skipped_bad_pose = 0;  // a pose not to trust (frame_checks.h PoseProblem, or the reader's)
  size_t skipped_pose_gap = 0;  // in a gap of timestamped ground truth, not interpolated
  // The median valid depth of the first frames and, when it is out of range, the likely depth
  // scale (0: none); see frame_checks.h DepthScaleCheck.
  double first_frames_median_depth_m = 0.0, suggested_depth_scale = 0.0;
  size_t frames_lost = 0;  // tracking only: lost, not integrated
  // Past the memory budget: new blocks not allocated, and the frames that had some.
  size_t blocks_refused = 0, frames_over_budget = 0;
  // Per integrated frame: decoding, integration, their sum; per tracked frame: tracking.
  std::vector<double> load_ms, integrate_ms, frame_ms, track_ms;
  // Per integrated frame, within integrate_ms: finding the band's blocks (a split map's ranks
  // walk all of it, or each its share and then exchange what they found) and updating them
  // (split between ranks).
  std::vector<double> collect_ms, exchange_ms, update_ms;
  double loop_s = 0.0;  // the whole loop, skipped frames included
};

struct FuseObserver {
  std::function<void(size_t done, size_t total)> progress;  // after every selected frame
  std::function<void(const std::string& message)> warning;
  // After each integrated frame, outside the integration timing (e.g. an incremental mesher);
  // a failure stops the run with that status.
  std::function<Status(const Frame& frame, const Pose3f& T_W_C, TsdfVolume& volume)> integrated;
  // Polled before every selected frame: true ends the run there with a kCancelled status (the
  // frame in progress is finished first). The CLI sets it from SIGINT / SIGTERM.
  std::function<bool()> stop_requested;
};

// A run split over ranks (distributed/sharded_fuse.h): frames travel from the rank that reads
// the dataset to the others, and all ranks move from frame to frame together. Each hook is
// called on the fusing thread, in frame order.
struct FrameRelay {
  // The reading rank: each selected frame as loaded, or the status that ends the run there
  // (a stop request), before it is fused.
  std::function<Status(const Result<Frame>& frame)> send;
  // The other ranks: replaces loading (the dataset is not read there).
  std::function<Result<Frame>()> receive;
  // After each selected frame: every rank's status of that frame in, the first failure (or ok)
  // out, the same on every rank.
  std::function<Status(const Status& local)> agree;
  // After `done` selected frames, agreed: the report so far (counts up to date), e.g. to write
  // a checkpoint every few frames.
  std::function<Status(size_t done, const FuseReport& so_far)> frame_done;
};

// Fuses dataset frames `indices` (in that order) into `volume`. Fails, naming the frame and its
// file, when a frame cannot be loaded, integrated or tracked; invalid params (Validate(), the
// volume's too) and a camera outside core/bounds.h's intrinsics ranges are refused before any
// frame is read. Past the volume's memory budget: see OnMemoryLimit (one warning when dropping). An
// empty report (no frame integrated) is not a failure: the caller decides.
Result<FuseReport> FuseDataset(const Dataset& dataset, const std::vector<size_t>& indices,
                               const FuseParams& params, TsdfVolume& volume,
                               const FuseObserver& observer = {},
                               const FrameRelay* relay = nullptr);

}  // namespace voxplan
