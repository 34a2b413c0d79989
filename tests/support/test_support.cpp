#include "tests/support/test_support.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>

namespace voxplan::test {

namespace fs = std::filesystem;

fs::path SharedDataDir() {
  if (const char* env = std::getenv("VOXPLAN_SHARED_DATA")) return env;
  return fs::path(VOXPLAN_SHARED_DATA_DIR);
}

TempDir::TempDir(const std::string& tag) {
  static std::atomic<int> counter{0};
  path_ = fs::temp_directory_path() /
          (tag + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  fs::remove_all(path_);
  fs::create_directories(path_);
}
TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

PinholeCamera TestCamera(int width, int height) {
  PinholeCamera cam;
  cam.width = width;
  cam.height = height;
  cam.fx = cam.fy = 0.8f * float(width);
  cam.cx = 0.5f * float(width) - 0.5f;
  cam.cy = 0.5f * float(height) - 0.5f;
  return cam;
}

float Box::Sdf(const Eigen::Vector3f& p) const {
  const Eigen::Vector3f c = 0.5f * (lo + hi), h = 0.5f * (hi - lo);
  const Eigen::Vector3f q = (p - c).cwiseAbs() - h;
  return q.cwiseMax(0.f).norm() + std::min(q.maxCoeff(), 0.f);
}

namespace {

// Ray distance t along unit direction dir from o to the first hit, or +inf.
float HitPlane(const Plane& s, const Eigen::Vector3f& o, const Eigen::Vector3f& dir) {
  const float denom = s.n.dot(dir);
  if (std::abs(denom) < 1e-9f) return std::numeric_limits<float>::infinity();
  const float t = (s.d - s.n.dot(o)) / denom;
  return t > 0 ? t : std::numeric_limits<float>::infinity();
}
float HitSphere(const Sphere& s, const Eigen::Vector3f& o, const Eigen::Vector3f& dir) {
  const Eigen::Vector3f oc = o - s.c;
  const float b = oc.dot(dir), c = oc.squaredNorm() - s.r * s.r;
  const float disc = b * b - c;
  if (disc < 0) return std::numeric_limits<float>::infinity();
  const float t = -b - std::sqrt(disc);
  return t > 0 ? t : std::numeric_limits<float>::infinity();
}
float HitBox(const Box& s, const Eigen::Vector3f& o, const Eigen::Vector3f& dir) {
  float t0 = 0.f, t1 = std::numeric_limits<float>::infinity();
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.f / dir[a];
    float ta = (s.lo[a] - o[a]) * inv, tb = (s.hi[a] - o[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return (t0 <= t1 && t0 > 0) ? t0 : std::numeric_limits<float>::infinity();
}

template <typename HitFn>
DepthImage Render(const PinholeCamera& cam, const Pose3f& T_W_C, HitFn hit) {
  DepthImage depth(cam.width, cam.height, 0.f);
  const Eigen::Vector3f o = T_W_C.translation();
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3f ray_C = cam.Unproject(float(u), float(v), 1.f);
      const Eigen::Vector3f dir = (T_W_C.linear() * ray_C).normalized();
      const float t = hit(o, dir);
      if (std::isfinite(t)) depth.at(u, v) = t / ray_C.norm();  // z = t * cos(angle)
    }
  return depth;
}

}  // namespace

DepthImage RenderDepth(const Plane& s, const PinholeCamera& cam, const Pose3f& T_W_C) {
  return Render(cam, T_W_C, [&](auto& o, auto& d) { return HitPlane(s, o, d); });
}
DepthImage RenderDepth(const Sphere& s, const PinholeCamera& cam, const Pose3f& T_W_C) {
  return Render(cam, T_W_C, [&](auto& o, auto& d) { return HitSphere(s, o, d); });
}
DepthImage RenderDepth(const Box& s, const PinholeCamera& cam, const Pose3f& T_W_C) {
  return Render(cam, T_W_C, [&](auto& o, auto& d) { return HitBox(s, o, d); });
}

TsdfVolume FillExactSdf(const std::function<float(const Eigen::Vector3f&)>& sdf,
                        const VolumeParams& params, const Eigen::Vector3f& lo,
                        const Eigen::Vector3f& hi, bool all_blocks) {
  TsdfVolume volume(params);
  const float voxel = params.voxel_size_m, trunc = params.trunc_m, block = voxel * kBlockSide;
  const BlockIndex b0 = BlockAt(lo, block), b1 = BlockAt(hi, block);
  for (int z = b0.z; z <= b1.z; ++z)
    for (int y = b0.y; y <= b1.y; ++y)
      for (int x = b0.x; x <= b1.x; ++x) {
        const BlockIndex b{x, y, z};
        const Eigen::Vector3f centre = BlockOrigin(b, block) + Eigen::Vector3f::Constant(block / 2);
        if (!all_blocks && std::abs(sdf(centre)) > block + trunc) continue;
        TsdfBlock& data = volume.FindOrAllocate(b);
        for (int i = 0; i < kBlockVoxels; ++i) {
          data.tsdf[i] = EncodeTsdf(sdf(VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), voxel)) / trunc);
          data.weight[i] = EncodeWeight(1.0f);
          data.r[i] = kExactRgb[0], data.g[i] = kExactRgb[1], data.b[i] = kExactRgb[2];
        }
      }
  return volume;
}

void ExpectSameImages(const RaycastImages& a, const RaycastImages& b) {
  auto same = [](const auto& x, const auto& y) {
    return x.data.size() == y.data.size() &&
           std::memcmp(x.data.data(), y.data.data(), x.data.size() * sizeof(x.data[0])) == 0;
  };
  EXPECT_TRUE(same(a.status, b.status)) << "status";
  EXPECT_TRUE(same(a.depth, b.depth)) << "depth";
  EXPECT_TRUE(same(a.vertex_W, b.vertex_W)) << "vertex_W";
  EXPECT_TRUE(same(a.normal_W, b.normal_W)) << "normal_W";
  EXPECT_TRUE(same(a.color, b.color)) << "color";
}

size_t EdgesNotClosed(const Mesh& mesh) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) directed[{t[k], t[(k + 1) % 3]}]++;
  size_t bad = 0;
  for (const auto& [e, n] : directed) {
    const auto it = directed.find({e.second, e.first});
    bad += (n != 1 || it == directed.end() || it->second != 1);
  }
  return bad;
}

}  // namespace voxplan::test
