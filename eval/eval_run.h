#pragma once
// Metrics of a (multi-)robot exploration run, from per-robot logs:
//   distance (Dong 2019 "total energy"; Guo 2022 D-C) per robot and in total, and total distance
//   per scene area (Dong 2019 normalises it "via dividing by scene area");
//   distance load balance D-LB = coefficient of variation (population standard deviation / mean)
//   of per-robot distance (Dong 2019, Guo 2022);
//   run time T-C, and time load balance T-LB = share of the robots' time spent waiting (Guo 2022);
//   floor coverage: share of ground-truth free floor cells the robots' 2-D map knows.
// And the run-log file `voxplan explore` writes and `voxplan eval run` reads.
//
// Run-log format (CSV, UTF-8, one sample a line):
//   # comment lines and blank lines are ignored anywhere
//   t,robot,x,y,yaw,cam_yaw,cam_pitch,status,mode      <- this header, first non-comment line
//   0.5,r0,1.25,-0.5,1.5707963,0,-0.2,busy,explorer
// t: seconds; robot: a name without commas or spaces; x, y: metres, world frame; yaw: radians,
// the base's heading (counter-clockwise from +x); cam_yaw: radians, the camera's pan relative to
// the base; cam_pitch: radians, camera tilt, positive up; status: `busy` (working on a task:
// moving or scanning) or `idle` (waiting); mode: free text without commas (Guo's "explorer" /
// "reconstructor"), may be empty. A robot's samples have strictly increasing t; robots may
// interleave. A sample's status and mode hold until that robot's next sample.
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "core/status.h"
#include "sim/floor_plan.h"

namespace voxplan {

enum class RobotStatus : uint8_t { kBusy = 0, kIdle = 1 };

struct RobotSample {
  double t_s = 0.0;
  double x_m = 0.0, y_m = 0.0, yaw_rad = 0.0;  // SE(2) base pose, world frame
  double cam_yaw_rad = 0.0;                    // pan relative to the base
  double cam_pitch_rad = 0.0;                  // tilt, positive up
  RobotStatus status = RobotStatus::kBusy;
  std::string mode;
};

struct RobotTrack {
  std::string robot;
  std::vector<RobotSample> samples;  // strictly increasing t_s
};

// Robots in order of first appearance in the file.
Result<std::vector<RobotTrack>> ReadRunLog(const std::string& path);
// Rows ordered by time, ties by track order; numbers in shortest round-trip form, so reading
// the file back gives the same doubles. Refuses names or modes the format cannot hold and
// tracks whose times do not increase.
Status WriteRunLog(const std::vector<RobotTrack>& tracks, const std::string& path);

struct RobotRunMetrics {
  std::string robot;
  size_t samples = 0;
  double distance_m = 0.0;            // planar path length of the base, straight between samples
  double start_s = 0.0, end_s = 0.0;  // first and last sample
  double busy_time_s = 0.0;           // intervals starting at a busy sample
  // Run time not spent busy: logged idle intervals, and the parts of the run before the robot's
  // first sample or after its last one (it was not working then).
  double idle_time_s = 0.0;
  double idle_fraction = 0.0;  // idle_time_s / run time
  // Per non-empty mode: time (within the robot's log span) and distance in that mode.
  std::map<std::string, double> mode_time_s;
  std::map<std::string, double> mode_distance_m;
  // Times the mode changed between two samples that both name one (Guo 2022's switches).
  size_t mode_switches = 0;
};

struct RunMetrics {
  std::vector<RobotRunMetrics> robots;  // in track order
  double start_s = 0.0, end_s = 0.0;
  double time_s = 0.0;            // T-C: last sample of any robot - first sample of any robot
  double distance_total_m = 0.0;  // D-C
  double distance_mean_m = 0.0;
  double distance_per_area = 0.0;  // m per m^2 of scene area; 0 when no area was given
  double load_balance_cov = 0.0;   // D-LB; 0 for one robot or when nobody moved
  double idle_time_total_s = 0.0;
  double time_load_balance = 0.0;  // T-LB: idle_time_total_s / (robots * time_s)
  // Summed over the robots: per mode, and the switches.
  std::map<std::string, double> mode_time_s;
  std::map<std::string, double> mode_distance_m;
  size_t mode_switches = 0;
};

struct RunEvalParams {
  double scene_area_m2 = 0.0;  // floor area for distance_per_area; 0: not computed
};

// Refuses no tracks, an empty track, unordered or non-finite samples, and a negative area.
Result<RunMetrics> EvaluateRun(const std::vector<RobotTrack>& tracks,
                               const RunEvalParams& params = {});

// Total distance travelled by all robots up to time t_s, a robot moving straight and at constant
// speed between its samples.
double DistanceUpTo(const std::vector<RobotTrack>& tracks, double t_s);

// Floor area of a scene: cells with floor below (free or obstacle), times the cell area.
double FloorArea(const FloorPlan& plan);

// A 2-D map of what the robots know, as the explorer keeps it: cells row-major in y rows,
// kUnknownCell where nothing was observed, any other value known (free or obstacle).
inline constexpr uint8_t kUnknownCell = 0;
struct ObservedRaster {
  Eigen::Vector2d origin_W = Eigen::Vector2d::Zero();  // world x, y of cell (0, 0)'s corner
  double resolution_m = 0.05;
  int width = 0, height = 0;
  std::vector<uint8_t> cells;
};

// Share of the plan's free cells whose centre lies in a known cell of `observed` (centres
// outside `observed` are unknown); resolutions and origins may differ. Refuses a plan without
// free cells and a raster whose size does not match its cells.
Result<double> FloorCoverage(const FloorPlan& truth, const ObservedRaster& observed);

// One row of a run's time series; NaN where a value was not measured (written as an empty field).
struct RunTimePoint {
  double t_s = 0.0;
  double distance_total_m = 0.0;
  int busy_robots = 0;
  double coverage = std::numeric_limits<double>::quiet_NaN();      // 0..1, FloorCoverage
  double completeness = std::numeric_limits<double>::quiet_NaN();  // 0..1, EvaluateMesh
  // The scene's interior not yet observed in the planning map, m³ (the explorer's definition:
  // explore/explore.h), and the mean uncertainty of its surface voxels, 0..1 (NaN: none yet).
  double unobserved_m3 = std::numeric_limits<double>::quiet_NaN();
  double mean_uncertainty = std::numeric_limits<double>::quiet_NaN();
};

// Distance and busy robots at every distinct sample time of the log (coverage and completeness
// NaN: the explorer fills them in from its maps).
std::vector<RunTimePoint> RunTimeSeries(const std::vector<RobotTrack>& tracks);

// CSV with header `t,distance_total_m,busy_robots,coverage,completeness,unobserved_m3,
// mean_uncertainty` (the last two since the unobserved-volume curve; a reader takes columns by
// name, so files without them still read).
Status WriteRunTimeSeriesCsv(const std::vector<RunTimePoint>& series, const std::string& path);

// The area under the unobserved-volume curve as a share of never observing anything more: the
// integral of unobserved_m3 from the first point with a value to horizon_s (linear between
// points, held at the last value after it: a run that ended early observes nothing more) over
// that first value times the span. 0 would be everything observed at once, 1 nothing after the
// start; a fixed horizon (the run's time limit) makes runs that end at different times
// comparable. NaN without a positive first value or a span.
double UnobservedAreaFraction(const std::vector<RunTimePoint>& series, double horizon_s);

}  // namespace voxplan
