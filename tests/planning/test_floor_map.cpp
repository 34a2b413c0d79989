// The floor map and the distances over it, on an L-shaped flat whose voxels are written
// directly: a dividing wall with a doorway, an unobserved column, a table top, a shelf above
// the band, clutter below it, partly observed columns and an opening in the outer wall.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include "core/parallel.h"
#include "core/volume.h"
#include "planning/floor_map.h"
#include "planning/geodesic.h"

namespace voxplan {
namespace {

constexpr float kVoxel = 0.05f;
constexpr float kInf = std::numeric_limits<float>::infinity();
// Extent of the allocated blocks, in voxels: blocks -1..8 by -1..6 by 0..4.
constexpr int kX0 = -8, kX1 = 72, kY0 = -8, kY1 = 56, kZ1 = 40;
// Float sums of at most a few hundred steps of exact unit costs.
constexpr float kSumTol = 1e-4f;
// 16-connected grid paths are at most 1 / cos(13.28 deg) - 1 = 2.75 % longer than the
// straight line between the same cell centres, 8-connected ones 1 / cos(22.5 deg) - 1 = 8.24 %.
constexpr float kGrid16Excess = 0.0275f;
constexpr float kGrid8Excess = 0.0824f;

enum class Kind {
  kOutside,
  kWall,
  kFree,
  kUnobserved,
  kTable,
  kShelf,
  kClutter,
  kPartial3,
  kPartial4
};

bool InL(int x, int y) { return x >= 0 && x < 64 && y >= 0 && y < 48 && !(x >= 40 && y >= 24); }

Kind LayoutAt(int x, int y) {
  if (!InL(x, y)) return Kind::kOutside;
  bool boundary = false;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) boundary |= !InL(x + dx, y + dy);
  if (boundary) return x == 63 && y >= 5 && y < 10 ? Kind::kFree : Kind::kWall;  // an opening
  if (x == 20 && !(y >= 20 && y < 28)) return Kind::kWall;  // dividing wall, doorway y 20..27
  if (x == 10 && y == 10) return Kind::kUnobserved;
  if (x >= 30 && x < 34 && y >= 5 && y < 8) return Kind::kTable;
  if (x == 50 && y == 10) return Kind::kShelf;
  if (x == 50 && y == 12) return Kind::kClutter;
  if (x == 12 && y == 30) return Kind::kPartial3;
  if (x == 13 && y == 30) return Kind::kPartial4;
  return Kind::kFree;
}

// Band: voxel centres in [0.1, 1.8] m, z 2..35 (34 voxels); 0.9 of them is 30.6, so 31 free
// voxels make a free column and 30 do not.
VoxelState StateAt(int x, int y, int z) {
  const Kind kind = LayoutAt(x, y);
  if (kind == Kind::kOutside) return VoxelState::kUnobserved;
  if (z == 0 || kind == Kind::kWall) return VoxelState::kOccupied;  // z = 0 is the floor slab
  switch (kind) {
    case Kind::kUnobserved:
      return VoxelState::kUnobserved;
    case Kind::kTable:
      return z == 14 ? VoxelState::kOccupied : VoxelState::kFree;  // 0.725 m
    case Kind::kShelf:
      return z == 38 ? VoxelState::kOccupied : VoxelState::kFree;  // 1.925 m
    case Kind::kClutter:
      return z == 1 ? VoxelState::kOccupied : VoxelState::kFree;  // 0.075 m
    case Kind::kPartial3:
      return z >= 5 && z < 8 ? VoxelState::kUnobserved : VoxelState::kFree;
    case Kind::kPartial4:
      return z >= 5 && z < 9 ? VoxelState::kUnobserved : VoxelState::kFree;
    default:
      return VoxelState::kFree;
  }
}

void SetVoxel(TsdfVolume& volume, GlobalVoxelIndex g, VoxelState s) {
  TsdfBlock& block = volume.FindOrAllocate(BlockOf(g));
  const int i = LinearIndex(LocalOf(g));
  // Truncation 4 voxels: tsdf -0.5 is 2 voxels behind a surface (occupied), +1 is free.
  block.tsdf[i] = EncodeTsdf(s == VoxelState::kOccupied ? -0.5f : 1.0f);
  block.weight[i] = EncodeWeight(s == VoxelState::kUnobserved ? 0.0f : 2.0f);
}

TsdfVolume LayoutVolume() {
  TsdfVolume volume({kVoxel, 4 * kVoxel});
  for (int z = 0; z < kZ1; ++z)
    for (int y = kY0; y < kY1; ++y)
      for (int x = kX0; x < kX1; ++x) SetVoxel(volume, {x, y, z}, StateAt(x, y, z));
  return volume;
}

// Expected classes straight from the layout, frontier by its definition.
FloorCell ExpectedBase(int x, int y) {
  if (x < kX0 || x >= kX1 || y < kY0 || y >= kY1) return FloorCell::kUnknown;
  switch (LayoutAt(x, y)) {
    case Kind::kOutside:
    case Kind::kUnobserved:
    case Kind::kPartial4:
      return FloorCell::kUnknown;
    case Kind::kWall:
    case Kind::kTable:
      return FloorCell::kObstacle;
    default:
      return FloorCell::kFree;
  }
}
FloorCell Expected(int x, int y) {
  const FloorCell base = ExpectedBase(x, y);
  if (base != FloorCell::kFree) return base;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (ExpectedBase(x + dx, y + dy) == FloorCell::kUnknown) return FloorCell::kFrontier;
  return FloorCell::kFree;
}

// Raster cell of global cell (x, y).
FloorCell MapAt(const FloorMap& map, int x, int y) {
  const Eigen::Vector2i o = map.geometry().origin_cell;
  return map.At(x - o.x(), y - o.y());
}
Eigen::Vector2f Center(int x, int y) {  // world xy of global cell (x, y) at 1 voxel per cell
  return {(float(x) + 0.5f) * kVoxel, (float(y) + 0.5f) * kVoxel};
}

void ExpectSameMap(const FloorMap& a, const FloorMap& b) {
  ASSERT_EQ(a.geometry(), b.geometry());
  size_t differing = 0;
  for (size_t i = 0; i < a.cells().size(); ++i) differing += a.cells()[i] != b.cells()[i];
  EXPECT_EQ(differing, 0u);
}

const TsdfVolume& SharedLayout() {
  static const TsdfVolume volume = LayoutVolume();
  return volume;
}

TEST(FloorMap, RefusesInvalidParameters) {
  FloorMapParams p;
  p.cell_voxels = 3;
  EXPECT_THROW(FloorMap(kVoxel, p), std::invalid_argument);
  p = {};
  p.band_min_m = 0.1f;
  p.band_max_m = 0.11f;  // centres at 0.075 and 0.125 m: none inside
  EXPECT_THROW(FloorMap(kVoxel, p), std::invalid_argument);
  p = {};
  p.min_free_fraction = 0.0f;
  EXPECT_THROW(FloorMap(kVoxel, p), std::invalid_argument);
  EXPECT_THROW(FloorMap(0.0f, FloorMapParams{}), std::invalid_argument);
  FloorMap map(kVoxel, FloorMapParams{});
  const TsdfVolume other({0.04f, 0.16f});
  const std::vector<BlockIndex> blocks = {{0, 0, 0}};
  EXPECT_EQ(map.Update(other, blocks).code(), StatusCode::kInvalidArgument);
}

TEST(FloorMap, ProjectsKnownLayout) {
  const FloorMap map = ProjectFloor(SharedLayout(), FloorMapParams{});
  EXPECT_EQ(map.geometry().origin_cell, Eigen::Vector2i(kX0, kY0));
  EXPECT_EQ(map.width(), kX1 - kX0);
  EXPECT_EQ(map.height(), kY1 - kY0);
  EXPECT_FLOAT_EQ(map.cell_size_m(), kVoxel);
  size_t wrong = 0;
  for (int y = kY0; y < kY1; ++y)
    for (int x = kX0; x < kX1; ++x) wrong += MapAt(map, x, y) != Expected(x, y);
  EXPECT_EQ(wrong, 0u);
  // The cases by hand.
  EXPECT_EQ(MapAt(map, 5, 5), FloorCell::kFree);
  EXPECT_EQ(MapAt(map, 20, 10), FloorCell::kObstacle);  // dividing wall
  EXPECT_EQ(MapAt(map, 20, 24), FloorCell::kFree);      // doorway
  EXPECT_EQ(MapAt(map, 31, 6), FloorCell::kObstacle);   // table top inside the band
  EXPECT_EQ(MapAt(map, 50, 10), FloorCell::kFree);      // shelf above the band
  EXPECT_EQ(MapAt(map, 50, 12), FloorCell::kFree);      // clutter below the band
  EXPECT_EQ(MapAt(map, 10, 10), FloorCell::kUnknown);   // unobserved column
  EXPECT_EQ(MapAt(map, 12, 30), FloorCell::kFrontier);  // 31 of 34 seen: free, next to unknown
  EXPECT_EQ(MapAt(map, 13, 30), FloorCell::kUnknown);   // 30 of 34 seen
  EXPECT_EQ(MapAt(map, 50, 40), FloorCell::kUnknown);   // outside the L
  EXPECT_EQ(MapAt(map, 63, 7), FloorCell::kFrontier);   // the opening looks outside
  EXPECT_EQ(MapAt(map, 62, 7), FloorCell::kFree);
  EXPECT_EQ(map.At(-1, 0), FloorCell::kUnknown);  // beyond the raster
  // Frontier: 8 around the unobserved column, 8 around the 30-of-34 column, 5 in the opening.
  EXPECT_EQ(map.Count(FloorCell::kFrontier), 21u);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (dx || dy) {
        EXPECT_EQ(MapAt(map, 10 + dx, 10 + dy), FloorCell::kFrontier);
      }
}

TEST(FloorMap, StrictFractionAndCoarseCells) {
  FloorMapParams strict;
  strict.min_free_fraction = 1.0f;
  const FloorMap all_seen = ProjectFloor(SharedLayout(), strict);
  EXPECT_EQ(MapAt(all_seen, 12, 30), FloorCell::kUnknown);
  EXPECT_EQ(MapAt(all_seen, 11, 30), FloorCell::kFrontier);

  // 2x2 voxel columns per cell: an obstacle exactly where any of the four fine cells is one.
  const FloorMap fine = ProjectFloor(SharedLayout(), FloorMapParams{});
  FloorMapParams coarse_params;
  coarse_params.cell_voxels = 2;
  const FloorMap coarse = ProjectFloor(SharedLayout(), coarse_params);
  EXPECT_FLOAT_EQ(coarse.cell_size_m(), 2 * kVoxel);
  ASSERT_EQ(coarse.width() * 2, fine.width());
  ASSERT_EQ(coarse.height() * 2, fine.height());
  size_t wrong = 0;
  for (int iy = 0; iy < coarse.height(); ++iy)
    for (int ix = 0; ix < coarse.width(); ++ix) {
      bool any_obstacle = false, all_free = true;
      for (int sy = 0; sy < 2; ++sy)
        for (int sx = 0; sx < 2; ++sx) {
          const FloorCell f = fine.At(2 * ix + sx, 2 * iy + sy);
          any_obstacle |= f == FloorCell::kObstacle;
          all_free &= IsFree(f);
        }
      const FloorCell c = coarse.At(ix, iy);
      wrong += (c == FloorCell::kObstacle) != any_obstacle;
      // Every fine column fully seen implies the coarse cell is free.
      wrong += all_free && !any_obstacle && !IsFree(c) &&
               LayoutAt(kX0 + 2 * ix, kY0 + 2 * iy) == Kind::kFree;
    }
  EXPECT_EQ(wrong, 0u);
}

TEST(FloorMap, IncrementalEqualsFromScratch) {
  TsdfVolume volume = LayoutVolume();
  std::vector<BlockIndex> blocks = volume.SortedBlockIndices();
  std::mt19937 rng(7);
  std::shuffle(blocks.begin(), blocks.end(), rng);
  FloorMap map(kVoxel, FloorMapParams{});
  // Feed the blocks in five uneven batches, each sorted: the raster grows batch by batch.
  const size_t cuts[] = {0, 3, 40, 41, 150, blocks.size()};
  uint64_t last_revision = map.revision();
  for (int k = 0; k < 5; ++k) {
    std::vector<BlockIndex> batch(blocks.begin() + ptrdiff_t(cuts[k]),
                                  blocks.begin() + ptrdiff_t(cuts[k + 1]));
    std::sort(batch.begin(), batch.end());
    ASSERT_TRUE(map.Update(volume, batch).ok());
    // A batch whose block columns were all projected before may change nothing.
    EXPECT_GE(map.revision(), last_revision);
    last_revision = map.revision();
  }
  EXPECT_GE(last_revision, 3u);
  ExpectSameMap(map, ProjectFloor(volume, FloorMapParams{}));

  // Nothing changed: the revision stays.
  const std::vector<BlockIndex> again = {{0, 0, 1}, {1, 1, 2}};
  ASSERT_TRUE(map.Update(volume, again).ok());
  EXPECT_EQ(map.revision(), last_revision);

  // Edit the volume: a new obstacle, the unobserved column seen, and new blocks east of the
  // raster. Only the touched blocks are passed.
  std::set<BlockIndex> touched;
  auto set = [&](int x, int y, int z, VoxelState s) {
    SetVoxel(volume, {x, y, z}, s);
    touched.insert(BlockOf(GlobalVoxelIndex{x, y, z}));
  };
  set(5, 5, 20, VoxelState::kOccupied);
  for (int z = 0; z < kZ1; ++z) set(10, 10, z, VoxelState::kFree);
  for (int y = 0; y < 8; ++y)
    for (int x = 72; x < 80; ++x)
      for (int z = 0; z < kZ1; ++z) set(x, y, z, VoxelState::kFree);
  ASSERT_TRUE(map.Update(volume, std::vector<BlockIndex>(touched.begin(), touched.end())).ok());
  EXPECT_GT(map.revision(), last_revision);
  EXPECT_EQ(MapAt(map, 5, 5), FloorCell::kObstacle);
  EXPECT_EQ(MapAt(map, 10, 10), FloorCell::kFree);
  EXPECT_EQ(MapAt(map, 9, 9), FloorCell::kFree);  // no longer next to unknown
  EXPECT_EQ(map.width(), 80 - kX0);
  ExpectSameMap(map, ProjectFloor(volume, FloorMapParams{}));
}

TEST(FloorMap, BlocksOutsideTheBandChangeNothing) {
  TsdfVolume volume = LayoutVolume();
  FloorMap map = ProjectFloor(volume, FloorMapParams{});
  const uint64_t revision = map.revision();
  SetVoxel(volume, {5, 5, 100}, VoxelState::kOccupied);  // 5 m up: block z 12
  const std::vector<BlockIndex> touched = {BlockOf(GlobalVoxelIndex{5, 5, 100})};
  ASSERT_TRUE(map.Update(volume, touched).ok());
  EXPECT_EQ(map.revision(), revision);
  EXPECT_EQ(MapAt(map, 5, 5), FloorCell::kFree);
}

TEST(FloorMap, ImageHasOneValuePerClass) {
  const FloorMap map = ProjectFloor(SharedLayout(), FloorMapParams{});
  const Image<uint8_t> image = FloorImage(map);
  ASSERT_EQ(image.width, map.width());
  ASSERT_EQ(image.height, map.height());
  const Eigen::Vector2i o = map.geometry().origin_cell;
  EXPECT_EQ(image.at(5 - o.x(), 5 - o.y()), kFloorPixelFree);
  EXPECT_EQ(image.at(20 - o.x(), 10 - o.y()), kFloorPixelObstacle);
  EXPECT_EQ(image.at(10 - o.x(), 10 - o.y()), kFloorPixelUnknown);
  EXPECT_EQ(image.at(9 - o.x(), 9 - o.y()), kFloorPixelFrontier);
  const std::set<uint8_t> values(image.data.begin(), image.data.end());
  EXPECT_EQ(values.size(), 4u);
}

// Squared distances by brute force over all sites.
Image<float> BruteForceSquaredDistance(const Image<uint8_t>& sites) {
  Image<float> out(sites.width, sites.height, kInf);
  for (int y = 0; y < sites.height; ++y)
    for (int x = 0; x < sites.width; ++x)
      for (int sy = 0; sy < sites.height; ++sy)
        for (int sx = 0; sx < sites.width; ++sx)
          if (sites.at(sx, sy))
            out.at(x, y) = std::min(out.at(x, y), float((x - sx) * (x - sx) + (y - sy) * (y - sy)));
  return out;
}

TEST(Clearance, DistanceTransformMatchesBruteForce) {
  std::mt19937 rng(11);
  const int sizes[][2] = {{1, 1}, {1, 17}, {13, 1}, {37, 23}, {64, 48}};
  for (const auto& size : sizes)
    for (double density : {0.0, 0.003, 0.05, 0.4}) {
      std::bernoulli_distribution site(density);
      Image<uint8_t> sites(size[0], size[1]);
      for (uint8_t& s : sites.data) s = site(rng);
      const Image<float> fast = SquaredDistanceTransform(sites);
      const Image<float> slow = BruteForceSquaredDistance(sites);
      ASSERT_EQ(fast.data.size(), slow.data.size());
      size_t wrong = 0;  // integer squared distances: exact
      for (size_t i = 0; i < fast.data.size(); ++i) wrong += fast.data[i] != slow.data[i];
      EXPECT_EQ(wrong, 0u) << size[0] << "x" << size[1] << " density " << density;
    }
}

TEST(Clearance, MetresToObstaclesOrUnknown) {
  const FloorMap map = ProjectFloor(SharedLayout(), FloorMapParams{});
  const Eigen::Vector2i o = map.geometry().origin_cell;
  const Image<float> to_obstacles = ComputeClearance(map);
  const Image<float> to_unknown_too = ComputeClearance(map, /*unknown_is_obstacle=*/true);
  // (11, 10): dividing wall 9 cells east; the unobserved column next door only counts as an
  // obstacle with the option.
  EXPECT_NEAR(to_obstacles.at(11 - o.x(), 10 - o.y()), 9 * kVoxel, 1e-6f);
  EXPECT_NEAR(to_unknown_too.at(11 - o.x(), 10 - o.y()), kVoxel, 1e-6f);
  EXPECT_EQ(to_obstacles.at(20 - o.x(), 10 - o.y()), 0.0f);
  // The far corner of the raster: unknown itself with the option, else nearest wall corner.
  EXPECT_EQ(to_unknown_too.at(0, 0), 0.0f);
  EXPECT_NEAR(to_obstacles.at(0, 0), std::hypot(8.0f, 8.0f) * kVoxel, 1e-6f);
}

GeodesicParams Params(float radius_m, GridConnectivity c = GridConnectivity::k16) {
  GeodesicParams p;
  p.robot_radius_m = radius_m;
  p.connectivity = c;
  return p;
}

float PathLength(const std::vector<Eigen::Vector2f>& path) {
  float length = 0.0f;
  for (size_t i = 1; i < path.size(); ++i) length += (path[i] - path[i - 1]).norm();
  return length;
}

TEST(FloorMap, MarkedObstaclesStayWhateverTheVolumeSays) {
  // A bumper's contacts shut the doorway (x 20, y 20..27) the camera saw free: no way from the
  // west room to the east one any more, through later updates and a rebuild alike.
  TsdfVolume volume = LayoutVolume();
  FloorMap map = ProjectFloor(volume, FloorMapParams{});
  GeodesicCache cache;
  ASSERT_TRUE(std::isfinite(
      cache.Field(map, Center(10, 40), Params(0.0f))
          ->At(30 - map.geometry().origin_cell.x(), 40 - map.geometry().origin_cell.y())));
  std::vector<Eigen::Vector2f> doorway;
  for (int y = 20; y < 28; ++y) doorway.push_back(Center(20, y));
  const uint64_t before = map.revision();
  EXPECT_TRUE(map.MarkObstacles(doorway));
  EXPECT_GT(map.revision(), before);
  const auto shut = [&](const FloorMap& m) {
    for (int y = 20; y < 28; ++y) EXPECT_EQ(MapAt(m, 20, y), FloorCell::kObstacle) << y;
    const Eigen::Vector2i o = m.geometry().origin_cell;
    EXPECT_EQ(cache.Field(m, Center(10, 40), Params(0.0f))->At(30 - o.x(), 40 - o.y()), kInf);
  };
  shut(map);
  // Marked again: nothing changes.
  const uint64_t marked = map.revision();
  EXPECT_FALSE(map.MarkObstacles(doorway));
  EXPECT_EQ(map.revision(), marked);
  // The volume still says free there; re-projecting its blocks keeps the marks.
  ASSERT_TRUE(map.Update(volume, volume.SortedBlockIndices()).ok());
  shut(map);
  ASSERT_TRUE(map.Rebuild(volume).ok());
  shut(map);
  // A contact beyond the raster grows it; the cell is an obstacle, its new neighbours unknown.
  const std::vector<Eigen::Vector2f> far = {Center(100, 5)};
  EXPECT_TRUE(map.MarkObstacles(far));
  EXPECT_EQ(MapAt(map, 100, 5), FloorCell::kObstacle);
  EXPECT_EQ(MapAt(map, 99, 5), FloorCell::kUnknown);
  EXPECT_EQ(MapAt(map, 10, 40), FloorCell::kFree);  // the rest is as it was
}

TEST(FloorMap, ContactsBesideSeenWallsNeedASecondReport) {
  // A bumper's contact two cells from the dividing wall the camera saw (x 20) is mostly that wall
  // a cell off on the map's grid: it goes on the map only when reported again. One in the open
  // goes on at once, and so do contacts beside cells only the bumper put there, or three cells
  // from the seen wall.
  FloorMap map = ProjectFloor(SharedLayout(), FloorMapParams{});
  const std::vector<Eigen::Vector2f> beside = {Center(22, 10)};
  ASSERT_EQ(MapAt(map, 22, 10), FloorCell::kFree);
  EXPECT_TRUE(map.MarkContacts(beside).empty());
  EXPECT_EQ(MapAt(map, 22, 10), FloorCell::kFree);
  EXPECT_EQ(map.MarkContacts(beside).size(), 1u);
  EXPECT_EQ(MapAt(map, 22, 10), FloorCell::kObstacle);
  EXPECT_TRUE(map.MarkContacts(beside).empty());  // already there: nothing changes
  for (const Eigen::Vector2i& c :
       {Eigen::Vector2i(10, 40), Eigen::Vector2i(11, 40), Eigen::Vector2i(23, 12)}) {
    const std::vector<Eigen::Vector2f> contact = {Center(c.x(), c.y())};
    EXPECT_EQ(map.MarkContacts(contact).size(), 1u) << c.transpose();
    EXPECT_EQ(MapAt(map, c.x(), c.y()), FloorCell::kObstacle) << c.transpose();
  }
}

TEST(Geodesic, StraightLinesAreEuclidean) {
  const FloorMap map = ProjectFloor(SharedLayout(), FloorMapParams{});
  GeodesicCache cache;
  const auto field = cache.Field(map, Center(3, 3), Params(0.1f));
  ASSERT_TRUE(field->has_source());
  const Eigen::Vector2i o = map.geometry().origin_cell;
  auto at = [&](int x, int y) { return field->At(x - o.x(), y - o.y()); };
  EXPECT_EQ(at(3, 3), 0.0f);
  EXPECT_NEAR(at(13, 3), 10 * kVoxel, kSumTol);                 // along x
  EXPECT_NEAR(at(3, 13), 10 * kVoxel, kSumTol);                 // along y
  EXPECT_NEAR(at(13, 8), std::sqrt(125.0f) * kVoxel, kSumTol);  // knight direction
  const auto diagonal = cache.Field(map, Center(3, 12), Params(0.1f));
  EXPECT_NEAR(diagonal->At(13 - o.x(), 22 - o.y()), std::sqrt(200.0f) * kVoxel, kSumTol);
  // With unit and diagonal steps only, the knight direction costs 5 + 5 (sqrt 2 - 1).
  const auto field8 = cache.Field(map, Center(3, 3), Params(0.1f, GridConnectivity::k8));
  EXPECT_NEAR(field8->At(13 - o.x(), 8 - o.y()), (5 + 5 * std::sqrt(2.0f)) * kVoxel, kSumTol);
}

TEST(Geodesic, AroundTheWallThroughTheDoorway) {
  const FloorMap map = ProjectFloor(SharedLayout(), FloorMapParams{});
  const Eigen::Vector2i o = map.geometry().origin_cell;
  // From (10, 40) to (30, 40): the dividing wall x = 20 is open only for y 20..27. Between
  // cell centres the shortest way bends at the doorway's last centre (20, 27); a path inside
  // the free cells may cut to the wall corners (19.5 / 20.5, 27.5), which bounds it below.
  const float via_centre_m = 2 * std::hypot(10.0f, 13.0f) * kVoxel;
  const float via_corners_m = (2 * std::hypot(9.5f, 12.5f) + 1.0f) * kVoxel;
  for (const auto& [connectivity, excess] : {std::pair{GridConnectivity::k16, kGrid16Excess},
                                             std::pair{GridConnectivity::k8, kGrid8Excess}}) {
    GeodesicCache cache;
    const auto field = cache.Field(map, Center(10, 40), Params(0.0f, connectivity));
    const float d = field->At(30 - o.x(), 40 - o.y());
    EXPECT_GE(d, via_corners_m * (1 - 1e-6f));
    EXPECT_LE(d, via_centre_m * (1 + excess));
    const auto path = ExtractPath(*field, Center(30, 40));
    ASSERT_TRUE(path.ok());
    EXPECT_TRUE(path->front().isApprox(Center(10, 40)));
    EXPECT_TRUE(path->back().isApprox(Center(30, 40)));
    EXPECT_NEAR(PathLength(*path), d, kSumTol);
    const auto same = cache.Path(map, Center(10, 40), Center(30, 40), Params(0.0f, connectivity));
    ASSERT_TRUE(same.ok());
    EXPECT_EQ(same->size(), path->size());
    for (const Eigen::Vector2f& p : *path) {
      const Eigen::Vector2i c = map.geometry().CellOf(p);
      EXPECT_TRUE(IsFree(map.At(c.x(), c.y())));
      if (c.x() + o.x() == 20) {
        EXPECT_TRUE(c.y() + o.y() >= 20 && c.y() + o.y() < 28);
      }
    }
  }
  // A wider robot keeps 3 cells from the door frame (only y 22..25 remain) and walks further;
  // at 5 cells the doorway closes.
  GeodesicCache cache;
  const float narrow = cache.Field(map, Center(10, 40), Params(0.0f))->At(30 - o.x(), 40 - o.y());
  const float wide = cache.Field(map, Center(10, 40), Params(0.15f))->At(30 - o.x(), 40 - o.y());
  EXPECT_TRUE(std::isfinite(wide));
  EXPECT_GT(wide, narrow);
  const auto closed = cache.Field(map, Center(10, 40), Params(0.25f));
  EXPECT_TRUE(closed->has_source());
  EXPECT_EQ(closed->At(30 - o.x(), 40 - o.y()), kInf);
  EXPECT_EQ(ExtractPath(*closed, Center(30, 40)).status().code(), StatusCode::kNotFound);
  EXPECT_EQ(cache.Path(map, Center(10, 40), Center(30, 40), Params(0.25f)).status().code(),
            StatusCode::kNotFound);
}

TEST(Geodesic, UnreachableAndUntraversable) {
  const FloorMap map = ProjectFloor(SharedLayout(), FloorMapParams{});
  const Eigen::Vector2i o = map.geometry().origin_cell;
  GeodesicCache cache;
  // Unknown cells are not traversable by default: no source, and nothing reaches outside.
  EXPECT_FALSE(cache.Field(map, Center(10, 10), Params(0.0f))->has_source());
  const auto inside = cache.Field(map, Center(5, 5), Params(0.0f));
  EXPECT_EQ(inside->At(10 - o.x(), 10 - o.y()), kInf);
  EXPECT_EQ(inside->At(66 - o.x(), 7 - o.y()), kInf);  // beyond the opening
  EXPECT_EQ(inside->At(-1, 0), kInf);
  // Allowing unknown opens the world beyond the opening.
  GeodesicParams explore = Params(0.0f);
  explore.unknown_traversable = true;
  const auto out = cache.Field(map, Center(5, 5), explore);
  EXPECT_TRUE(std::isfinite(out->At(66 - o.x(), 7 - o.y())));
  EXPECT_TRUE(std::isfinite(out->At(10 - o.x(), 10 - o.y())));
  // Snapping moves a point off the unknown column to a free neighbour 1 cell away.
  GeodesicParams snap = Params(0.0f);
  snap.snap_radius_m = 0.06f;
  const auto snapped = cache.Field(map, Center(10, 10), snap);
  ASSERT_TRUE(snapped->has_source());
  const Eigen::Vector2i s = snapped->source_cell + o;
  EXPECT_EQ((s - Eigen::Vector2i(10, 10)).cwiseAbs().sum(), 1);
  // In a matrix the snapped point's straight offset (one cell) is added to its distances.
  const std::vector<Eigen::Vector2f> points = {Center(10, 10), Center(5, 5)};
  const Eigen::MatrixXf m = cache.DistanceMatrix(map, points, snap);
  const float from_snapped = snapped->At(5 - o.x(), 5 - o.y());
  EXPECT_NEAR(m(0, 1), from_snapped + kVoxel, kSumTol);
  EXPECT_NEAR(m(1, 0), from_snapped + kVoxel, kSumTol);
  // Without snapping the unknown point reaches nothing.
  const Eigen::MatrixXf unsnapped = cache.DistanceMatrix(map, points, Params(0.0f));
  EXPECT_EQ(unsnapped(0, 1), kInf);
  EXPECT_EQ(unsnapped(1, 0), kInf);
}

TEST(Geodesic, NoCornerCutting) {
  // A free 24 x 24 patch split by a diagonal of obstacle cells that only touch at corners.
  TsdfVolume volume({kVoxel, 4 * kVoxel});
  for (int z = 0; z < kZ1; ++z)
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 24; ++x)
        SetVoxel(volume, {x, y, z}, x == y ? VoxelState::kOccupied : VoxelState::kFree);
  const FloorMap map = ProjectFloor(volume, FloorMapParams{});
  for (GridConnectivity c : {GridConnectivity::k8, GridConnectivity::k16}) {
    GeodesicCache cache;
    const auto field = cache.Field(map, Center(12, 3), Params(0.0f, c));
    EXPECT_TRUE(std::isfinite(field->At(20, 3)));
    EXPECT_EQ(field->At(3, 12), kInf);
  }
}

