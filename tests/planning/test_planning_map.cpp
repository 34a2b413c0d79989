// Planning maps on a box room seen from its centre: states, frontier and surface voxels against
// brute force, uncertainty, normals, ray casts, label fusion and incremental vs rebuilt maps; the
// map summaries of a run's time series (map_summary.h) against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <set>
#include <utility>

#include "planning/integrate_planning.h"
#include "planning/map_summary.h"
#include "planning/planning_map.h"
#include "tests/fusion/box_room.h"

namespace voxplan {
namespace {

constexpr float kVoxel = 0.05f;
constexpr float kTrunc = 0.15f;
// Walls off the voxel grid by 0.4 voxel so no voxel centre sits on a classification boundary.
const test::BoxRoom kRoom{Eigen::Vector3f(-1.49f, -1.29f, -0.99f),
                          Eigen::Vector3f(1.49f, 1.29f, 0.99f)};
const Eigen::Vector3f kEye(0.02f, 0.03f, 0.01f);

struct Fixture {
  TsdfVolume volume{{kVoxel, kTrunc}};
  PlanningMap map{volume};
  PinholeCamera cam = test::RoomCamera();
  IntegrateParams params;

  Fixture() { params.max_depth_m = 4.0f; }
  PlanningFrameStats Fuse(const Pose3f& T_W_C, const LabelImage* labels = nullptr) {
    const DepthImage depth = test::RenderRoomDepth(kRoom, cam, T_W_C);
    auto stats =
        IntegratePlanningFrame(depth, ColorImage(), labels, cam, T_W_C, params, volume, map);
    EXPECT_TRUE(stats.ok()) << stats.status().message();
    return stats.ok() ? *stats : PlanningFrameStats{};
  }
};

// Every voxel of the blocks around the room.
std::vector<GlobalVoxelIndex> RoomVoxels() {
  std::vector<GlobalVoxelIndex> out;
  const GlobalVoxelIndex lo = VoxelAt(kRoom.lo - Eigen::Vector3f::Constant(0.5f), kVoxel);
  const GlobalVoxelIndex hi = VoxelAt(kRoom.hi + Eigen::Vector3f::Constant(0.5f), kVoxel);
  for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y)
      for (int x = lo.x; x <= hi.x; ++x) out.push_back({x, y, z});
  return out;
}

const GlobalVoxelIndex kFaces[6] = {{-1, 0, 0}, {1, 0, 0},  {0, -1, 0},
                                    {0, 1, 0},  {0, 0, -1}, {0, 0, 1}};
GlobalVoxelIndex Add(GlobalVoxelIndex a, GlobalVoxelIndex b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}

// The definitions of planning/planning_map.h evaluated voxel by voxel through StateAt.
std::set<GlobalVoxelIndex> BruteForce(const PlanningMap& map, VoxelState self, VoxelState nb) {
  std::set<GlobalVoxelIndex> out;
  for (const GlobalVoxelIndex& g : RoomVoxels()) {
    if (map.StateAt(g) != self) continue;
    for (const GlobalVoxelIndex& f : kFaces)
      if (map.StateAt(Add(g, f)) == nb) {
        out.insert(g);
        break;
      }
  }
  return out;
}

TEST(PlanningMap, RoomFromCentreHasOccupiedWallsFreeInteriorUnobservedOutside) {
  Fixture fx;
  for (const Pose3f& pose : test::AxisViews(kEye)) fx.Fuse(pose);
  const float margin = 2.f * kVoxel;
  size_t checked_free = 0, checked_wall = 0, checked_outside = 0;
  size_t front_layer = 0, front_occupied = 0;
  for (const GlobalVoxelIndex& g : RoomVoxels()) {
    const Eigen::Vector3f p = VoxelCenter(g, kVoxel);
    const float sdf = kRoom.Sdf(p);
    const VoxelState state = fx.map.StateAt(g);
    if (sdf > margin && (p - kEye).norm() > 0.2f) {
      EXPECT_EQ(state, VoxelState::kFree) << p.transpose();
      ++checked_free;
    } else if (sdf < 0.f && sdf > -1.5f * kVoxel) {
      // Just behind a wall: every view puts it behind the observed surface.
      EXPECT_EQ(state, VoxelState::kOccupied) << p.transpose();
      ++checked_wall;
    } else if (sdf > 0.f && sdf < 0.5f * kVoxel) {
      // Just in front: projective distances seen at grazing angles (near the room's edges)
      // are longer than the true distance and may push a voxel over to free.
      ++front_layer;
      front_occupied += state == VoxelState::kOccupied;
    } else if (sdf < -(kTrunc + margin)) {
      EXPECT_EQ(state, VoxelState::kUnobserved) << p.transpose();
      ++checked_outside;
    }
  }
  EXPECT_GT(checked_free, 10000u);
  EXPECT_GT(checked_wall, 2000u);
  EXPECT_GT(checked_outside, 2000u);
  EXPECT_GT(double(front_occupied), 0.9 * double(front_layer));
  // Point and batched queries agree.
  const std::vector<Eigen::Vector3f> points = {Eigen::Vector3f(0.5f, 0.4f, 0.3f),
                                               Eigen::Vector3f(1.48f, 0.2f, 0.1f),
                                               Eigen::Vector3f(1.9f, 0.2f, 0.1f)};
  const std::vector<VoxelState> expected = {VoxelState::kFree, VoxelState::kOccupied,
                                            VoxelState::kUnobserved};
  EXPECT_EQ(fx.map.StatesAt(points), expected);
  // All walls seen, nothing behind them: no free voxel touches unobserved space.
  EXPECT_EQ(fx.map.CountFrontier(), 0u);
}

TEST(PlanningMap, FrontierAndSurfaceMatchTheirDefinitionsAcrossBlockFaces) {
  Fixture fx;
  fx.Fuse(test::AxisViews(kEye)[0]);  // looking along +x only
  const std::vector<GlobalVoxelIndex> frontier = fx.map.FrontierVoxels();
  const auto expected = BruteForce(fx.map, VoxelState::kFree, VoxelState::kUnobserved);
  ASSERT_GT(frontier.size(), 500u);
  EXPECT_EQ(std::set<GlobalVoxelIndex>(frontier.begin(), frontier.end()), expected);
  EXPECT_TRUE(std::is_sorted(frontier.begin(), frontier.end()));
  // The frontier is the side of the view frustum: max(|dy|, |dz|) = dx within a few voxels,
  // except near the camera, where min depth and the voxel grid blur the apex.
  for (const GlobalVoxelIndex& g : frontier) {
    const Eigen::Vector3f d = VoxelCenter(g, kVoxel) - kEye;
    if (d.norm() < 0.3f) continue;
    // 1.111: tan of the half field of view, (side / 2) / (0.45 side).
    EXPECT_NEAR(std::max(std::abs(d.y()), std::abs(d.z())) / 1.111f, d.x(), 3.f * kVoxel)
        << d.transpose();
  }
  const std::vector<MapSurfaceVoxel> surface = fx.map.SurfaceVoxels();
  std::set<GlobalVoxelIndex> surface_set;
  for (const MapSurfaceVoxel& v : surface) surface_set.insert(v.index);
  EXPECT_EQ(surface_set, BruteForce(fx.map, VoxelState::kOccupied, VoxelState::kFree));
  EXPECT_EQ(fx.map.CountSurface(), surface.size());
  // The seen wall is x = 1.49: its surface voxels are the last row before it, normals -x.
  size_t on_wall = 0;
  for (const MapSurfaceVoxel& v : surface) {
    if (std::abs(v.center_W.x() - 1.475f) > 1e-4f || std::abs(v.center_W.y()) > 0.8f ||
        std::abs(v.center_W.z()) > 0.8f)
      continue;
    ++on_wall;
    EXPECT_GT(-v.normal_W.x(), 0.95f) << v.center_W.transpose();
    EXPECT_NEAR(v.uncertainty, 1.0f / v.weight, 1e-6f);
  }
  EXPECT_GT(on_wall, 300u);
}

TEST(PlanningMap, SurfaceUncertaintyFallsWithMoreObservations) {
  Fixture fx;
  const Pose3f pose = test::AxisViews(kEye)[0];
  const GlobalVoxelIndex wall_voxel = VoxelAt(Eigen::Vector3f(1.475f, 0.1f, 0.1f), kVoxel);
  float previous = std::numeric_limits<float>::infinity();
  for (int k = 1; k <= 4; ++k) {
    fx.Fuse(pose);
    float found = -1.f;
    for (const MapSurfaceVoxel& v : fx.map.SurfaceVoxels())
      if (v.index == wall_voxel) found = v.uncertainty;
    ASSERT_GT(found, 0.f) << "wall voxel not a surface voxel after " << k << " frames";
    EXPECT_NEAR(found, 1.0f / float(k), 1e-3f);  // constant weighting: weight = frames
    EXPECT_LT(found, previous);
    previous = found;
  }
}

TEST(PlanningMap, CastRayStopsAtWallsAndUnobservedSpace) {
  Fixture fx;
  for (const Pose3f& pose : test::AxisViews(kEye)) fx.Fuse(pose);
  const Eigen::Vector3f from(0.f, 0.1f, 0.1f);
  const RayCastResult wall = fx.map.CastRay(from, Eigen::Vector3f(3.f, 0.1f, 0.1f));
  EXPECT_EQ(wall.hit, RayHit::kOccupied);
  // The first occupied voxel is [1.45, 1.5), entered at x = 1.45.
  EXPECT_NEAR(wall.distance_m, 1.45f, 1e-3f);
  EXPECT_EQ(fx.map.StateAt(wall.voxel), VoxelState::kOccupied);
  const RayCastResult inside = fx.map.CastRay(from, Eigen::Vector3f(1.0f, -0.5f, 0.4f));
  EXPECT_EQ(inside.hit, RayHit::kNone);
  const RayCastResult outside =
      fx.map.CastRay(Eigen::Vector3f(2.5f, 0.f, 0.f), Eigen::Vector3f(0.f, 0.f, 0.f));
  EXPECT_EQ(outside.hit, RayHit::kUnobserved);
  EXPECT_NEAR(outside.distance_m, 0.f, 1e-6f);
  const RayCastResult through =
      fx.map.CastRay(Eigen::Vector3f(2.5f, 0.f, 0.f), Eigen::Vector3f(0.f, 0.f, 0.f), false);
  EXPECT_EQ(through.hit, RayHit::kOccupied);
  // The outermost observed voxel behind the wall, [1.60, 1.65): 0.135 m behind it, inside the
  // 0.15 m truncation.
  EXPECT_NEAR(through.distance_m, 2.5f - 1.65f, 1e-3f);
}

TEST(PlanningMap, LabelFusionKeepsTheMajorityAndCounts) {
  Fixture fx;
  fx.map.SetInstanceClass(7, "wall");
  const Pose3f pose = test::AxisViews(kEye)[0];
  // Left half of the image labelled 7 three times and 9 once; right half 9 always.
  LabelImage major(fx.cam.width, fx.cam.height, 0), minor(fx.cam.width, fx.cam.height, 0);
  for (int v = 0; v < fx.cam.height; ++v)
    for (int u = 0; u < fx.cam.width; ++u) {
      major.at(u, v) = u < fx.cam.width / 2 ? 7 : 9;
      minor.at(u, v) = 9;
    }
  for (int k = 0; k < 3; ++k) fx.Fuse(pose, &major);
  const PlanningFrameStats last = fx.Fuse(pose, &minor);
  EXPECT_EQ(last.revision, fx.map.revision());
  // The camera looks along +x with image x along -y: the left half sees y > 0.
  const GlobalVoxelIndex left = VoxelAt(Eigen::Vector3f(1.475f, 0.5f, 0.1f), kVoxel);
  const GlobalVoxelIndex right = VoxelAt(Eigen::Vector3f(1.475f, -0.5f, 0.1f), kVoxel);
  EXPECT_EQ(fx.map.LabelAt(left), 7u);
  EXPECT_EQ(fx.map.LabelAt(right), 9u);
  const auto left_candidates = fx.map.LabelCandidatesAt(left);
  ASSERT_EQ(left_candidates.size(), 2u);
  EXPECT_EQ(left_candidates[0], (std::pair<uint32_t, uint16_t>(7, 3)));
  EXPECT_EQ(left_candidates[1], (std::pair<uint32_t, uint16_t>(9, 1)));
  EXPECT_EQ(fx.map.LabelAt(VoxelAt(Eigen::Vector3f(0.5f, 0.f, 0.f), kVoxel)), 0u);

  const std::vector<InstanceRecord> instances = fx.map.Instances();
  ASSERT_EQ(instances.size(), 2u);
  EXPECT_EQ(instances[0].id, 7u);
  EXPECT_EQ(instances[0].class_name, "wall");
  EXPECT_EQ(instances[1].id, 9u);
  EXPECT_TRUE(instances[1].class_name.empty());
  for (const InstanceRecord& r : instances) {
    EXPECT_GT(r.voxel_count, 100u);
    // Labels sit on the walls the view sees: the +x wall, and floor, ceiling and side walls
    // from x = 0.89 on (where the 48 degree half field of view reaches them).
    EXPECT_GT(r.bbox_min_W.x(), 0.85f);
    EXPECT_LT(r.bbox_max_W.x(), 1.49f + 2.f * kVoxel);
    ASSERT_FALSE(r.surface_points_W.empty());
    ASSERT_EQ(r.surface_points_W.size(), r.surface_normals_W.size());
    size_t on_wall = 0;
    for (size_t i = 0; i < r.surface_points_W.size(); ++i) {
      const Eigen::Vector3f& p = r.surface_points_W[i];
      if (std::abs(p.x() - 1.475f) > 1e-4f || std::abs(p.y()) > 0.8f || std::abs(p.z()) > 0.8f)
        continue;
      ++on_wall;
      EXPECT_GT(-r.surface_normals_W[i].x(), 0.95f);
    }
    EXPECT_GT(on_wall, 100u);
  }
  EXPECT_GT(instances[0].bbox_min_W.y(), instances[1].bbox_min_W.y());  // 7 is the y > 0 side
  // Surface voxels carry the same fused labels.
  size_t labelled = 0;
  for (const MapSurfaceVoxel& v : fx.map.SurfaceVoxels()) {
    ASSERT_EQ(v.label, fx.map.LabelAt(v.index));
    labelled += v.label != 0;
  }
  EXPECT_GT(labelled, 200u);
}

TEST(PlanningMap, IncrementalUpdateEqualsRebuild) {
  Fixture fx;
  const std::vector<Pose3f> views = test::AxisViews(kEye);
  uint64_t revision = fx.map.revision();
  for (int k : {0, 2, 5, 1}) {
    fx.Fuse(views[size_t(k)]);
    EXPECT_GT(fx.map.revision(), revision);
    revision = fx.map.revision();
  }
  PlanningMap rebuilt(fx.volume);
  rebuilt.Rebuild();
  ASSERT_EQ(rebuilt.num_blocks(), fx.map.num_blocks());
  ASSERT_EQ(rebuilt.num_blocks(), fx.volume.num_blocks());
  for (const BlockIndex& b : fx.volume.SortedBlockIndices()) {
    const PlanningBlock* a = fx.map.FindBlock(b);
    const PlanningBlock* r = rebuilt.FindBlock(b);
    ASSERT_TRUE(a && r);
    EXPECT_EQ(a->occupied, r->occupied);
    EXPECT_EQ(a->free, r->free);
    EXPECT_EQ(a->frontier, r->frontier);
    EXPECT_EQ(a->surface, r->surface);
  }
  EXPECT_EQ(fx.map.FrontierVoxels(), rebuilt.FrontierVoxels());
  EXPECT_GT(fx.map.CountFrontier(), 0u);  // three of six walls unseen
}

// The normal rule of planning/planning_map.h voxel by voxel through the volume: central differences
// of observed TSDF values, one-sided next to unobserved voxels.
Eigen::Vector3f ReferenceNormal(const TsdfVolume& volume, GlobalVoxelIndex g,
                                const VoxelStateParams& state) {
  auto tsdf = [&](GlobalVoxelIndex q) -> std::optional<float> {
    const TsdfBlock* b = volume.FindBlock(BlockOf(q));
    if (!b) return std::nullopt;
    const int i = LinearIndex(LocalOf(q));
    if (DecodeWeight(b->weight[i]) < state.min_weight) return std::nullopt;
    return DecodeTsdf(b->tsdf[i]);
  };
  const std::optional<float> c = tsdf(g);
  Eigen::Vector3f grad = Eigen::Vector3f::Zero();
  for (int k = 0; k < 3; ++k) {
    const std::optional<float> m = tsdf(Add(g, kFaces[2 * k])), p = tsdf(Add(g, kFaces[2 * k + 1]));
    if (m && p) {
      grad[k] = 0.5f * (*p - *m);
    } else if (p && c) {
      grad[k] = *p - *c;
    } else if (m && c) {
      grad[k] = *c - *m;
    }
  }
  const float n = grad.norm();
  return n > 0.f ? Eigen::Vector3f(grad / n) : Eigen::Vector3f::Zero();
}

// SurfaceVoxels asked between frames (so later calls reuse cached blocks) equals a fresh map's,
// and its normals (read through each block's face neighbours) equal the voxel-by-voxel rule.
TEST(PlanningMap, CachedSurfaceVoxelsEqualAFreshMapsAfterEveryFrame) {
  Fixture fx;
  const std::vector<Pose3f> views = test::AxisViews(kEye);
  size_t largest = 0;
  for (int k : {0, 2, 5, 1, 0, 3}) {
    fx.Fuse(views[size_t(k)]);
    const std::vector<MapSurfaceVoxel> cached = fx.map.SurfaceVoxels();
    PlanningMap fresh(fx.volume);
    fresh.Rebuild();
    const std::vector<MapSurfaceVoxel> expected = fresh.SurfaceVoxels();
    ASSERT_EQ(cached.size(), expected.size()) << "after view " << k;
    for (size_t i = 0; i < cached.size(); ++i) {
      ASSERT_EQ(cached[i].index, expected[i].index);
      // Bitwise: a stale normal next to a changed face neighbour would differ here.
      ASSERT_EQ(cached[i].normal_W, expected[i].normal_W) << "voxel " << i << " after view " << k;
      ASSERT_EQ(cached[i].weight, expected[i].weight);
      ASSERT_EQ(cached[i].normal_W, ReferenceNormal(fx.volume, cached[i].index, {}));
    }
    largest = std::max(largest, cached.size());
  }
  EXPECT_GT(largest, 1000u);
}

// The per-block masks (fixed-point thresholds, SIMD on x86-64) against ClassifyVoxel itself,
// on random voxels and on values right at each threshold, for several rules.
TEST(PlanningMap, MasksMatchClassifyVoxel) {
  TsdfVolume volume({kVoxel, kTrunc});
  const BlockIndex b{-3, 2, -1};
  TsdfBlock& block = volume.FindOrAllocate(b);
  std::mt19937 rng(7);
  for (const VoxelStateParams rule : {VoxelStateParams{}, VoxelStateParams{1e-6f, -2.f},
                                      VoxelStateParams{3.f, 2.9f}, VoxelStateParams{600.f, 9.f}}) {
    const PlanningMapParams params{rule, 0.5f};
    PlanningMap map(volume, params);
    // Values near the thresholds: weight around min_weight, tsdf around the occupied bound.
    const int w_edge = int(std::lround(rule.min_weight * kWeightScale));
    const int t_edge = int(std::lround(rule.occupied_max_sdf_vox / (kTrunc / kVoxel) * kTsdfScale));
    for (int i = 0; i < kBlockVoxels; ++i) {
      const bool edge = i % 2 == 0;
      block.weight[i] =
          uint16_t(edge ? std::clamp(w_edge + int(rng() % 5) - 2, 0, 65535) : int(rng() % 65536));
      block.tsdf[i] = int16_t(edge ? std::clamp(t_edge + int(rng() % 5) - 2, -32768, 32767)
                                   : int(rng() % 65536) - 32768);
    }
    map.Update({b});
    const PlanningBlock* pb = map.FindBlock(b);
    ASSERT_NE(pb, nullptr);
    for (int i = 0; i < kBlockVoxels; ++i) {
      const VoxelState expected =
          ClassifyVoxel(block.tsdf[i], block.weight[i], kTrunc / kVoxel, rule);
      EXPECT_EQ(TestBit(pb->free, i), expected == VoxelState::kFree) << i;
      EXPECT_EQ(TestBit(pb->occupied, i), expected == VoxelState::kOccupied) << i;
    }
  }
}

TEST(PlanningMap, RefusesMismatchedInputs) {
  Fixture fx;
  TsdfVolume other({kVoxel, kTrunc});
  const Pose3f pose = test::AxisViews(kEye)[0];
  const DepthImage depth = test::RenderRoomDepth(kRoom, fx.cam, pose);
  EXPECT_FALSE(
      IntegratePlanningFrame(depth, {}, nullptr, fx.cam, pose, fx.params, other, fx.map).ok());
  const LabelImage small(4, 4, 1);
  EXPECT_FALSE(
      IntegratePlanningFrame(depth, {}, &small, fx.cam, pose, fx.params, fx.volume, fx.map).ok());
  EXPECT_THROW(PlanningMap(fx.volume, PlanningMapParams{{0.f, 0.5f}, 0.5f}), std::invalid_argument);
}

TEST(MapSummary, UnobservedVoxelsOfARegionAndMeanUncertaintyMatchBruteForce) {
  // A region across block faces on every axis, negative coordinates included, reaching past the
  // room into blocks never allocated; a hole and duplicate columns.
  std::vector<Eigen::Vector2i> columns;
  for (int y = -37; y <= 21; ++y)
    for (int x = -45; x <= 33; ++x)
      if (!(x > -5 && x < 4 && y > -3 && y < 6)) columns.emplace_back(x, y);
  columns.emplace_back(0, -37);
  columns.emplace_back(-45, 21);
  const int z0 = -13, z1 = 11;
  const ColumnRegion region(columns, z0, z1);
  std::set<std::pair<int, int>> distinct;
  for (const Eigen::Vector2i& c : columns) distinct.insert({c.x(), c.y()});
  ASSERT_EQ(region.voxels(), distinct.size() * size_t(z1 - z0));
  auto brute = [&](const PlanningMap& map) {
    size_t n = 0;
    for (const auto& [x, y] : distinct)
      for (int z = z0; z < z1; ++z)
        n += map.StateAt(GlobalVoxelIndex{x, y, z}) == VoxelState::kUnobserved;
    return n;
  };
  auto mean_uncertainty = [](const PlanningMap& map) {
    double sum = 0.0;
    const std::vector<MapSurfaceVoxel> surface = map.SurfaceVoxels();
    for (const MapSurfaceVoxel& v : surface) sum += std::clamp(v.uncertainty, 0.f, 1.f);
    return surface.empty() ? std::nan("") : sum / double(surface.size());
  };

  Fixture fx;
  EXPECT_EQ(region.CountUnobserved(fx.map), region.voxels());  // an empty map
  EXPECT_TRUE(std::isnan(MeanSurfaceUncertainty(fx.map)));
  size_t last = region.voxels();
  const std::vector<Pose3f> views = test::AxisViews(kEye);
  for (size_t k = 0; k < views.size(); ++k) {
    fx.Fuse(views[k]);
    if (k == 2) fx.Fuse(views[k]);  // some walls seen twice: weights above 1
    const size_t unobserved = region.CountUnobserved(fx.map);
    EXPECT_EQ(unobserved, brute(fx.map)) << "after view " << k;
    EXPECT_LE(unobserved, last) << "observed voxels stay observed";
    EXPECT_LT(unobserved, region.voxels());
    last = unobserved;
    EXPECT_NEAR(MeanSurfaceUncertainty(fx.map), mean_uncertainty(fx.map), 1e-9) << k;
  }
  EXPECT_GT(last, 0u);  // beyond the walls
  EXPECT_EQ(ColumnRegion(columns, 4, 4).voxels(), 0u);
  EXPECT_EQ(ColumnRegion(columns, 4, 4).CountUnobserved(fx.map), 0u);
}

}  // namespace
}  // namespace voxplan
