#include "eval/eval_run.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include "io/file_util.h"

namespace voxplan {

namespace {

constexpr std::string_view kHeader = "t,robot,x,y,yaw,cam_yaw,cam_pitch,status,mode";
constexpr size_t kFields = 9;

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> SplitCommas(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    fields.push_back(Trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

bool ParseDouble(std::string_view token, double* value) {
  // from_chars takes no leading '+'; accept it as strtod would.
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), *value);
  return ec == std::errc() && end == token.data() + token.size() && std::isfinite(*value);
}

// Shortest form that reads back as the same double.
std::string FormatDouble(double value) {
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return ec == std::errc() ? std::string(buffer, end) : std::string("nan");
}

bool ValidRobotName(const std::string& name) {
  return !name.empty() && name.find_first_of(", \t\r\n") == std::string::npos;
}

bool ValidMode(const std::string& mode) {
  return mode.find_first_of(",\r\n") == std::string::npos && Trim(mode) == mode;
}

bool SampleFinite(const RobotSample& s) {
  return std::isfinite(s.t_s) && std::isfinite(s.x_m) && std::isfinite(s.y_m) &&
         std::isfinite(s.yaw_rad) && std::isfinite(s.cam_yaw_rad) && std::isfinite(s.cam_pitch_rad);
}

// Every track named, non-empty, finite and strictly increasing in time; names unique.
Status CheckTracks(const std::vector<RobotTrack>& tracks, const std::string& who) {
  if (tracks.empty()) return InvalidArgument(who + ": no robot tracks");
  for (size_t r = 0; r < tracks.size(); ++r) {
    const RobotTrack& track = tracks[r];
    if (!ValidRobotName(track.robot))
      return InvalidArgument(who + ": robot name '" + track.robot +
                             "' is empty or holds a comma or white space");
    for (size_t q = 0; q < r; ++q) {
      if (tracks[q].robot == track.robot)
        return InvalidArgument(who + ": robot '" + track.robot + "' has two tracks");
    }
    if (track.samples.empty())
      return InvalidArgument(who + ": robot '" + track.robot + "' has no samples");
    for (size_t i = 0; i < track.samples.size(); ++i) {
      const RobotSample& s = track.samples[i];
      const std::string where =
          who + ": robot '" + track.robot + "' sample " + std::to_string(i) + ": ";
      if (!SampleFinite(s)) return InvalidArgument(where + "non-finite value");
      if (i > 0 && !(s.t_s > track.samples[i - 1].t_s))
        return InvalidArgument(where + "time " + FormatDouble(s.t_s) + " s is not after " +
                               FormatDouble(track.samples[i - 1].t_s) + " s");
    }
  }
  return Status::Ok();
}

double StepLength(const RobotSample& a, const RobotSample& b) {
  return std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
}

}  // namespace

Result<std::vector<RobotTrack>> ReadRunLog(const std::string& path) {
  Result<std::string> text = ReadFileToString(path);
  if (!text.ok()) return text.status();
  std::vector<RobotTrack> tracks;
  std::unordered_map<std::string, size_t> track_of;
  std::vector<int> last_line;  // per track, line of its latest sample
  bool header_seen = false;
  std::istringstream lines(*text);
  std::string line;
  for (int line_number = 1; std::getline(lines, line); ++line_number) {
    std::string_view view = Trim(line);
    // A UTF-8 byte order mark from spreadsheet programs.
    if (line_number == 1 && view.substr(0, 3) == "\xEF\xBB\xBF") view = Trim(view.substr(3));
    if (view.empty() || view.front() == '#') continue;
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    if (!header_seen) {
      if (view != kHeader)
        return CorruptData(where + "expected the header '" + std::string(kHeader) + "'");
      header_seen = true;
      continue;
    }
    const std::vector<std::string_view> fields = SplitCommas(view);
    if (fields.size() != kFields)
      return CorruptData(where + "expected " + std::to_string(kFields) +
                         " comma-separated fields '" + std::string(kHeader) + "', got " +
                         std::to_string(fields.size()));
    RobotSample sample;
    double* numbers[] = {&sample.t_s,     &sample.x_m,         &sample.y_m,
                         &sample.yaw_rad, &sample.cam_yaw_rad, &sample.cam_pitch_rad};
    const size_t columns[] = {0, 2, 3, 4, 5, 6};
    for (size_t k = 0; k < 6; ++k) {
      const std::string_view token = fields[columns[k]];
      if (!ParseDouble(token, numbers[k]))
        return CorruptData(where + "column '" + std::string(SplitCommas(kHeader)[columns[k]]) +
                           "': not a finite number: '" + std::string(token) + "'");
    }
    const std::string robot(fields[1]);
    if (!ValidRobotName(robot))
      return CorruptData(where + "robot name '" + robot + "' is empty or holds white space");
    if (fields[7] == "busy") {
      sample.status = RobotStatus::kBusy;
    } else if (fields[7] == "idle") {
      sample.status = RobotStatus::kIdle;
    } else {
      return CorruptData(where + "status must be 'busy' or 'idle', got '" + std::string(fields[7]) +
                         "'");
    }
    sample.mode = std::string(fields[8]);
    auto [it, added] = track_of.emplace(robot, tracks.size());
    if (added) {
      tracks.push_back(RobotTrack{robot, {}});
      last_line.push_back(0);
    }
    RobotTrack& track = tracks[it->second];
    if (!track.samples.empty() && !(sample.t_s > track.samples.back().t_s))
      return CorruptData(where + "time " + std::string(fields[0]) + " of robot '" + robot +
                         "' is not after its sample at line " +
                         std::to_string(last_line[it->second]));
    last_line[it->second] = line_number;
    track.samples.push_back(std::move(sample));
  }
  if (!header_seen) return CorruptData(path + ": empty run log (no header)");
  if (tracks.empty()) return CorruptData(path + ": run log has no samples");
  return tracks;
}

Status WriteRunLog(const std::vector<RobotTrack>& tracks, const std::string& path) {
  VOXPLAN_RETURN_IF_ERROR(CheckTracks(tracks, "WriteRunLog " + path));
  struct Row {
    double t;
    size_t track, sample;
  };
  std::vector<Row> rows;
  for (size_t r = 0; r < tracks.size(); ++r) {
    for (size_t i = 0; i < tracks[r].samples.size(); ++i) {
      const RobotSample& s = tracks[r].samples[i];
      if (!ValidMode(s.mode))
        return InvalidArgument("WriteRunLog " + path + ": robot '" + tracks[r].robot + "' mode '" +
                               s.mode + "' holds a comma, a line break or surrounding white space");
      rows.push_back({s.t_s, r, i});
    }
  }
  std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    return a.t < b.t || (a.t == b.t && a.track < b.track);
  });
  std::string text = "# voxplan run log: status and mode hold until the robot's next sample\n";
  text += kHeader;
  text += '\n';
  for (const Row& row : rows) {
    const RobotSample& s = tracks[row.track].samples[row.sample];
    text += FormatDouble(s.t_s) + ',' + tracks[row.track].robot + ',' + FormatDouble(s.x_m) + ',' +
            FormatDouble(s.y_m) + ',' + FormatDouble(s.yaw_rad) + ',' +
            FormatDouble(s.cam_yaw_rad) + ',' + FormatDouble(s.cam_pitch_rad) + ',' +
            (s.status == RobotStatus::kBusy ? "busy" : "idle") + ',' + s.mode + '\n';
  }
  return WriteFileAtomically(path, text);
}

