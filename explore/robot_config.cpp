#include "explore/robot_config.h"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/bounds.h"
#include "io/file_util.h"

namespace voxplan {

namespace {

using nlohmann::json;

constexpr uint64_t kMaxConfigBytes = 1 << 20;

// Reads the keys of one JSON object into fields, each with its bounds; the first problem wins.
class Reader {
 public:
  Reader(const json& object, std::string where) : object_(object), where_(std::move(where)) {
    if (!object_.is_object()) problem_ = where_ + " must be a JSON object";
  }

  // A number in [lo, hi] (NaN and infinities refused).
  void Number(const char* key, float* field, double lo, double hi) {
    seen_.insert(key);
    if (!problem_.empty() || !object_.contains(key)) return;
    const json& v = object_[key];
    if (!v.is_number()) {
      problem_ = where_ + "." + key + " must be a number";
      return;
    }
    const double x = v.get<double>();
    if (!(x >= lo && x <= hi)) {
      problem_ =
          where_ + "." + key + " must be in [" + Num(lo) + ", " + Num(hi) + "], got " + Num(x);
      return;
    }
    *field = float(x);
  }
  void Mount(const char* key, MountKind* field) {
    seen_.insert(key);
    if (!problem_.empty() || !object_.contains(key)) return;
    const json& v = object_[key];
    if (v == "head") {
      *field = MountKind::kHead;
    } else if (v == "arm") {
      *field = MountKind::kArm;
    } else {
      problem_ = where_ + "." + key + " must be \"head\" or \"arm\"";
    }
  }
  // A nested object, read by `read` (a Reader over it).
  template <class F>
  void Object(const char* key, F&& read) {
    seen_.insert(key);
    if (!problem_.empty() || !object_.contains(key)) return;
    Reader inner(object_[key], where_ + "." + key);
    read(inner);
    inner.Finish();
    if (problem_.empty()) problem_ = inner.problem_;
  }
  // Refuses keys nobody read.
  void Finish() {
    if (!problem_.empty() || !object_.is_object()) return;
    for (const auto& [key, value] : object_.items())
      if (!seen_.count(key)) {
        problem_ = where_ + " has an unknown key \"" + key + "\"";
        return;
      }
  }
  const std::string& problem() const { return problem_; }

 private:
  static std::string Num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  }
  const json& object_;
  std::string where_;
  std::set<std::string> seen_;
  std::string problem_;
};

void ReadArm(Reader& r, ArmParams& a) {
  r.Number("height_min_m", &a.height_min_m, 0.01, 3.0);
  r.Number("height_max_m", &a.height_max_m, 0.01, 3.0);
  r.Number("reach_min_m", &a.reach_min_m, 0.0, 3.0);
  r.Number("reach_max_m", &a.reach_max_m, 0.0, 3.0);
  r.Number("reach_half_angle_deg", &a.reach_half_angle_deg, 0.0, 180.0);
  r.Number("max_abs_pitch_deg", &a.max_abs_pitch_deg, 0.0, 90.0);
  r.Number("speed_mps", &a.speed_mps, 0.001, 10.0);
}

void ReadMode(Reader& r, ModeParams& m) {
  r.Number("max_speed_mps", &m.max_speed_mps, 0.001, 10.0);
  r.Number("max_turn_rate_radps", &m.max_turn_rate_radps, 0.001, 20.0);
  r.Number("horizontal_fov_deg", &m.horizontal_fov_deg, 1.01, 178.99);
  r.Number("min_range_m", &m.min_range_m, 0.01, bounds::kDepthMaxM);
  r.Number("max_range_m", &m.max_range_m, 0.02, bounds::kDepthMaxM);
  r.Number("capture_hz", &m.capture_hz, 0.0, kMaxCaptureHz);
  r.Number("switch_s", &m.switch_s, 0.0, kMaxSwitchS);
  r.Mount("mount", &m.mount);
  r.Object("arm", [&](Reader& inner) { ReadArm(inner, m.arm); });
}

json ModeJson(const ModeParams& m) {
  return {{"max_speed_mps", m.max_speed_mps},
          {"max_turn_rate_radps", m.max_turn_rate_radps},
          {"horizontal_fov_deg", m.horizontal_fov_deg},
          {"min_range_m", m.min_range_m},
          {"max_range_m", m.max_range_m},
          {"capture_hz", m.capture_hz},
          {"switch_s", m.switch_s},
          {"mount", MountKindName(m.mount)},
          {"arm",
           {{"height_min_m", m.arm.height_min_m},
            {"height_max_m", m.arm.height_max_m},
            {"reach_min_m", m.arm.reach_min_m},
            {"reach_max_m", m.arm.reach_max_m},
            {"reach_half_angle_deg", m.arm.reach_half_angle_deg},
            {"max_abs_pitch_deg", m.arm.max_abs_pitch_deg},
            {"speed_mps", m.arm.speed_mps}}}};
}

}  // namespace

