#include "pipeline/fuse_dataset.h"

#include <algorithm>
#include <memory>
#include <optional>
#include <stdexcept>

#include "core/bounds.h"
#include "core/parallel.h"
#include "core/stopwatch.h"
#include "pipeline/frame_checks.h"

namespace voxplan {

namespace {

bool AllZero(const DepthImage& depth) {
  return std::none_of(depth.data.begin(), depth.data.end(), [](float z) { return z > 0.f; });
}

// The status with the frame's file in front, unless the message already names it (a frame
// without a file, such as a rendered one, is named by its index).
Status Naming(const Status& status, const Frame& frame) {
  return status.Naming(frame.depth_path.empty() ? "frame " + std::to_string(frame.index)
                                                : frame.depth_path);
}

// Names the first few skipped frames of one kind, then counts the rest.
class SkipCounter {
 public:
  SkipCounter(const FuseObserver& observer, int max_named, const char* what_in_all)
      : observer_(observer), max_named_(size_t(std::max(max_named, 0))), what_(what_in_all) {}
  void Skip(const Frame& frame, const std::string& why) {
    if (++count_ <= max_named_ && observer_.warning)
      observer_.warning("frame " + std::to_string(frame.index) + " (" + frame.depth_path + ") " +
                        why);
  }
  void Finish() const {
    if (count_ > max_named_ && observer_.warning)
      observer_.warning(std::to_string(count_) + " frames in all " + what_);
  }
  size_t count() const { return count_; }

 private:
  const FuseObserver& observer_;
  size_t max_named_;
  const char* what_;
  size_t count_ = 0;
};

// The budget as messages give it: "512 MiB".
std::string BudgetText(const TsdfVolume& volume) {
  return std::to_string(volume.params().max_memory_bytes >> 20) + " MiB";
}

// Counts a frame's refused blocks; the first time warns (or fails, with kFail).
Status CountOverBudget(const IntegrateStats& stats, const Frame& frame, const FuseParams& params,
                       const TsdfVolume& volume, const FuseObserver& observer, FuseReport& report) {
  if (stats.blocks_refused == 0) return Status::Ok();
  const std::string where = "frame " + std::to_string(frame.index) + " (" + frame.depth_path + ")";
  if (params.on_memory_limit == OnMemoryLimit::kFail)
    return ResourceExhausted("memory budget of " + BudgetText(volume) + " reached at " + where +
                             ": the map holds " + std::to_string(volume.num_blocks()) +
                             " blocks, " + std::to_string(stats.blocks_refused) +
                             " more were needed");
  if (report.frames_over_budget == 0 && observer.warning)
    observer.warning("memory budget of " + BudgetText(volume) + " reached at " + where +
                     ": no new blocks from here on (surfaces first seen later are left out; "
                     "blocks and frames dropped are counted)");
  report.blocks_refused += stats.blocks_refused;
  ++report.frames_over_budget;
  return Status::Ok();
}

// The skip counters of frames whose dataset pose cannot be used.
struct PoseSkips {
  SkipCounter none, bad, gap;
  void Finish() const {
    none.Finish();
    bad.Finish();
    gap.Finish();
  }
};

// The dataset's pose of a frame when it can be trusted; else the frame is counted as skipped
// for the reason.
std::optional<Pose3f> DatasetPose(const Frame& frame, const FuseParams& params,
                                  const VolumeParams& volume, PoseSkips& skips) {
  if (frame.T_W_C) {
    const std::string why = PoseProblem(*frame.T_W_C, params.max_pose_translation_m, volume,
                                        params.integrate.max_depth_m);
    if (why.empty()) return Pose3f(frame.T_W_C->cast<float>());
    skips.bad.Skip(frame, "has a pose not to trust (" + why + "); skipped");
  } else if (frame.pose_rejected == PoseRejection::kBadValues) {
    skips.bad.Skip(frame, "has a pose not to trust (" + frame.pose_rejected_why + "); skipped");
  } else if (frame.pose_rejected == PoseRejection::kGroundTruthGap) {
    skips.gap.Skip(frame, "has no pose (" + frame.pose_rejected_why + "); skipped");
  } else {
    skips.none.Skip(frame, "has no pose; skipped");
  }
  return std::nullopt;
}

}  // namespace

Result<FuseReport> FuseDataset(const Dataset& dataset, const std::vector<size_t>& indices,
                               const FuseParams& params, TsdfVolume& volume,
                               const FuseObserver& observer, const FrameRelay* relay) {
  const DatasetInfo& info = dataset.info();
  VOXPLAN_RETURN_IF_ERROR(params.Validate());
  VOXPLAN_RETURN_IF_ERROR(volume.params().Validate());
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckIntrinsics(info.camera));
  std::optional<FrameTracker> tracker;
  if (params.track) {
    try {
      tracker.emplace(info.camera, params.tracking);
    } catch (const std::invalid_argument& e) {
      return InvalidArgument(std::string("tracking: ") + e.what());
    }
  }
  bool tracker_started = false;