TEST(Geodesic, MatrixCacheFollowsRevisionAndParams) {
  TsdfVolume volume = LayoutVolume();
  FloorMap map = ProjectFloor(volume, FloorMapParams{});
  const std::vector<Eigen::Vector2f> points = {Center(5, 5),   Center(10, 40), Center(30, 40),
                                               Center(55, 15), Center(10, 10), Center(5, 6)};
  GeodesicCache cache;
  const GeodesicParams params = Params(0.1f);
  const Eigen::MatrixXf m = cache.DistanceMatrix(map, points, params);
  // (10, 10) is unknown: no field; the other five lie in distinct cells.
  EXPECT_EQ(cache.fields_computed(), 5u);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(m(i, i), 0.0f);
    for (int j = 0; j < 6; ++j) {
      if (i == j) continue;
      if (i == 4 || j == 4) {
        EXPECT_EQ(m(i, j), kInf);
        continue;
      }
      EXPECT_NEAR(m(i, j), m(j, i), kSumTol);
      const Eigen::Vector2i c = map.geometry().CellOf(points[size_t(j)]);
      EXPECT_EQ(m(i, j), cache.Field(map, points[size_t(i)], params)->At(c.x(), c.y()));
    }
  }
  EXPECT_NEAR(m(0, 5), kVoxel, kSumTol);
  EXPECT_GE(m(1, 2), (points[2] - points[1]).norm());
  // Same revision and params: nothing recomputed.
  EXPECT_TRUE(cache.DistanceMatrix(map, points, params) == m);
  EXPECT_EQ(cache.fields_computed(), 5u);
  // An update that changes nothing keeps the cache.
  const std::vector<BlockIndex> same = {{0, 0, 1}};
  ASSERT_TRUE(map.Update(volume, same).ok());
  (void)cache.DistanceMatrix(map, points, params);
  EXPECT_EQ(cache.fields_computed(), 5u);
  // A new obstacle bumps the revision: all fields again, and the detour shows.
  // (20, 26) closes the top of the doorway for this radius.
  std::set<BlockIndex> touched_set;
  for (int z = 2; z < 36; ++z) {
    SetVoxel(volume, {20, 26, z}, VoxelState::kOccupied);
    touched_set.insert(BlockOf(GlobalVoxelIndex{20, 26, z}));
  }
  const std::vector<BlockIndex> touched(touched_set.begin(), touched_set.end());
  const uint64_t revision = map.revision();
  ASSERT_TRUE(map.Update(volume, touched).ok());
  EXPECT_GT(map.revision(), revision);
  const Eigen::MatrixXf after = cache.DistanceMatrix(map, points, params);
  EXPECT_EQ(cache.fields_computed(), 10u);
  EXPECT_EQ(cache.num_cached_fields(), 5u);
  EXPECT_GT(after(1, 2), m(1, 2));
  // Another radius is another cache entry.
  const GeodesicParams narrow = Params(0.05f);
  (void)cache.DistanceMatrix(map, points, narrow);
  EXPECT_EQ(cache.fields_computed(), 15u);
  // A copy shares the revision, hence the fields; a fresh projection is a new revision.
  const FloorMap copy = map;
  (void)cache.DistanceMatrix(copy, points, narrow);
  EXPECT_EQ(cache.fields_computed(), 15u);
  (void)cache.DistanceMatrix(ProjectFloor(volume, FloorMapParams{}), points, narrow);
  EXPECT_EQ(cache.fields_computed(), 20u);
}

