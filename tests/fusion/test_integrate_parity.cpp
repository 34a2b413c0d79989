// Parity: scalar vs SIMD kernels, 1 vs 2 threads, and the 16-bit voxel encoding vs a float
// reference integrator.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>

#include "core/parallel.h"
#include "fusion/integrate.h"
#include "fusion/integrate_kernel.h"
#include "fusion/mesh_extract.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

struct Sequence {
  PinholeCamera cam = test::TestCamera(160, 120);
  std::vector<DepthImage> depth;
  std::vector<ColorImage> color;
  std::vector<Pose3f> poses;
};

// A sphere on a floor seen from a ring of poses, with a colour gradient and some invalid pixels.
Sequence MakeSequence() {
  Sequence seq;
  const test::Sphere sphere{Eigen::Vector3f(0, 0, 0.35f), 0.35f};
  const test::Plane floor{Eigen::Vector3f(0, 0, 1), 0.0f};
  for (int k = 0; k < 5; ++k) {
    const float a = 0.4f + float(k) * 0.5f;
    const Pose3f T_W_C = LookAt(Eigen::Vector3f(1.4f * std::cos(a), 1.4f * std::sin(a), 0.9f),
                                Eigen::Vector3f(0, 0, 0.3f));
    DepthImage ds = test::RenderDepth(sphere, seq.cam, T_W_C);
    const DepthImage df = test::RenderDepth(floor, seq.cam, T_W_C);
    ColorImage col(seq.cam.width, seq.cam.height);
    for (int v = 0; v < seq.cam.height; ++v)
      for (int u = 0; u < seq.cam.width; ++u) {
        float& d = ds.at(u, v);
        const float f = df.at(u, v);
        if (d == 0.f || (f > 0.f && f < d)) d = f;
        if ((u * 7 + v * 13 + k) % 29 == 0) d = 0.f;  // dropouts
        col.at(u, v) = PackRgb(uint8_t(u + 40 * k), uint8_t(v * 2), uint8_t(255 - u));
      }
    seq.depth.push_back(ds);
    seq.color.push_back(col);
    seq.poses.push_back(T_W_C);
  }
  return seq;
}

TsdfVolume Fuse(const Sequence& seq, const IntegrateParams& params, float voxel = 0.02f) {
  TsdfVolume volume({voxel, 4 * voxel});
  for (size_t i = 0; i < seq.poses.size(); ++i) {
    auto stats = IntegrateFrame(seq.depth[i], seq.color[i], seq.cam, seq.poses[i], params, volume);
    EXPECT_TRUE(stats.ok());
  }
  return volume;
}

void ExpectIdentical(const TsdfVolume& a, const TsdfVolume& b) {
  const auto ia = a.SortedBlockIndices(), ib = b.SortedBlockIndices();
  ASSERT_EQ(ia, ib);
  size_t differing = 0;
  for (const BlockIndex& idx : ia)
    differing += std::memcmp(a.FindBlock(idx), b.FindBlock(idx), sizeof(TsdfBlock)) != 0;
  EXPECT_EQ(differing, 0u) << "of " << ia.size() << " blocks";
}