Result<RunMetrics> EvaluateRun(const std::vector<RobotTrack>& tracks, const RunEvalParams& params) {
  VOXPLAN_RETURN_IF_ERROR(CheckTracks(tracks, "EvaluateRun"));
  if (!(params.scene_area_m2 >= 0.0) || !std::isfinite(params.scene_area_m2))
    return InvalidArgument("EvaluateRun: scene_area_m2 must be non-negative");
  RunMetrics run;
  run.start_s = tracks.front().samples.front().t_s;
  run.end_s = tracks.front().samples.back().t_s;
  for (const RobotTrack& track : tracks) {
    run.start_s = std::min(run.start_s, track.samples.front().t_s);
    run.end_s = std::max(run.end_s, track.samples.back().t_s);
  }
  run.time_s = run.end_s - run.start_s;

  for (const RobotTrack& track : tracks) {
    RobotRunMetrics robot;
    robot.robot = track.robot;
    robot.samples = track.samples.size();
    robot.start_s = track.samples.front().t_s;
    robot.end_s = track.samples.back().t_s;
    for (size_t i = 0; i + 1 < track.samples.size(); ++i) {
      const RobotSample& a = track.samples[i];
      const RobotSample& b = track.samples[i + 1];
      const double step_m = StepLength(a, b), dt_s = b.t_s - a.t_s;
      robot.distance_m += step_m;
      if (a.status == RobotStatus::kBusy) robot.busy_time_s += dt_s;
      if (!a.mode.empty()) {
        robot.mode_time_s[a.mode] += dt_s;
        robot.mode_distance_m[a.mode] += step_m;
        if (!b.mode.empty() && b.mode != a.mode) ++robot.mode_switches;
      }
    }
    for (const auto& [mode, t] : robot.mode_time_s) run.mode_time_s[mode] += t;
    for (const auto& [mode, d] : robot.mode_distance_m) run.mode_distance_m[mode] += d;
    run.mode_switches += robot.mode_switches;
    robot.idle_time_s = run.time_s - robot.busy_time_s;
    robot.idle_fraction = run.time_s > 0.0 ? robot.idle_time_s / run.time_s : 0.0;
    run.distance_total_m += robot.distance_m;
    run.idle_time_total_s += robot.idle_time_s;
    run.robots.push_back(std::move(robot));
  }

  const double n = double(run.robots.size());
  run.distance_mean_m = run.distance_total_m / n;
  double variance = 0.0;
  for (const RobotRunMetrics& robot : run.robots) {
    const double d = robot.distance_m - run.distance_mean_m;
    variance += d * d / n;
  }
  if (run.distance_mean_m > 0.0) run.load_balance_cov = std::sqrt(variance) / run.distance_mean_m;
  if (params.scene_area_m2 > 0.0)
    run.distance_per_area = run.distance_total_m / params.scene_area_m2;
  if (run.time_s > 0.0) run.time_load_balance = run.idle_time_total_s / (n * run.time_s);
  return run;
}

