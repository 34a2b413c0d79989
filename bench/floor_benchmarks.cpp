// Benchmarks of the 2-D floor map on a 20 x 12 m house at 5 cm (400 x 240 cells): incremental
// projection of one frame's blocks, a full rebuild, clearance, geodesic fields and a 30 x 30
// geodesic distance matrix. The house is written into the volume directly (walls with doors,
// tables, two unobserved patches), so the numbers need no simulator.
// Run: build/bench/voxplan_floorbench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/parallel.h"
#include "core/volume.h"
#include "planning/floor_map.h"
#include "planning/geodesic.h"

namespace voxplan {
namespace {

constexpr float kVoxel = 0.05f;
constexpr int kCellsX = 400, kCellsY = 240, kVoxelsZ = 48;  // 20 x 12 x 2.4 m

VoxelState HouseState(int x, int y, int z) {
  if (x < 0 || y < 0 || x >= kCellsX || y >= kCellsY) return VoxelState::kUnobserved;
  if (z == 0) return VoxelState::kOccupied;  // floor slab
  // Unobserved patches: a closed store room and a corner not yet scanned.
  if (x >= 330 && y >= 180) return VoxelState::kUnobserved;
  if (x >= 20 && x < 60 && y >= 200 && y < 230) return VoxelState::kUnobserved;
  const bool outer = x < 2 || y < 2 || x >= kCellsX - 2 || y >= kCellsY - 2;
  // Three cross walls with 1 m doors and one long wall with a door per room.
  const bool cross = (x == 100 || x == 200 || x == 300) && !(y >= 50 + x / 5 && y < 70 + x / 5);
  const bool hall = (y == 120 || y == 121) && (x % 100 < 40 || x % 100 >= 60);
  if (outer || cross || hall) return VoxelState::kOccupied;
  // A table in every room: occupied only at its top, 0.75 m.
  const bool table = (x % 100 >= 30 && x % 100 < 60) && (y % 120 >= 40 && y % 120 < 60);
  if (table && z == 15) return VoxelState::kOccupied;
  return VoxelState::kFree;
}

const TsdfVolume& House() {
  static const TsdfVolume volume = [] {
    TsdfVolume v({kVoxel, 4 * kVoxel});
    for (int bz = 0; bz < kVoxelsZ / kBlockSide; ++bz)
      for (int by = 0; by < kCellsY / kBlockSide; ++by)
        for (int bx = 0; bx < kCellsX / kBlockSide; ++bx) {
          const BlockIndex b{bx, by, bz};
          TsdfBlock& block = v.FindOrAllocate(b);
          for (int i = 0; i < kBlockVoxels; ++i) {
            const GlobalVoxelIndex g = GlobalOf(b, VoxelOfLinear(i));
            const VoxelState s = HouseState(g.x, g.y, g.z);
            block.tsdf[i] = EncodeTsdf(s == VoxelState::kOccupied ? -0.5f : 1.0f);
            block.weight[i] = EncodeWeight(s == VoxelState::kUnobserved ? 0.0f : 2.0f);
          }
        }
    return v;
  }();
  return volume;
}

const FloorMap& HouseMap() {
  static const FloorMap map = ProjectFloor(House(), FloorMapParams{});
  return map;
}

// The blocks a depth camera at (5, 3) m looking along +x (90 deg field of view, 4 m range)
// touches: every block of the volume whose column centre lies in that sector.
std::vector<BlockIndex> FrameBlocks() {
  std::vector<BlockIndex> blocks;
  const float block_m = kVoxel * kBlockSide;
  for (int bz = 0; bz < kVoxelsZ / kBlockSide; ++bz)
    for (int by = 0; by < kCellsY / kBlockSide; ++by)
      for (int bx = 0; bx < kCellsX / kBlockSide; ++bx) {
        const float dx = (float(bx) + 0.5f) * block_m - 5.0f;
        const float dy = (float(by) + 0.5f) * block_m - 3.0f;
        if (dx > 0.0f && std::abs(dy) <= dx && std::hypot(dx, dy) <= 4.0f)
          blocks.push_back({bx, by, bz});
      }
  std::sort(blocks.begin(), blocks.end());
  return blocks;
}

// A spread of points on free cells with room for a 0.2 m robot.
std::vector<Eigen::Vector2f> SpreadPoints(int n) {
  const FloorMap& map = HouseMap();
  const Image<uint8_t> ok = TraversableCells(map, GeodesicParams{});
  std::vector<Eigen::Vector2f> points;
  for (int i = 0; int(points.size()) < n && i < 100000; ++i) {
    const int ix = (i * 7919) % map.width(), iy = (i * 104729) % map.height();
    if (ok.at(ix, iy)) points.push_back(map.geometry().CellCenter(ix, iy));
  }
  return points;
}

void BM_FloorUpdateFrame(benchmark::State& state) {
  ThreadLimit limit(int(state.range(0)));
  FloorMap map = HouseMap();
  const std::vector<BlockIndex> blocks = FrameBlocks();
  for (auto _ : state) benchmark::DoNotOptimize(map.Update(House(), blocks));
  state.counters["blocks"] = double(blocks.size());
}
BENCHMARK(BM_FloorUpdateFrame)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_FloorRebuild(benchmark::State& state) {
  ThreadLimit limit(int(state.range(0)));
  FloorMap map(kVoxel, FloorMapParams{});
  for (auto _ : state) benchmark::DoNotOptimize(map.Rebuild(House()));
  state.counters["blocks"] = double(House().num_blocks());
}
BENCHMARK(BM_FloorRebuild)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_Clearance(benchmark::State& state) {
  ThreadLimit limit(1);
  for (auto _ : state) benchmark::DoNotOptimize(ComputeClearance(HouseMap()));
}
BENCHMARK(BM_Clearance)->Unit(benchmark::kMicrosecond);

void BM_GeodesicField(benchmark::State& state) {
  GeodesicParams params;
  params.connectivity = GridConnectivity(state.range(0));
  const Image<uint8_t> traversable = TraversableCells(HouseMap(), params);
  const Eigen::Vector2i source = HouseMap().geometry().CellOf(SpreadPoints(1).front());
  for (auto _ : state)
    benchmark::DoNotOptimize(
        GeodesicField(traversable, HouseMap().geometry(), source, params.connectivity));
  state.counters["traversable"] =
      double(std::count(traversable.data.begin(), traversable.data.end(), uint8_t(1)));
}
BENCHMARK(BM_GeodesicField)->Arg(8)->Arg(16)->Unit(benchmark::kMillisecond);

void BM_DistanceMatrix30(benchmark::State& state) {
  ThreadLimit limit(int(state.range(0)));
  const std::vector<Eigen::Vector2f> points = SpreadPoints(30);
  for (auto _ : state) {
    GeodesicCache cache;  // cold: 30 fields and the traversable mask every time
    benchmark::DoNotOptimize(cache.DistanceMatrix(HouseMap(), points, GeodesicParams{}));
  }
}
BENCHMARK(BM_DistanceMatrix30)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace voxplan

BENCHMARK_MAIN();