  FuseReport report;
  report.frames_selected = indices.size();
  SkipCounter no_depth(observer, params.max_skip_warnings, "had no valid depth and were skipped");
  PoseSkips pose_skips{
      {observer, params.max_skip_warnings, "had no pose and were skipped"},
      {observer, params.max_skip_warnings, "had a pose not to trust and were skipped"},
      {observer, params.max_skip_warnings, "lay in gaps of the ground truth and were skipped"}};
  // Float depth is metres: no depth scale to suggest.
  DepthScaleCheck depth_check(info.root, info.depth_metres ? 0.0 : info.depth_scale);
  SkipCounter lost(observer, params.max_skip_warnings, "lost tracking and were not integrated");
  // Selected frame k, loaded (in `load_ms`): skipped, or posed, integrated and recorded.
  const auto fuse_frame = [&](size_t k, Result<Frame>& frame, double load_ms) -> Status {
    const size_t i = indices[k];
    if (!frame.ok()) return frame.status().WithContext("frame " + std::to_string(i));
    if (AllZero(frame->depth)) {
      no_depth.Skip(*frame, "has no valid depth; skipped");
      if (observer.progress) observer.progress(k + 1, indices.size());
      return Status::Ok();
    }
    if (auto w = depth_check.Add(frame->depth, frame->depth_path); w && observer.warning)
      observer.warning(*w);
    std::optional<Pose3f> T_W_C;
    if (tracker && !tracker_started) {
      T_W_C = frame->T_W_C ? Pose3f(frame->T_W_C->cast<float>()) : Pose3f::Identity();
      tracker->Reset(*T_W_C);
      tracker_started = true;
    } else if (tracker) {
      Result<TrackingResult> tracked = tracker->Track(frame->depth, frame->color, volume);
      if (!tracked.ok()) return Naming(tracked.status(), *frame);
      report.track_ms.push_back(tracked->track_ms);
      if (tracked->ok) {
        T_W_C = tracked->T_W_C;
        tracker->Accept(*T_W_C);
      } else {
        lost.Skip(*frame, "lost tracking (" + tracked->failure + "); not integrated");
      }
    } else {
      T_W_C = DatasetPose(*frame, params, volume.params(), pose_skips);
    }
    if (T_W_C) {
      const Stopwatch integrate_clock;
      Result<IntegrateStats> stats =
          IntegrateFrame(frame->depth, frame->color, info.camera, *T_W_C, params.integrate, volume);
      const double integrate_ms = integrate_clock.ElapsedMs();
      if (!stats.ok()) return Naming(stats.status(), *frame);
      VOXPLAN_RETURN_IF_ERROR(CountOverBudget(*stats, *frame, params, volume, observer, report));
      report.load_ms.push_back(load_ms);
      report.integrate_ms.push_back(integrate_ms);
      report.collect_ms.push_back(stats->collect_ms);
      report.exchange_ms.push_back(stats->exchange_ms);
      report.update_ms.push_back(stats->update_ms);
      report.frame_ms.push_back(load_ms + integrate_ms);
      report.frames.push_back(
          {frame->index, frame->timestamp, *T_W_C, frame->depth_path, frame->color_path});
      if (observer.integrated) {
        if (Status s = observer.integrated(*frame, *T_W_C, volume); !s.ok()) return s;
      }
    }
    if (observer.progress) observer.progress(k + 1, indices.size());
    return Status::Ok();
  };

  // Frames are decoded up to params.prefetch ahead on worker tasks while the caller's thread
  // fuses them in order (core/parallel.h ProduceAhead), each loaded frame in slot k % slots.
  // A fused frame stays in its slot until the next frame for the slot is decoded: freed there,
  // on the decoding thread, its images' memory is reused at once for the next ones (freed on
  // the fusing thread, a worker's heap was trimmed and faulted in again: +5 % CPU time).
  struct Loaded {
    std::optional<Result<Frame>> frame;
    double load_ms = 0.0;
  };
  const bool receiving = relay && relay->receive;  // frames come from another rank
  std::vector<Loaded> loaded((receiving ? 0 : params.prefetch) + 1);
  const auto count_skips = [&] {
    report.skipped_no_pose = pose_skips.none.count();
    report.skipped_bad_pose = pose_skips.bad.count();
    report.skipped_pose_gap = pose_skips.gap.count();
    report.first_frames_median_depth_m = depth_check.median_m();
    report.suggested_depth_scale = depth_check.suggested_scale();
    report.skipped_no_depth = no_depth.count();
    report.frames_lost = lost.count();
  };
  Status end = Status::Ok();  // what stopped the run early
  const Stopwatch loop_clock;
  ProduceAhead(
      indices.size(), receiving ? 0 : params.prefetch,
      [&](size_t k) {
        if (receiving) return;
        Loaded& slot = loaded[k % loaded.size()];
        slot.frame.reset();
        const Stopwatch load_clock;
        slot.frame.emplace(dataset.Load(indices[k]));
        slot.load_ms = load_clock.ElapsedMs();
      },
      [&](size_t k) {
        Loaded& slot = loaded[k % loaded.size()];
        if (receiving) {
          const Stopwatch receive_clock;
          slot.frame.emplace(relay->receive());
          slot.load_ms = receive_clock.ElapsedMs();
          if (!slot.frame->ok() && slot.frame->status().code() == StatusCode::kCancelled) {
            end = slot.frame->status();
            return false;
          }
        } else if (observer.stop_requested && observer.stop_requested()) {
          end = Cancelled("stopped before frame " + std::to_string(indices[k]) + " (" +
                          std::to_string(k) + " of " + std::to_string(indices.size()) +
                          " selected frames done)");
          if (relay && relay->send) {
            if (Status s = relay->send(end); !s.ok()) end = s;
          }
          return false;
        } else if (relay && relay->send) {
          if (Status s = relay->send(*slot.frame); !s.ok()) {
            end = s;
            return false;
          }
        }
        end = fuse_frame(k, *slot.frame, slot.load_ms);
        if (relay && relay->agree) end = relay->agree(end);
        if (end.ok() && relay && relay->frame_done) {
          count_skips();
          end = relay->frame_done(k + 1, report);
        }
        return end.ok();
      });
  if (!end.ok()) return end;
  report.loop_s = loop_clock.ElapsedS();
  if (auto w = depth_check.Finish(); w && observer.warning) observer.warning(*w);
  pose_skips.Finish();
  lost.Finish();
  no_depth.Finish();
  count_skips();
  return report;
}

}  // namespace voxplan