double DistanceUpTo(const std::vector<RobotTrack>& tracks, double t_s) {
  double total = 0.0;
  for (const RobotTrack& track : tracks) {
    for (size_t i = 0; i + 1 < track.samples.size(); ++i) {
      const RobotSample& a = track.samples[i];
      const RobotSample& b = track.samples[i + 1];
      if (t_s <= a.t_s) break;
      const double step_m = StepLength(a, b);
      total += t_s >= b.t_s ? step_m : step_m * (t_s - a.t_s) / (b.t_s - a.t_s);
    }
  }
  return total;
}

double FloorArea(const FloorPlan& plan) {
  const size_t floor_cells = size_t(std::count_if(
      plan.cells.begin(), plan.cells.end(), [](PlanCell c) { return c != PlanCell::kOutside; }));
  return double(floor_cells) * double(plan.resolution_m) * double(plan.resolution_m);
}

Result<double> FloorCoverage(const FloorPlan& truth, const ObservedRaster& observed) {
  if (!(observed.resolution_m > 0.0) || !std::isfinite(observed.resolution_m))
    return InvalidArgument("FloorCoverage: observed raster resolution must be positive");
  if (observed.width < 0 || observed.height < 0 ||
      observed.cells.size() != size_t(observed.width) * size_t(observed.height))
    return InvalidArgument(
        "FloorCoverage: observed raster has " + std::to_string(observed.cells.size()) +
        " cells for " + std::to_string(observed.width) + " x " + std::to_string(observed.height));
  if (truth.cells.size() != size_t(truth.width) * size_t(truth.height))
    return InvalidArgument("FloorCoverage: floor plan cells do not match its size");
  size_t free_cells = 0, known = 0;
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      if (truth.at(x, y) != PlanCell::kFree) continue;
      ++free_cells;
      const Eigen::Vector2d centre = truth.CellCenter(x, y).cast<double>();
      const Eigen::Vector2d cell = (centre - observed.origin_W) / observed.resolution_m;
      const double ox = std::floor(cell.x()), oy = std::floor(cell.y());
      if (ox < 0 || oy < 0 || ox >= observed.width || oy >= observed.height) continue;
      known += observed.cells[size_t(oy) * size_t(observed.width) + size_t(ox)] != kUnknownCell;
    }
  }
  if (free_cells == 0) return InvalidArgument("FloorCoverage: the floor plan has no free cell");
  return double(known) / double(free_cells);
}

