#pragma once
// voxplan fuse: its options, and the parts its sharded run (cmd_fuse_sharded.cpp, under mpirun
// or with checkpoints) shares with the one-process run.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "apps/voxplan/cli_common.h"
#include "distributed/communicator.h"
#include "pipeline/fuse_dataset.h"
#include "planning/octomap_export.h"

namespace voxplan::cli {

struct FuseOptions {
  DatasetInput in;
  double voxel_size_m = 0.01;
  double trunc_m = 0.04;
  int threads = 0;
  std::string intrinsics;
  double depth_scale = 0.0;
  std::string weighting = "constant";
  std::string kernel = "auto";
  double max_weight = 64.0;
  double mesh_min_weight = 0.5;
  std::string mesh_path, map_path, stats_path, frame_list_path, trajectory_path;
  std::string points_path, octomap_path;
  bool track = false;
  double photometric_weight = 0.0;
  MemoryBudgetOptions memory;
  double max_pose_gap_s = 0.1;
  size_t prefetch = FuseParams::kDefaultPrefetch;
  size_t checkpoint_every = 0;      // selected frames between checkpoints of --map (0: none)
  bool resume = false;              // continue the run whose checkpoint --map is
  std::string band_walk = "split";  // under mpirun: split the band walk over the ranks, or "whole"
};

// The stats object: the same on the last stdout line and in --stats.
nlohmann::json FuseStats(const FuseOptions& o, const DatasetInfo& info,
                         const IntegrateParams& params, const FuseReport& report,
                         const TsdfVolume& volume, const Mesh& mesh, double mesh_ms,
                         const std::optional<OctomapExportStats>& octomap);
// The run's fusion and volume parameters, from the options.
FuseParams FuseParamsOf(const FuseOptions& o);
VolumeParams VolumeParamsOf(const FuseOptions& o);
// The dataset options (--intrinsics, --depth-scale, --max-pose-gap) into *options: kExitOk, or
// the usage exit code after printing why.
int DatasetOptionsOf(const FuseOptions& o, DatasetOptions* options);
// No output may be another output or one of the dataset's files; the exit code (printed why).
int RefuseCollisions(const FuseOptions& o, const Dataset& dataset);

// The run split over mpirun's ranks, or checkpointed / resumed (distributed/sharded_fuse.h).
int RunFuseSharded(const FuseOptions& o, Communicator& comm);

}  // namespace voxplan::cli
