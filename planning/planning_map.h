#pragma once
// Maps a planner reads, derived from a TSDF volume fused with free-space carving (usually at a
// coarse planning resolution such as 5 cm): per-voxel state, frontier and surface voxels as
// per-block bit masks, and an object map of instance labels fused per voxel. Everything is a
// per-block sidecar keyed like the TSDF blocks and updated only for the blocks a frame touched
// (and their face neighbours, whose border voxels see the change).
//
// Definitions (6-connectivity throughout; a voxel of an unallocated block is unobserved):
//  - state: ClassifyVoxel (core/voxel_state.h), the one rule.
//  - frontier voxel: an observed free voxel with at least one unobserved face neighbour.
//  - surface voxel: an occupied voxel with at least one free face neighbour, i.e. the
//    occupied side of an observed free/occupied interface. Its uncertainty is 1 / TSDF weight
//    (Dong et al. 2019, §3.2: the fusion weight measures scanning quality, as it grows with
//    the number of observations and falls with distance when depth weighting is on); its
//    normal is the normalised TSDF gradient (central differences, one-sided at unobserved
//    neighbours), pointing into free space.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"
#include "core/volume.h"
#include "core/voxel_state.h"

namespace voxplan {

// One bit per voxel of a block, bit LinearIndex(v) % 64 of word LinearIndex(v) / 64.
using BlockMask = std::array<uint64_t, kBlockVoxels / 64>;
inline bool TestBit(const BlockMask& m, int i) { return (m[size_t(i) >> 6] >> (i & 63)) & 1u; }
template <typename F>  // f(linear index) for every set bit, ascending
inline void ForEachBit(const BlockMask& m, F&& f) {
  for (size_t w = 0; w < m.size(); ++w)
    for (uint64_t bits = m[w]; bits != 0; bits &= bits - 1) f(int(w * 64) + __builtin_ctzll(bits));
}

struct PlanningBlock {
  BlockMask occupied{}, free{};  // unobserved: neither
  BlockMask frontier{}, surface{};
  uint64_t revision = 0;  // map revision that last recomputed this block
};

// Instance labels fused per voxel: a few (label, count) candidates, space-saving style: an
// unseen label takes a free slot, else it decrements the weakest candidate and takes its slot
// once that reaches zero. The voxel's label is the candidate with the highest count (ties: the
// smaller label). Label 0 means "no label" and is never stored.
inline constexpr int kLabelCandidates = 4;
struct LabelBlock {
  uint32_t label[kBlockVoxels][kLabelCandidates];
  uint16_t count[kBlockVoxels][kLabelCandidates];
};
static_assert(std::is_trivially_copyable_v<LabelBlock>);
// The label of voxel i (linear index): its strongest candidate, 0 when it has none.
uint32_t FusedLabel(const LabelBlock& lb, int i);

struct PlanningMapParams {
  VoxelStateParams state;
  // A pixel's label goes to the voxels whose centre lies within this many voxels of the
  // observed surface along the pixel's ray.
  float label_band_vox = 0.5f;
};

// Not SurfaceVoxel: plugins/host/planner_world.h has the planner's, and explore uses both.
struct MapSurfaceVoxel {
  GlobalVoxelIndex index;
  Eigen::Vector3f center_W;
  Eigen::Vector3f normal_W;  // unit; zero when the gradient vanishes
  float weight = 0.f;
  float uncertainty = 0.f;  // 1 / weight
  uint32_t label = 0;       // fused instance label, 0: none
};

struct InstanceRecord {
  uint32_t id = 0;
  std::string class_name;  // empty when unknown
  size_t voxel_count = 0;  // occupied voxels whose fused label is this one
  Eigen::Vector3f bbox_min_W = Eigen::Vector3f::Zero(), bbox_max_W = Eigen::Vector3f::Zero();
  // The instance's surface voxels (centre, outward normal), sorted by voxel index.
  std::vector<Eigen::Vector3f> surface_points_W, surface_normals_W;
};

enum class RayHit { kNone, kOccupied, kUnobserved };
struct RayCastResult {
  RayHit hit = RayHit::kNone;  // kNone: free all the way to the segment's end
  GlobalVoxelIndex voxel;      // the voxel that stopped the ray
  float distance_m = 0.f;      // along the segment to where the ray entered that voxel
};

struct PlanningUpdateStats {
  size_t blocks_touched = 0;  // blocks the caller reported
  size_t blocks_updated = 0;  // touched plus their allocated face neighbours
  double update_ms = 0.0;
};

class PlanningMap {
 public:
  // Derived from `volume`, which must outlive the map. Throws std::invalid_argument for a
  // non-positive min weight.
  explicit PlanningMap(const TsdfVolume& volume, PlanningMapParams params = {});