TEST(Determinism, OneAndTwoThreadsAgree) {
  auto run = [](int threads) {
    ThreadLimit limit(threads);
    TsdfVolume volume = LayoutVolume();
    std::vector<BlockIndex> blocks = volume.SortedBlockIndices();
    FloorMap map(kVoxel, FloorMapParams{});
    const size_t half = blocks.size() / 2;
    EXPECT_TRUE(map.Update(volume, std::span(blocks).first(half)).ok());
    EXPECT_TRUE(map.Update(volume, std::span(blocks).subspan(half)).ok());
    GeodesicCache cache;
    std::vector<Eigen::Vector2f> points;
    for (int i = 0; i < 12; ++i) points.push_back(Center(3 + 4 * i % 56, 3 + 7 * i % 20));
    struct Out {
      std::vector<FloorCell> cells;
      decltype(DepthImage::data) clearance;
      Eigen::MatrixXf distances;
    };
    return Out{map.cells(), ComputeClearance(map).data,
               cache.DistanceMatrix(map, points, Params(0.1f))};
  };
  const auto one = run(1);
  const auto two = run(2);
  EXPECT_TRUE(one.cells == two.cells);
  EXPECT_TRUE(one.clearance == two.clearance);
  EXPECT_TRUE((one.distances.array() == two.distances.array()).all());
}

}  // namespace
}  // namespace voxplan
