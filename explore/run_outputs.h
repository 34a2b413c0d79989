#pragma once
// The artefacts of one exploration experiment (explore/explore_run.h) in its output folder, in
// formats scripts/explore-suite and the tests read back:
//   mesh.ply        the final mesh of the fused map
//   metrics.json    completeness (see completeness_reference), accuracy, distances, balance,
//                   times, plan calls, termination (with planner_fault: the call a planner
//                   crashed or hung in); all but plan_ms_* and the fault's times repeat for a seed;
//                   with a moved floor (--floor-z) scene_floor_z_m, the scene file's z of the
//                   run's z = 0 (the run's world is the file's moved down by it)
//   timeseries.csv  coverage, completeness (every 30 s, volume estimate), distance, unobserved
//                   interior volume and mean surface uncertainty vs time
//   unobserved.svg  the unobserved interior volume over time
//   run_log.csv     every robot's poses and status (eval/eval_run.h format)
//   timeline.svg    per robot: its mode (explorer, reconstructor) or idle over time
//   topdown.png     the final floor map, each robot's path, start / end marks, reached views
//   plan_log.txt    rejected tasks, failed tasks and plans, the plugin's messages
//   plan_calls.csv  one row per plan call with its wall time and the plugin's diagnostics
//   robot.json      the robot and its modes as run (explore/robot_config.h: --robot-config)
//   objects.csv     per object: completeness at 2 and 5 cm, accuracy (Guo 2022 eq. 6, 7)
//   world.ply, world_instances.tsv, world_rooms.tsv (generated worlds), world_floor_plan.png
//   and .yaml: the world as run (sim/world_io.h), written before the loop starts; metrics.json's
//   world_fingerprint is its WorldFingerprintHex
// Every error names the file it could not write. The report as JSON is here too, beside
// metrics.json.
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/status.h"
#include "explore/explore_run.h"
#include "sim/world_io.h"

namespace voxplan {

// mesh.ply, written as soon as the mesh exists (before the evaluation).
Status WriteRunMesh(const Mesh& mesh, const std::string& out_dir);

// metrics.json's object as one line of JSON (keys sorted).
std::string RunMetricsJson(const ExploreRunParams& params, const ExploreRunReport& report);
// The same plus the wall-time breakdown (setup_ms, tour_frames, render_ms, noise_ms, fuse_ms,
// floor_ms, plan_ms_total, series_ms, loop_ms, eval_ms): a run's summary line.
std::string RunSummaryJson(const ExploreRunParams& params, const ExploreRunReport& report);

// Everything but mesh.ply into params.out_dir.
Status WriteRunOutputs(const ExploreRunParams& params, const ExploreRunReport& report);

// The paths of every file above in `out_dir`, for a caller to check against its inputs.
std::vector<std::string> RunOutputFiles(const std::string& out_dir);
// WriteWorld's options for the world files above.
WorldWriteOptions RunWorldFiles();

// Whether `world` is the world of the run that wrote `run_file` (a run_log.csv or mesh.ply in a
// run's folder): OK when it is, or when the folder holds no metrics.json (not an explore run);
// InvalidArgument, naming both fingerprints and the run's world file, when metrics.json's
// world_fingerprint differs; NotFound when metrics.json has none (a run from before it was
// recorded: the caller warns); the error of an unreadable metrics.json otherwise.
Status CheckRunWorld(const std::string& run_file, const World& world);

}  // namespace voxplan