std::string MeshBytes(const Mesh& m) {
  std::string out;
  auto append = [&](const void* p, size_t n) { out.append(static_cast<const char*>(p), n); };
  append(m.positions.data(), m.positions.size() * sizeof(m.positions[0]));
  append(m.normals.data(), m.normals.size() * sizeof(m.normals[0]));
  append(m.colors.data(), m.colors.size() * sizeof(m.colors[0]));
  append(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
  return out;
}

TEST(Parity, ScalarAndSimdKernelsAreBitIdentical) {
  if (!SimdKernelAvailable()) GTEST_SKIP() << "this CPU has no AVX2";
  const Sequence seq = MakeSequence();
  for (Weighting weighting : {Weighting::kConstant, Weighting::kDepthDependent}) {
    IntegrateParams params;
    params.weighting = weighting;
    params.max_weight = 3.0f;  // so the cap is reached
    params.kernel = Kernel::kScalar;
    const TsdfVolume scalar = Fuse(seq, params);
    params.kernel = Kernel::kSimd;
    const TsdfVolume simd = Fuse(seq, params);
    EXPECT_GT(scalar.num_blocks(), 50u);
    ExpectIdentical(scalar, simd);
  }
}

TEST(Parity, OneAndTwoThreadsGiveIdenticalVolumesAndMeshes) {
  const Sequence seq = MakeSequence();
  auto run = [&](int threads) {
    ThreadLimit limit(threads);
    TsdfVolume volume = Fuse(seq, {});
    Mesh mesh = ExtractMesh(volume);
    return std::make_pair(std::move(volume), MeshBytes(mesh));
  };
  const auto one = run(1);
  const auto two = run(2);
  ExpectIdentical(one.first, two.first);
  EXPECT_FALSE(one.second.empty());
  EXPECT_EQ(one.second, two.second);
}

// The band walk's row filter: the SIMD one keeps exactly the pixels the scalar one keeps, on
// rows of every width (tails included) with invalid, out-of-range and NaN depths.
TEST(Parity, BandRowFilterScalarAndSimdAgree) {
  if (!SimdKernelAvailable()) GTEST_SKIP() << "this CPU has no AVX2";
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  for (int width : {1, 7, 8, 9, 31, 64, 333}) {
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<float> depth(static_cast<size_t>(width));
      float d = 0.5f + 2.f * unit(rng);
      for (float& x : depth) {
        const float r = unit(rng);
        // Mostly smooth runs (so neighbours share blocks), with jumps and invalid values.
        if (r < 0.05f) d = 0.5f + 2.f * unit(rng);
        x = r < 0.08f ? 0.f : (r < 0.1f ? std::nanf("") : (r < 0.12f ? 5.f : d));
        d += 0.002f * (unit(rng) - 0.5f);
      }
      internal::BandRow row;
      row.depth = depth.data();
      row.width = width;
      for (int k = 0; k < 3; ++k) {
        row.row[k] = 4.f * (unit(rng) - 0.5f);
        row.du[k] = 0.01f * (unit(rng) - 0.5f);
        row.origin[k] = 100.f * (unit(rng) - 0.5f);
      }
      row.trunc_m = 0.02f + 0.1f * unit(rng);
      row.min_depth_m = 0.1f;
      row.max_depth_m = 3.0f;
      std::vector<internal::BandCandidate> scalar(static_cast<size_t>(width)),
          simd(static_cast<size_t>(width));
      size_t valid_scalar = 0, valid_simd = 0;
      const int n_scalar = internal::BandRowCandidatesScalar(row, scalar.data(), &valid_scalar);
      const int n_simd = internal::BandRowCandidatesSimd(row, simd.data(), &valid_simd);
      EXPECT_EQ(valid_scalar, valid_simd);
      // The SIMD filter may keep a few more pixels in the row's last (width % 8) ones; the
      // band walk drops those again, so compare the kept pixels up to there.
      const int full = width - width % 8;
      scalar.resize(size_t(n_scalar));
      simd.resize(size_t(n_simd));
      auto in_tail = [&](const internal::BandCandidate& c) { return c.u >= full; };
      std::erase_if(scalar, in_tail);
      std::erase_if(simd, in_tail);
      ASSERT_EQ(scalar.size(), simd.size()) << "width " << width << ", trial " << trial;
      for (size_t i = 0; i < scalar.size(); ++i) {
        EXPECT_EQ(scalar[i].u, simd[i].u);
        EXPECT_EQ(std::memcmp(scalar[i].a, simd[i].a, sizeof(scalar[i].a)), 0);
        EXPECT_EQ(std::memcmp(scalar[i].b, simd[i].b, sizeof(scalar[i].b)), 0);
      }
    }
  }
}