  const PlanningMapParams& params() const { return params_; }
  const TsdfVolume& volume() const { return *volume_; }
  // Bumped by every Update / Rebuild / FuseLabels call that changed something.
  uint64_t revision() const { return revision_; }

  // Recomputes the sidecars of `touched` (any order, duplicates allowed) and of their face
  // neighbours; a block gone from the volume drops its sidecar. Every change to the volume must
  // be reported here (IntegrateFrame's touched_blocks does); otherwise call Rebuild.
  PlanningUpdateStats Update(const std::vector<BlockIndex>& touched);
  // From scratch: every block of the volume.
  PlanningUpdateStats Rebuild();

  // Label fusion for one frame: `labels` (0 = none) registered with `depth` (metres, 0 =
  // invalid); only voxels of `blocks` (the frame's touched blocks) are visited. InvalidArgument
  // when sizes disagree with the camera.
  Status FuseLabels(const DepthImage& depth, const LabelImage& labels, const PinholeCamera& camera,
                    const Pose3f& T_W_C, const std::vector<BlockIndex>& blocks, float min_depth_m,
                    float max_depth_m);
  void SetInstanceClass(uint32_t id, std::string class_name);

  // State queries read the TSDF through ClassifyVoxel, so they are current even between
  // updates.
  VoxelState StateAt(GlobalVoxelIndex g) const;
  VoxelState StateAt(const Eigen::Vector3f& p_W) const;
  std::vector<VoxelState> StatesAt(const std::vector<Eigen::Vector3f>& points_W) const;
  // Walks the voxels from `from_W` to `to_W`; stops at the first occupied voxel, or (with
  // stop_at_unobserved) the first unobserved one.
  RayCastResult CastRay(const Eigen::Vector3f& from_W, const Eigen::Vector3f& to_W,
                        bool stop_at_unobserved = true) const;

  // Sorted by voxel index (z, y, x).
  std::vector<GlobalVoxelIndex> FrontierVoxels() const;
  // Block by block (blocks by index, voxels by linear index in the block). Blocks unchanged
  // since the last call come from a cache (a planner asks every call, the map changes in a few
  // places between calls), so calls must not overlap.
  std::vector<MapSurfaceVoxel> SurfaceVoxels() const;
  // The fused label of a voxel (0: none) and its candidates.
  uint32_t LabelAt(GlobalVoxelIndex g) const;
  std::vector<std::pair<uint32_t, uint16_t>> LabelCandidatesAt(GlobalVoxelIndex g) const;
  // One record per fused label, sorted by id.
  std::vector<InstanceRecord> Instances() const;

  const PlanningBlock* FindBlock(BlockIndex b) const;
  size_t num_blocks() const { return blocks_.size(); }
  size_t CountFrontier() const;
  size_t CountSurface() const;

 private:
  PlanningUpdateStats UpdateBlocks(const std::vector<BlockIndex>& touched);
  bool Observed(const TsdfBlock& b, int i) const { return b.weight[i] >= min_weight_fixed_; }
  // A block and its six face neighbours (null where unallocated), in Neighbour() order.
  struct Neighbourhood {
    const TsdfBlock* self = nullptr;
    const TsdfBlock* faces[6] = {};
  };
  Neighbourhood NeighbourhoodOf(BlockIndex b) const;
  Eigen::Vector3f NormalAt(GlobalVoxelIndex g) const;
  Eigen::Vector3f NormalIn(const Neighbourhood& n, VoxelIndex v) const;

  const TsdfVolume* volume_;
  PlanningMapParams params_;
  float trunc_vox_;
  // ClassifyVoxel's rule in fixed point: weight >= min_weight_fixed_ is observed, then
  // tsdf <= max_occupied_tsdf_ is occupied.
  int32_t min_weight_fixed_;
  int32_t max_occupied_tsdf_;
  uint64_t revision_ = 0;
  std::unordered_map<uint64_t, PlanningBlock> blocks_;  // PackBlockIndex -> sidecar
  std::unordered_map<uint64_t, std::unique_ptr<LabelBlock>> labels_;
  std::unordered_map<uint32_t, std::string> classes_;
  // SurfaceVoxels per block, valid while the block's revision is unchanged: a block's surface
  // voxels and their normals depend on its TSDF and its face neighbours', and UpdateBlocks
  // stamps a block whenever it or a face neighbour was touched. Sorted by key.
  struct SurfaceCacheEntry {
    uint64_t key = 0;  // PackBlockIndex
    uint64_t revision = 0;
    std::vector<MapSurfaceVoxel> voxels;
  };
  mutable std::vector<SurfaceCacheEntry> surface_cache_;
};

}  // namespace voxplan