std::vector<RunTimePoint> RunTimeSeries(const std::vector<RobotTrack>& tracks) {
  std::vector<double> times;
  for (const RobotTrack& track : tracks)
    for (const RobotSample& s : track.samples) times.push_back(s.t_s);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  std::vector<RunTimePoint> series;
  series.reserve(times.size());
  for (double t : times) {
    RunTimePoint point;
    point.t_s = t;
    point.distance_total_m = DistanceUpTo(tracks, t);
    for (const RobotTrack& track : tracks) {
      if (track.samples.empty() || t < track.samples.front().t_s || t > track.samples.back().t_s)
        continue;
      // The latest sample at or before t sets the status.
      const auto after =
          std::upper_bound(track.samples.begin(), track.samples.end(), t,
                           [](double time, const RobotSample& s) { return time < s.t_s; });
      point.busy_robots += std::prev(after)->status == RobotStatus::kBusy;
    }
    series.push_back(point);
  }
  return series;
}

Status WriteRunTimeSeriesCsv(const std::vector<RunTimePoint>& series, const std::string& path) {
  const auto field = [](double v) { return std::isfinite(v) ? FormatDouble(v) : std::string(); };
  std::string text =
      "t,distance_total_m,busy_robots,coverage,completeness,unobserved_m3,mean_uncertainty\n";
  for (const RunTimePoint& p : series) {
    text += field(p.t_s) + ',' + field(p.distance_total_m) + ',' + std::to_string(p.busy_robots) +
            ',' + field(p.coverage) + ',' + field(p.completeness) + ',' + field(p.unobserved_m3) +
            ',' + field(p.mean_uncertainty) + '\n';
  }
  return WriteFileAtomically(path, text);
}

double UnobservedAreaFraction(const std::vector<RunTimePoint>& series, double horizon_s) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const RunTimePoint* last = nullptr;
  double t0 = 0.0, u0 = 0.0, area = 0.0;
  for (const RunTimePoint& p : series) {
    if (!std::isfinite(p.unobserved_m3)) continue;
    if (!last) {
      t0 = p.t_s;
      u0 = p.unobserved_m3;
    } else {
      area += 0.5 * (last->unobserved_m3 + p.unobserved_m3) * (p.t_s - last->t_s);
    }
    last = &p;
  }
  if (!last || !(u0 > 0.0)) return nan;
  const double end_s = std::max(horizon_s, last->t_s);
  if (!(end_s > t0)) return nan;
  area += last->unobserved_m3 * (end_s - last->t_s);
  return area / (u0 * (end_s - t0));
}

}  // namespace voxplan