RobotParams Guo2022RobotParams() {
  RobotParams p;
  ModeParams& e = p.explorer;
  e.min_range_m = 0.35f;
  e.capture_hz = 2.f;
  e.switch_s = 2.f;
  ModeParams& r = p.reconstructor;
  r.min_range_m = 0.2f;
  r.capture_hz = 2.f;
  r.switch_s = 2.f;
  r.mount = MountKind::kArm;  // ArmParams' defaults are the workspace above
  return p;
}

RobotParams Xu2017RobotParams() {
  RobotParams p;
  ModeParams& e = p.explorer;
  e.max_speed_mps = 0.3f;  // X L304
  e.horizontal_fov_deg = 58.f;
  e.min_range_m = 0.5f;  // a Kinect v1's
  e.max_range_m = 4.f;
  e.capture_hz = 5.f;
  // The camera joints at a_m = 40°/s (X L306, whose second "v_m" is a typo for it).
  p.camera_yaw_rate_radps = p.camera_pitch_rate_radps = 0.6981317f;
  return p;
}

Result<RobotParams> ParseRobotConfig(const std::string& json_text, const RobotParams& base,
                                     const std::string& source) {
  json j;
  try {
    j = json::parse(json_text);
  } catch (const json::exception& e) {
    return InvalidArgument(source + ": not valid JSON: " + e.what());
  }
  RobotParams p = base;
  Reader r(j, "robot");
  r.Number("radius_m", &p.radius_m, 0.01, 2.0);
  r.Number("camera_height_m", &p.camera_height_m, 0.01, 3.0);
  r.Number("camera_yaw_rate_radps", &p.camera_yaw_rate_radps, 0.001, 20.0);
  r.Number("camera_pitch_rate_radps", &p.camera_pitch_rate_radps, 0.001, 20.0);
  r.Number("max_abs_pitch_deg", &p.max_abs_pitch_deg, 0.0, 89.9);
  r.Number("dwell_s", &p.dwell_s, 0.0, 600.0);
  r.Object("explorer", [&](Reader& inner) { ReadMode(inner, p.explorer); });
  r.Object("reconstructor", [&](Reader& inner) { ReadMode(inner, p.reconstructor); });
  r.Finish();
  if (!r.problem().empty()) return InvalidArgument(source + ": " + r.problem());
  if (Status s = p.Validate(); !s.ok()) return InvalidArgument(source + ": " + s.message());
  return p;
}

Result<RobotParams> ReadRobotConfig(const std::string& path, const RobotParams& base) {
  std::error_code ec;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxConfigBytes)
    return InvalidArgument(path + ": a robot config of " + std::to_string(size) +
                           " bytes is over the limit of " + std::to_string(kMaxConfigBytes));
  Result<std::string> text = ReadFileToString(path);
  if (!text.ok()) return text.status();
  return ParseRobotConfig(*text, base, path);
}

std::string RobotConfigJson(const RobotParams& p) {
  const json j = {{"radius_m", p.radius_m},
                  {"camera_height_m", p.camera_height_m},
                  {"camera_yaw_rate_radps", p.camera_yaw_rate_radps},
                  {"camera_pitch_rate_radps", p.camera_pitch_rate_radps},
                  {"max_abs_pitch_deg", p.max_abs_pitch_deg},
                  {"dwell_s", p.dwell_s},
                  {"explorer", ModeJson(p.explorer)},
                  {"reconstructor", ModeJson(p.reconstructor)}};
  return j.dump(2) + "\n";
}

Status ApplyExploreProfile(const std::string& name, ExploreParams* params) {
  if (name == "guo2022") {
    params->robot = Guo2022RobotParams();
    params->recon_voxel_size_m = 0.02f;
    params->recon_weighting = Weighting::kDepthDependent;
    params->detector = DetectorParams{};
    return Status::Ok();
  }
  if (name == "xu2017") {
    params->robot = Xu2017RobotParams();
    params->recon_voxel_size_m = 0.02f;
    params->step_s = 0.1;  // the planner's 0.4 s sub-steps land within a tenth of a second
    return Status::Ok();
  }
  return NotFound("unknown profile '" + name + "' (" + ExploreProfileNames() + ")");
}

const char* ExploreProfileNames() { return "guo2022, xu2017"; }

}  // namespace voxplan
