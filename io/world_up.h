#pragma once
// The world's up axis: what a dataset's convention states or its poses show (DatasetInfo::up),
// recorded in map files (.vpmap version 2) so that views of a map are upright unasked.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

#include "core/status.h"

namespace voxplan {

// One of the six signed world axes, or unknown (a version 1 map, a dataset without a
// convention whose poses do not tell). Consumers take unknown as +z, voxplan's own convention.
enum class WorldUp : uint8_t { kUnknown = 0, kPlusX, kMinusX, kPlusY, kMinusY, kPlusZ, kMinusZ };

// "unknown", "+x", "-x", "+y", "-y", "+z", "-z".
const char* WorldUpName(WorldUp up);
// "x" / "+x" / "-x" ... "z" / "+z" / "-z" (an axis without a sign is the positive one) and
// "unknown"; InvalidArgument naming the text otherwise.
Result<WorldUp> ParseWorldUp(const std::string& text);
// The unit vector of the axis; none for kUnknown.
std::optional<Eigen::Vector3f> WorldUpVector(WorldUp up);
// The unit vector, +z for kUnknown (what a map without the field has always meant).
Eigen::Vector3f WorldUpOrZ(WorldUp up);
// As map files store it: the enum's value, 0..6; anything else is none.
std::optional<WorldUp> WorldUpFromCode(uint32_t code);

// The documented rule for datasets whose world has no stated up (io/README.md): the frames are
// taken to be upright pictures, so each camera's image-up direction, -y of the camera for fy > 0
// and +y for a y-flipped camera (fy < 0, ICL-NUIM's: its images are upright with +y up), is a
// vote for the world's up. The mean of the votes gives the axis nearest to it when the cameras
// agree (the mean is at least kMinAgreement long: held upright, rolled little) and the mean lies
// within kMaxOffAxisDeg of that axis; otherwise the up stays unknown.
class WorldUpEstimator {
 public:
  static constexpr double kMinAgreement = 0.5;
  static constexpr double kMaxOffAxisDeg = 30.0;

  explicit WorldUpEstimator(float fy) : image_up_y_(fy < 0.0f ? 1.0 : -1.0) {}
  // One camera's rotation (camera to world); non-finite ones are ignored.
  void Add(const Eigen::Matrix3d& R_W_C);

  struct Estimate {
    WorldUp up = WorldUp::kUnknown;
    size_t poses = 0;
    double agreement = 0.0;     // length of the mean vote, 0..1
    double off_axis_deg = 0.0;  // angle from the mean vote to the nearest axis
    // "estimated from 400 poses (their mean image up 13 deg from -y)", or why it is unknown.
    std::string Describe() const;
  };
  Estimate Result() const;

 private:
  double image_up_y_;
  Eigen::Vector3d sum_ = Eigen::Vector3d::Zero();
  size_t count_ = 0;
};

}  // namespace voxplan
