#include "eval/path_smoothness.h"

#include <cmath>
#include <vector>

namespace voxplan {

namespace {

// The shortest signed angle from a to b, in (−π, π].
double AngleStep(double a, double b) { return std::remainder(b - a, 2.0 * std::numbers::pi); }

// One body's orientation at a sample: pan (about world z) and tilt.
struct Orientation {
  double pan = 0.0, tilt = 0.0;
};

void Finish(PathSmoothness* s) {
  s->mean_abs_angular_accel_radps2 =
      s->time_s > 0.0 ? s->angular_velocity_jumps_radps / s->time_s : 0.0;
  s->turning_per_m = s->distance_m > 0.0 ? s->turning_rad / s->distance_m : 0.0;
  s->sharp_turns_per_10m =
      s->distance_m > 0.0 ? 10.0 * double(s->sharp_turns) / s->distance_m : 0.0;
}

template <typename OrientationOf>
PathSmoothness Measure(const RobotTrack& track, const SmoothnessParams& params,
                       OrientationOf orientation_of) {
  PathSmoothness s;
  const std::vector<RobotSample>& samples = track.samples;
  if (samples.empty()) return s;
  s.time_s = samples.back().t_s - samples.front().t_s;
  double last_pan_rate = 0.0, last_tilt_rate = 0.0;  // at rest before the first sample
  // The sharp-turn window: its travel so far and net pan change.
  double window_m = 0.0, window_pan = 0.0;
  for (size_t i = 0; i + 1 < samples.size(); ++i) {
    const RobotSample& a = samples[i];
    const RobotSample& b = samples[i + 1];
    const Orientation oa = orientation_of(a), ob = orientation_of(b);
    const double dpan = AngleStep(oa.pan, ob.pan), dtilt = ob.tilt - oa.tilt;
    const double step_m = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    const double dt = b.t_s - a.t_s;  // > 0: run logs have strictly increasing times
    const double pan_rate = dpan / dt, tilt_rate = dtilt / dt;
    s.angular_velocity_jumps_radps +=
        std::hypot(pan_rate - last_pan_rate, tilt_rate - last_tilt_rate);
    last_pan_rate = pan_rate;
    last_tilt_rate = tilt_rate;
    s.turning_rad += std::hypot(dpan, dtilt);
    s.distance_m += step_m;
    window_pan += dpan;
    window_m += step_m;
    if (window_m >= params.window_m) {
      if (std::abs(window_pan) > params.sharp_turn_rad) ++s.sharp_turns;
      window_m = 0.0;
      window_pan = 0.0;
    }
  }
  if (std::abs(window_pan) > params.sharp_turn_rad) ++s.sharp_turns;  // the last, short window
  s.angular_velocity_jumps_radps += std::hypot(last_pan_rate, last_tilt_rate);  // comes to rest
  Finish(&s);
  return s;
}

}  // namespace

PathSmoothness BaseSmoothness(const RobotTrack& track, const SmoothnessParams& params) {
  return Measure(track, params, [](const RobotSample& r) { return Orientation{r.yaw_rad, 0.0}; });
}

PathSmoothness CameraSmoothness(const RobotTrack& track, const SmoothnessParams& params) {
  return Measure(track, params, [](const RobotSample& r) {
    return Orientation{r.yaw_rad + r.cam_yaw_rad, r.cam_pitch_rad};
  });
}

PathSmoothness CombineSmoothness(const PathSmoothness& a, const PathSmoothness& b) {
  PathSmoothness s;
  s.time_s = a.time_s + b.time_s;
  s.distance_m = a.distance_m + b.distance_m;
  s.angular_velocity_jumps_radps = a.angular_velocity_jumps_radps + b.angular_velocity_jumps_radps;
  s.turning_rad = a.turning_rad + b.turning_rad;
  s.sharp_turns = a.sharp_turns + b.sharp_turns;
  Finish(&s);
  return s;
}

}  // namespace voxplan
