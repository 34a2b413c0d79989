#include "core/bounds.h"

#include <cmath>
#include <cstdio>

namespace voxplan::bounds {

namespace {

// Shortest round-trip-ish text for messages: 0.001, 1e-09, 16384.
std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

}  // namespace

std::string RangeText(double lo, double hi, const std::string& unit) {
  // Appended piece by piece: GCC 12 warns (-Wrestrict, falsely) on "[" + std::string.
  std::string text = "[";
  text += Number(lo);
  text += ", ";
  text += Number(hi);
  text += "]";
  if (!unit.empty()) text += " " + unit;
  return text;
}

Status CheckRange(const std::string& name, double value, double lo, double hi,
                  const std::string& unit) {
  if (value >= lo && value <= hi) return Status::Ok();  // false for NaN
  return InvalidArgument(name + " must be in " + RangeText(lo, hi, unit) + ", got " +
                         Number(value));
}

Status CheckImageSize(const std::string& name, int64_t width, int64_t height) {
  if (width < 1 || height < 1 || width > kImageSideMax || height > kImageSideMax)
    return InvalidArgument(name + ": width and height must be in [1, " +
                           std::to_string(kImageSideMax) + "], got " + std::to_string(width) + "x" +
                           std::to_string(height));
  if (width * height > kImagePixelsMax)
    return InvalidArgument(name + ": at most " + std::to_string(kImagePixelsMax) + " pixels, got " +
                           std::to_string(width) + "x" + std::to_string(height));
  return Status::Ok();
}

Status CheckIntrinsics(const PinholeCamera& c) {
  VOXPLAN_RETURN_IF_ERROR(CheckImageSize("camera image size", c.width, c.height));
  const double w = c.width, h = c.height;
  VOXPLAN_RETURN_IF_ERROR(CheckRange("camera |fx| (image width " + Number(w) + ")", std::abs(c.fx),
                                     kFocalMinPerSide * w, kFocalMaxPerSide * w, "pixels"));
  VOXPLAN_RETURN_IF_ERROR(CheckRange("camera |fy| (image height " + Number(h) + ")", std::abs(c.fy),
                                     kFocalMinPerSide * h, kFocalMaxPerSide * h, "pixels"));
  VOXPLAN_RETURN_IF_ERROR(CheckRange("camera cx", c.cx, 0.0, w, "pixels"));
  return CheckRange("camera cy", c.cy, 0.0, h, "pixels");
}

}  // namespace voxplan::bounds