// The blocks of the truncation band are the same with either filter, and hold the end blocks
// of the valid pixels' bands.
TEST(Parity, TruncationBandIsTheSameWithEitherFilter) {
  if (!SimdKernelAvailable()) GTEST_SKIP() << "this CPU has no AVX2";
  const Sequence seq = MakeSequence();
  const VolumeParams volume_params{0.02f, 0.08f};
  for (size_t f = 0; f < seq.poses.size(); ++f) {
    IntegrateParams params;
    params.kernel = Kernel::kScalar;
    const auto scalar =
        BlocksInTruncationBand(seq.depth[f], seq.cam, seq.poses[f], params, volume_params);
    params.kernel = Kernel::kSimd;
    const auto simd =
        BlocksInTruncationBand(seq.depth[f], seq.cam, seq.poses[f], params, volume_params);
    ASSERT_EQ(scalar, simd) << "frame " << f;
    ASSERT_TRUE(std::is_sorted(simd.begin(), simd.end()));
    ASSERT_EQ(std::adjacent_find(simd.begin(), simd.end()), simd.end());
    // Both ends of every valid pixel's band, computed independently (rounding may put a
    // point on the other side of a block face now and then).
    const std::set<BlockIndex> band(simd.begin(), simd.end());
    const float block = volume_params.voxel_size_m * kBlockSide;
    size_t missing = 0, checked = 0;
    for (int v = 0; v < seq.cam.height; ++v) {
      for (int u = 0; u < seq.cam.width; ++u) {
        const float d = seq.depth[f].at(u, v);
        if (!(d >= params.min_depth_m && d <= params.max_depth_m)) continue;
        const Eigen::Vector3f ray((float(u) - seq.cam.cx) / seq.cam.fx,
                                  (float(v) - seq.cam.cy) / seq.cam.fy, 1.f);
        for (float z : {d - volume_params.trunc_m, d + volume_params.trunc_m}) {
          missing += !band.count(BlockAt(seq.poses[f] * (ray * z), block));
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 1000u);
    EXPECT_LE(missing, checked / 1000) << "frame " << f;
  }
}

// The same projective update in float and double, without quantisation: the compact encoding
// must stay within a few 16-bit steps of it (far below a voxel).
TEST(CompactEncoding, MatchesAFloatReferenceIntegrator) {
  // 16-bit TSDF steps are 1/32767 of the truncation: 1.2e-4 voxel at 4 voxels of truncation.
  constexpr double kMaxQuantisationErrorVox = 1e-3;
  const Sequence seq = MakeSequence();
  const float voxel = 0.02f, trunc = 0.08f;
  const TsdfVolume volume = Fuse(seq, {}, voxel);
  struct Ref {
    double tsdf = 1.0, weight = 0.0;
  };
  std::map<GlobalVoxelIndex, Ref> reference;
  for (size_t f = 0; f < seq.poses.size(); ++f) {
    const Pose3f T_C_W = seq.poses[f].inverse();
    // Like the engine, update only the blocks of this frame's truncation band.
    for (const BlockIndex& b :
         BlocksInTruncationBand(seq.depth[f], seq.cam, seq.poses[f], {}, volume.params())) {
      for (int i = 0; i < kBlockVoxels; ++i) {
        const GlobalVoxelIndex g = GlobalOf(b, VoxelOfLinear(i));
        const Eigen::Vector3f p_C = T_C_W * VoxelCenter(g, voxel);
        if (p_C.z() <= 0) continue;
        const float u = std::floor(seq.cam.fx * p_C.x() / p_C.z() + seq.cam.cx + 0.5f);
        const float v = std::floor(seq.cam.fy * p_C.y() / p_C.z() + seq.cam.cy + 0.5f);
        if (u < 0 || v < 0 || u > seq.cam.width - 1 || v > seq.cam.height - 1) continue;
        const float d = seq.depth[f].at(int(u), int(v));
        if (!(d >= 0.1f && d <= 3.0f)) continue;
        const double sdf = double(d) - double(p_C.z());
        if (sdf < -trunc) continue;
        Ref& r = reference[g];
        const double t = std::min(1.0, sdf / trunc);
        r.tsdf = (r.tsdf * r.weight + t) / (r.weight + 1.0);
        r.weight = std::min(r.weight + 1.0, 64.0);
      }
    }
  }
  ASSERT_GT(reference.size(), 10000u);
  size_t tsdf_off = 0, weight_mismatch = 0;
  double worst_vox = 0.0;
  for (const auto& [g, r] : reference) {
    const TsdfBlock* block = volume.FindBlock(BlockOf(g));
    ASSERT_NE(block, nullptr);
    const int i = LinearIndex(LocalOf(g));
    const double err_vox = std::abs(DecodeTsdf(block->tsdf[i]) - r.tsdf) * trunc / voxel;
    tsdf_off += err_vox > kMaxQuantisationErrorVox;
    if (err_vox <= kMaxQuantisationErrorVox) worst_vox = std::max(worst_vox, err_vox);
    weight_mismatch += std::abs(DecodeWeight(block->weight[i]) - r.weight) > 1e-6;
  }
  // Eigen's float projection can round a voxel onto the neighbouring pixel at a pixel border,
  // which is not an encoding error: allow that for a tiny fraction of voxels.
  const size_t allowed = reference.size() / 1000;
  EXPECT_LE(tsdf_off, allowed) << "voxels off by more than " << kMaxQuantisationErrorVox
                               << " voxel";
  EXPECT_LE(weight_mismatch, allowed);
  RecordProperty("worst_quantisation_error_vox", std::to_string(worst_vox));
}

}  // namespace
}  // namespace voxplan
