#pragma once
// Line plots as standalone SVG text (time series of exploration runs, benchmark curves): axes
// with round tick values, one polyline per series in the robot palette, a legend. Same input,
// same bytes: numbers are printed with a fixed precision.
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace voxplan {

struct PlotSeries {
  std::string name;
  std::vector<double> x, y;  // same length; non-finite points break the line
};

struct PlotParams {
  std::string title;
  std::string x_label, y_label;
  int width_px = 720, height_px = 420;
  // Fixed y range when y_min < y_max (e.g. 0..1 for coverage); else from the data.
  double y_min = 0.0, y_max = 0.0;
};

// Refuses series whose x and y lengths differ and plots with no finite point at all.
Result<std::string> SvgLinePlot(const std::vector<PlotSeries>& series, const PlotParams& params);

// A timeline (Guo 2022 Fig. 9): one row per robot, coloured spans of what it was doing.
struct TimelineSpan {
  double t0_s = 0.0, t1_s = 0.0;
  int category = 0;  // index into TimelineParams::categories
};
struct TimelineRow {
  std::string name;
  std::vector<TimelineSpan> spans;
};
struct TimelineCategory {
  std::string name;
  uint32_t rgbx = 0;  // PackRgb (core/image.h)
};
struct TimelineParams {
  std::string title;
  std::string x_label = "time (s)";
  std::vector<TimelineCategory> categories;
  int width_px = 720, row_px = 26;
};

// Refuses a span with a category out of range or non-finite or reversed times, and a timeline
// with no span at all.
Result<std::string> SvgTimeline(const std::vector<TimelineRow>& rows, const TimelineParams& params);

// "Nice" tick values covering [lo, hi] with about `count` steps of 1, 2 or 5 times a power of
// ten (exposed for tests).
std::vector<double> NiceTicks(double lo, double hi, int count);

}  // namespace voxplan
