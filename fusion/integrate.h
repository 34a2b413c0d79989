#pragma once
// Projective TSDF integration of one RGB-D frame, in two lock-free phases: collect the blocks of
// the truncation band (deduplicated, sorted) and allocate them serially, then update each block
// in parallel with the scalar reference kernel or the SIMD kernel (same contract, bit-identical).
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"
#include "core/shard.h"
#include "core/status.h"
#include "core/volume.h"

namespace voxplan {

enum class Weighting {
  kConstant,        // every observation weighs 1
  kDepthDependent,  // 1 / z^2 (z in metres), as the sensor's axial noise grows with depth
};
enum class Kernel { kAuto, kScalar, kSimd };

// How the ranks of a split map pool the blocks each found in its share of a frame's band
// (distributed/sharded_fuse.cpp). Collective: every rank calls it once per IntegrateFrame, in
// the same order; it returns the sorted, duplicate-free blocks of all ranks' finds this rank owns.
class BandExchange {
 public:
  virtual ~BandExchange() = default;
  virtual Result<std::vector<BlockIndex>> Exchange(const std::vector<BlockIndex>& found) = 0;
};

struct IntegrateParams {
  float min_depth_m = 0.1f;
  float max_depth_m = 3.0f;
  float max_weight = 64.0f;  // weight cap: older observations fade once reached
  Weighting weighting = Weighting::kConstant;
  Kernel kernel = Kernel::kAuto;
  bool integrate_color = true;
  // Also allocate (and so update) the blocks in front of the truncation band, from min depth on,
  // so free space is carved: voxels there get TSDF +1 and weight, which planning maps need.
  bool carve_free_space = false;
  // Carving replaces the per-pixel band walk with rays through the corners of square pixel
  // tiles (out to the tiles' farthest depth plus the truncation), tiles small enough that
  // neighbouring rays are at most this many blocks apart at max depth.
  float carve_ray_spacing_blocks = 0.25f;
  // With carving: a (finite) reading beyond max_depth_m is not fused as a surface, but the
  // free space it shows in front of max_depth_m is, as a laser's max-range beam clears
  // (OctoMap's maxrange). Real sensors return such readings; their noise keeps them out of the
  // model, so they update only voxels still unobserved or free, never a fused surface.
  bool clear_beyond_max_depth = false;
  // A map split over ranks (distributed/): only the blocks this rank owns are allocated and
  // updated. Without `band_exchange` every rank walks the frame's whole band to find them; with
  // it, each walks its share of the image's rows and the exchange hands it every rank's finds
  // that it owns (the same blocks, found once).
  ShardSpec shard;
  BandExchange* band_exchange = nullptr;

  // Depth range within [0, bounds::kDepthMaxM] with min < max, max weight in (0, kMaxWeight],
  // a positive carve ray spacing; InvalidArgument naming the value and the range otherwise.
  Status Validate() const;
};

struct IntegrateStats {
  size_t blocks_in_band = 0;  // blocks updated this frame (band, plus carved ones when carving)
  size_t blocks_allocated = 0;
  // New blocks the volume's memory budget refused: their voxels were not updated this frame.
  size_t blocks_refused = 0;
  size_t valid_pixels = 0;
  // Finding the band's blocks: the whole band on every rank of a split map, or with a band
  // exchange each rank's share, then the exchange's time.
  double collect_ms = 0.0;
  double exchange_ms = 0.0;
  double allocate_ms = 0.0;  // collecting, looking up and allocating them
  double update_ms = 0.0;
  // Every block this frame updated, sorted (BlockIndex order) without duplicates, so maps
  // derived from the volume can update incrementally.
  std::vector<BlockIndex> touched_blocks;
};

// depth: metres, 0 = invalid; color: empty or the same size as depth. Refuses (InvalidArgument)
// invalid params (theirs and the volume's Validate()), intrinsics outside core/bounds.h's
// ranges, images that do not match the camera and non-finite poses. Blocks past the volume's
// memory budget are left out (IntegrateStats::blocks_refused).
Result<IntegrateStats> IntegrateFrame(const DepthImage& depth, const ColorImage& color,
                                      const PinholeCamera& camera, const Pose3f& T_W_C,
                                      const IntegrateParams& params, TsdfVolume& volume);

// With params.shard, only the blocks it owns are updated (the band functions below ignore it).
// Blocks within the truncation band of every valid pixel, sorted and without duplicates.
std::vector<BlockIndex> BlocksInTruncationBand(const DepthImage& depth, const PinholeCamera& camera,
                                               const Pose3f& T_W_C, const IntegrateParams& params,
                                               const VolumeParams& volume_params);

// The blocks IntegrateFrame updates (sorted, without duplicates): BlocksInTruncationBand, or
// with params.carve_free_space the blocks the carving rays cross from min depth through the
// band.
std::vector<BlockIndex> BlocksToUpdate(const DepthImage& depth, const PinholeCamera& camera,
                                       const Pose3f& T_W_C, const IntegrateParams& params,
                                       const VolumeParams& volume_params);

// True when this CPU runs the SIMD kernel (AVX2); the one place the SIMD path is chosen.
bool SimdKernelAvailable();
Kernel ResolveKernel(Kernel requested);
const char* KernelName(Kernel kernel);

}  // namespace voxplan
