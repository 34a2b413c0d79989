#pragma once
// Shared helpers for the suite: analytic scenes with exact depth and SDF, seeded randomness,
// temporary folders and the path of ../shared/data.
#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <string>

#include "core/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "core/pose.h"
#include "core/raycast.h"
#include "core/volume.h"

namespace voxplan::test {

// ../shared/data as seen from the source tree (VOXPLAN_SHARED_DATA overrides it).
std::filesystem::path SharedDataDir();
// A fresh empty folder under the system temp dir, removed when the object dies.
class TempDir {
 public:
  explicit TempDir(const std::string& tag = "voxplan");
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

PinholeCamera TestCamera(int width = 160, int height = 120);

// Analytic scenes: exact signed distance (positive outside the solid / in front of the plane)
// and exact ray depth (z along the optical axis, 0 where the ray misses).
struct Plane {  // n . p = d, normal n pointing towards free space
  Eigen::Vector3f n;
  float d;
  float Sdf(const Eigen::Vector3f& p) const { return n.dot(p) - d; }
};
struct Sphere {
  Eigen::Vector3f c;
  float r;
  float Sdf(const Eigen::Vector3f& p) const { return (p - c).norm() - r; }
};
struct Box {  // axis-aligned
  Eigen::Vector3f lo, hi;
  float Sdf(const Eigen::Vector3f& p) const;
};

DepthImage RenderDepth(const Plane& s, const PinholeCamera& cam, const Pose3f& T_W_C);
DepthImage RenderDepth(const Sphere& s, const PinholeCamera& cam, const Pose3f& T_W_C);
DepthImage RenderDepth(const Box& s, const PinholeCamera& cam, const Pose3f& T_W_C);

// A volume holding the exact truncated SDF `sdf` at the voxel centres of every block of
// [lo, hi] near the surface (or all of them with `all_blocks`), weight 1, colour kExactRgb.
inline constexpr uint8_t kExactRgb[3] = {10, 20, 30};
TsdfVolume FillExactSdf(const std::function<float(const Eigen::Vector3f&)>& sdf,
                        const VolumeParams& params, const Eigen::Vector3f& lo,
                        const Eigen::Vector3f& hi, bool all_blocks = false);

using voxplan::LookAt;  // core/pose.h; tests may still write test::LookAt

// Directed edges of a closed, consistently oriented mesh that are not matched by exactly one
// opposite edge (0 for such a mesh).
size_t EdgesNotClosed(const Mesh& mesh);

// Every image of two ray casts is the same, byte for byte (NaNs included); a failure names the
// image.
void ExpectSameImages(const RaycastImages& a, const RaycastImages& b);

}  // namespace voxplan::test
