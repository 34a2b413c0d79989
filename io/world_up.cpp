#include "io/world_up.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace voxplan {

namespace {

struct AxisName {
  WorldUp up;
  const char* name;
  int axis;
  float sign;
};
constexpr AxisName kAxes[] = {{WorldUp::kPlusX, "+x", 0, 1.f}, {WorldUp::kMinusX, "-x", 0, -1.f},
                              {WorldUp::kPlusY, "+y", 1, 1.f}, {WorldUp::kMinusY, "-y", 1, -1.f},
                              {WorldUp::kPlusZ, "+z", 2, 1.f}, {WorldUp::kMinusZ, "-z", 2, -1.f}};

const AxisName* Find(WorldUp up) {
  for (const AxisName& a : kAxes)
    if (a.up == up) return &a;
  return nullptr;
}

}  // namespace

const char* WorldUpName(WorldUp up) {
  const AxisName* a = Find(up);
  return a ? a->name : "unknown";
}

Result<WorldUp> ParseWorldUp(const std::string& text) {
  if (text == "unknown") return WorldUp::kUnknown;
  for (const AxisName& a : kAxes) {
    if (text == a.name || (a.sign > 0.f && text == a.name + 1)) return a.up;
  }
  return InvalidArgument("up axis must be x, y, z, -x, -y, -z (or +x, +y, +z), got '" + text + "'");
}

std::optional<Eigen::Vector3f> WorldUpVector(WorldUp up) {
  const AxisName* a = Find(up);
  if (!a) return std::nullopt;
  Eigen::Vector3f v = Eigen::Vector3f::Zero();
  v[a->axis] = a->sign;
  return v;
}

Eigen::Vector3f WorldUpOrZ(WorldUp up) {
  return WorldUpVector(up).value_or(Eigen::Vector3f::UnitZ());
}

std::optional<WorldUp> WorldUpFromCode(uint32_t code) {
  if (code > uint32_t(WorldUp::kMinusZ)) return std::nullopt;
  return WorldUp(code);
}

void WorldUpEstimator::Add(const Eigen::Matrix3d& R_W_C) {
  const Eigen::Vector3d vote = image_up_y_ * R_W_C.col(1);
  if (!vote.allFinite()) return;
  sum_ += vote;
  ++count_;
}

WorldUpEstimator::Estimate WorldUpEstimator::Result() const {
  Estimate e;
  e.poses = count_;
  if (count_ == 0) return e;
  const Eigen::Vector3d mean = sum_ / double(count_);
  e.agreement = mean.norm();
  if (!(e.agreement > 0.0)) return e;
  int axis = 0;
  mean.cwiseAbs().maxCoeff(&axis);
  const double cosine = std::abs(mean[axis]) / e.agreement;
  e.off_axis_deg = std::acos(std::min(1.0, cosine)) * 180.0 / std::numbers::pi;
  if (e.agreement < kMinAgreement || e.off_axis_deg > kMaxOffAxisDeg) return e;
  for (const AxisName& a : kAxes)
    if (a.axis == axis && (a.sign > 0.f) == (mean[axis] > 0.0)) e.up = a.up;
  return e;
}

std::string WorldUpEstimator::Estimate::Describe() const {
  if (poses == 0) return "unknown: no poses";
  char text[160];
  if (up == WorldUp::kUnknown) {
    std::snprintf(text, sizeof(text),
                  "unknown: the image up of %zu poses agrees %.2f (at least %.2f wanted) and lies "
                  "%.0f deg from the nearest axis (at most %.0f)",
                  poses, agreement, kMinAgreement, off_axis_deg, kMaxOffAxisDeg);
  } else {
    std::snprintf(text, sizeof(text),
                  "estimated from %zu poses (their mean image up %.0f deg from %s)", poses,
                  off_axis_deg, WorldUpName(up));
  }
  return text;
}

}  // namespace voxplan
