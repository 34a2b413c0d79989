#include "planning/planning_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "core/parallel.h"
#include "core/stopwatch.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace voxplan {

namespace {

constexpr uint16_t kRow10 = 0x3ff;  // a padded row: x = -1 .. 8 as bits 0 .. 9

// The 8 bits of x-row (y, z) in a block mask: word z, bits 8y .. 8y + 7.
inline uint16_t Row(const BlockMask& m, int y, int z) {
  return uint16_t((m[size_t(z)] >> (8 * y)) & 0xff);
}
// Bit x of every row (y, z) -> bit y of the result for one z: the x = const column.
inline uint16_t Column(const BlockMask& m, int x, int z) {
  uint16_t c = 0;
  for (int y = 0; y < kBlockSide; ++y) c |= uint16_t(((m[size_t(z)] >> (8 * y + x)) & 1u) << y);
  return c;
}

const BlockMask kEmptyMask{};

// Frontier and surface masks of one block from its free / occupied masks and those of its six
// face neighbours (nullptr: unallocated, all unobserved).
void ComputeInterfaces(PlanningBlock& pb, const PlanningBlock* const nb[6]) {
  // Padded rows [z + 1][y + 1], bits x + 1; only the 6 face layers of the padding are filled.
  uint16_t fr[10][10] = {}, oc[10][10] = {};
  for (int z = 0; z < kBlockSide; ++z)
    for (int y = 0; y < kBlockSide; ++y) {
      fr[z + 1][y + 1] = uint16_t(Row(pb.free, y, z) << 1);
      oc[z + 1][y + 1] = uint16_t(Row(pb.occupied, y, z) << 1);
    }
  // -x / +x neighbours: their x = 7 / x = 0 column into padded bit 0 / 9.
  for (int k = 0; k < 2; ++k) {
    const PlanningBlock* n = nb[k];
    if (!n) continue;
    const int x = k == 0 ? kBlockSide - 1 : 0, bit = k == 0 ? 0 : 9;
    for (int z = 0; z < kBlockSide; ++z) {
      const uint16_t cf = Column(n->free, x, z), co = Column(n->occupied, x, z);
      for (int y = 0; y < kBlockSide; ++y) {
        fr[z + 1][y + 1] |= uint16_t(((cf >> y) & 1u) << bit);
        oc[z + 1][y + 1] |= uint16_t(((co >> y) & 1u) << bit);
      }
    }
  }
  // -y / +y: their y = 7 / y = 0 rows into padded row 0 / 9.
  for (int k = 0; k < 2; ++k) {
    const PlanningBlock* n = nb[2 + k];
    if (!n) continue;
    const int y = k == 0 ? kBlockSide - 1 : 0, py = k == 0 ? 0 : 9;
    for (int z = 0; z < kBlockSide; ++z) {
      fr[z + 1][py] = uint16_t(Row(n->free, y, z) << 1);
      oc[z + 1][py] = uint16_t(Row(n->occupied, y, z) << 1);
    }
  }
  // -z / +z: their z = 7 / z = 0 slices into padded slice 0 / 9.
  for (int k = 0; k < 2; ++k) {
    const PlanningBlock* n = nb[4 + k];
    if (!n) continue;
    const int z = k == 0 ? kBlockSide - 1 : 0, pz = k == 0 ? 0 : 9;
    for (int y = 0; y < kBlockSide; ++y) {
      fr[pz][y + 1] = uint16_t(Row(n->free, y, z) << 1);
      oc[pz][y + 1] = uint16_t(Row(n->occupied, y, z) << 1);
    }
  }
  for (int z = 1; z <= kBlockSide; ++z) {
    uint64_t front = 0, surf = 0;
    for (int y = 1; y <= kBlockSide; ++y) {
      auto unobs = [&](int zz, int yy) { return uint16_t(~(fr[zz][yy] | oc[zz][yy]) & kRow10); };
      const uint16_t u = unobs(z, y);
      const uint16_t nb_unobs = uint16_t((u << 1) | (u >> 1) | unobs(z, y - 1) | unobs(z, y + 1) |
                                         unobs(z - 1, y) | unobs(z + 1, y));
      const uint16_t f = fr[z][y];
      const uint16_t nb_free =
          uint16_t((f << 1) | (f >> 1) | fr[z][y - 1] | fr[z][y + 1] | fr[z - 1][y] | fr[z + 1][y]);
      front |= uint64_t((fr[z][y] & nb_unobs) >> 1 & 0xff) << (8 * (y - 1));
      surf |= uint64_t((oc[z][y] & nb_free) >> 1 & 0xff) << (8 * (y - 1));
    }
    pb.frontier[size_t(z - 1)] = front;
    pb.surface[size_t(z - 1)] = surf;
  }
}

// Free / occupied masks of a block: observed when weight >= w_min, then occupied when
// tsdf <= t_max (ClassifyVoxel in fixed point). SSE2 (x86-64 baseline) does 16 voxels per step.
void ClassifyBlock(const TsdfBlock& tb, int32_t w_min, int32_t t_max, PlanningBlock& pb) {
#if defined(__SSE2__)
  // Unsigned weights compare as signed after flipping the top bit; thresholds outside the
  // 16-bit ranges mean all or nothing.
  const bool all_observed = w_min <= 0, none_observed = w_min > 65535;
  const bool all_occupied = t_max >= 32767, none_occupied = t_max < -32768;
  const __m128i flip = _mm_set1_epi16(int16_t(0x8000));
  const __m128i w_min_s = _mm_set1_epi16(int16_t(std::clamp(w_min, 0, 65535) ^ 0x8000));
  const __m128i t_max_v = _mm_set1_epi16(int16_t(std::clamp(t_max, -32768, 32767)));
  const __m128i ones = _mm_set1_epi16(-1);
  for (int w = 0; w < kBlockVoxels / 64; ++w) {
    uint64_t free = 0, occ = 0;
    for (int k = 0; k < 64; k += 16) {
      const int i = w * 64 + k;
      __m128i obs[2], occupied[2];
      for (int h = 0; h < 2; ++h) {
        const __m128i wv = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&tb.weight[i + 8 * h]));
        const __m128i tv = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&tb.tsdf[i + 8 * h]));
        obs[h] = all_observed ? ones
                 : none_observed
                     ? _mm_setzero_si128()
                     : _mm_xor_si128(_mm_cmplt_epi16(_mm_xor_si128(wv, flip), w_min_s), ones);
        occupied[h] = all_occupied    ? ones
                      : none_occupied ? _mm_setzero_si128()
                                      : _mm_xor_si128(_mm_cmpgt_epi16(tv, t_max_v), ones);
      }
      const __m128i o8 = _mm_packs_epi16(obs[0], obs[1]);
      const __m128i c8 = _mm_packs_epi16(occupied[0], occupied[1]);
      const uint64_t o = uint32_t(_mm_movemask_epi8(o8)), c = uint32_t(_mm_movemask_epi8(c8));
      free |= (o & ~c & 0xffff) << k;
      occ |= (o & c) << k;
    }
    pb.free[size_t(w)] = free;
    pb.occupied[size_t(w)] = occ;
  }
#else
  for (int w = 0; w < kBlockVoxels / 64; ++w) {
    uint64_t free = 0, occ = 0;
    for (int k = 0; k < 64; ++k) {
      const int i = w * 64 + k;
      const bool observed = int32_t(tb.weight[i]) >= w_min;
      const bool occupied = int32_t(tb.tsdf[i]) <= t_max;
      free |= uint64_t(observed && !occupied) << k;
      occ |= uint64_t(observed && occupied) << k;
    }
    pb.free[size_t(w)] = free;
    pb.occupied[size_t(w)] = occ;
  }
#endif
}

BlockIndex Neighbour(BlockIndex b, int k) {
  static constexpr int kOff[6][3] = {{-1, 0, 0}, {1, 0, 0},  {0, -1, 0},
                                     {0, 1, 0},  {0, 0, -1}, {0, 0, 1}};
  return {b.x + kOff[k][0], b.y + kOff[k][1], b.z + kOff[k][2]};
}

int Popcount(const BlockMask& m) {
  int n = 0;
  for (uint64_t w : m) n += __builtin_popcountll(w);
  return n;
}

}  // namespace

PlanningMap::PlanningMap(const TsdfVolume& volume, PlanningMapParams params)
    : volume_(&volume), params_(params) {
  if (!(params.state.min_weight > 0.f))
    throw std::invalid_argument("planning map min weight must be positive");
  trunc_vox_ = volume.trunc_m() / volume.voxel_size_m();
  // The fixed-point thresholds that reproduce ClassifyVoxel exactly (both tests are monotonic).
  min_weight_fixed_ = 65536;
  for (int32_t w = 0; w <= 65535; ++w)
    if (!(DecodeWeight(uint16_t(w)) < params.state.min_weight)) {
      min_weight_fixed_ = w;
      break;
    }
  max_occupied_tsdf_ = -32769;
  for (int32_t t = 32767; t >= -32768; --t)
    if (DecodeTsdf(int16_t(t)) * trunc_vox_ <= params.state.occupied_max_sdf_vox) {
      max_occupied_tsdf_ = t;
      break;
    }
}

PlanningUpdateStats PlanningMap::Update(const std::vector<BlockIndex>& touched) {
  return UpdateBlocks(touched);
}

PlanningUpdateStats PlanningMap::Rebuild() {
  blocks_.clear();
  return UpdateBlocks(volume_->SortedBlockIndices());
}

PlanningUpdateStats PlanningMap::UpdateBlocks(const std::vector<BlockIndex>& touched) {
  const Stopwatch clock;
  PlanningUpdateStats stats;
  stats.blocks_touched = touched.size();
  // Phase 1 (touched blocks): free / occupied masks from the TSDF. Sidecars are created or
  // dropped serially so the parallel part only writes into existing ones.
  std::vector<uint64_t> keys;
  keys.reserve(touched.size());
  for (BlockIndex b : touched)
    if (InPackRange(b)) keys.push_back(PackBlockIndex(b));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<std::pair<PlanningBlock*, const TsdfBlock*>> own;
  own.reserve(keys.size());
  bool changed = false;
  for (uint64_t key : keys) {
    const TsdfBlock* tb = volume_->FindBlock(UnpackBlockIndex(key));
    if (!tb) {
      changed |= blocks_.erase(key) > 0;
      labels_.erase(key);
      continue;
    }
    own.emplace_back(&blocks_[key], tb);
  }
  const int32_t w_min = min_weight_fixed_, t_max = max_occupied_tsdf_;
  ParallelFor(own.size(), 16, [&](size_t begin, size_t end) {
    for (size_t j = begin; j < end; ++j) ClassifyBlock(*own[j].second, w_min, t_max, *own[j].first);
  });

  // Phase 2 (touched blocks and their face neighbours): frontier and surface masks.
  std::vector<uint64_t> iface_keys;
  iface_keys.reserve(keys.size() * 3);
  for (uint64_t key : keys) {
    iface_keys.push_back(key);
    for (int k = 0; k < 6; ++k) {
      const BlockIndex n = Neighbour(UnpackBlockIndex(key), k);
      if (InPackRange(n)) iface_keys.push_back(PackBlockIndex(n));
    }
  }
  std::sort(iface_keys.begin(), iface_keys.end());
  iface_keys.erase(std::unique(iface_keys.begin(), iface_keys.end()), iface_keys.end());
  struct Job {
    PlanningBlock* block;
    const PlanningBlock* nb[6];
  };
  std::vector<Job> jobs;
  jobs.reserve(iface_keys.size());
  for (uint64_t key : iface_keys) {
    const auto it = blocks_.find(key);
    if (it == blocks_.end()) continue;
    Job job{&it->second, {}};
    const BlockIndex b = UnpackBlockIndex(key);
    for (int k = 0; k < 6; ++k) {
      const BlockIndex n = Neighbour(b, k);
      const auto nit = InPackRange(n) ? blocks_.find(PackBlockIndex(n)) : blocks_.end();
      job.nb[k] = nit == blocks_.end() ? nullptr : &nit->second;
    }
    jobs.push_back(job);
  }
  const uint64_t revision = revision_ + 1;
  ParallelFor(jobs.size(), 32, [&](size_t begin, size_t end) {
    for (size_t j = begin; j < end; ++j) {
      ComputeInterfaces(*jobs[j].block, jobs[j].nb);
      jobs[j].block->revision = revision;
    }
  });
  if (changed || !jobs.empty()) revision_ = revision;
  stats.blocks_updated = jobs.size();
  stats.update_ms = clock.ElapsedMs();
  return stats;
}

VoxelState PlanningMap::StateAt(GlobalVoxelIndex g) const {
  const TsdfBlock* b = volume_->FindBlock(BlockOf(g));
  if (!b) return VoxelState::kUnobserved;
  const int i = LinearIndex(LocalOf(g));
  return ClassifyVoxel(b->tsdf[i], b->weight[i], trunc_vox_, params_.state);
}

VoxelState PlanningMap::StateAt(const Eigen::Vector3f& p_W) const {
  return StateAt(VoxelAt(p_W, volume_->voxel_size_m()));
}

std::vector<VoxelState> PlanningMap::StatesAt(const std::vector<Eigen::Vector3f>& points_W) const {
  std::vector<VoxelState> states(points_W.size());
  ParallelFor(points_W.size(), 1024, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) states[i] = StateAt(points_W[i]);
  });
  return states;
}

RayCastResult PlanningMap::CastRay(const Eigen::Vector3f& from_W, const Eigen::Vector3f& to_W,
                                   bool stop_at_unobserved) const {
  // Amanatides & Woo in voxel units, visiting every voxel the segment passes through.
  const float s = volume_->voxel_size_m();
  const Eigen::Vector3f a = from_W / s, d = (to_W - from_W) / s;
  const float length_m = (to_W - from_W).norm();
  int cell[3] = {FloorToInt(a.x()), FloorToInt(a.y()), FloorToInt(a.z())};
  const Eigen::Vector3f bv = to_W / s;
  const int last[3] = {FloorToInt(bv.x()), FloorToInt(bv.y()), FloorToInt(bv.z())};
  int step[3];
  float t_max[3], t_delta[3];
  for (int k = 0; k < 3; ++k) {
    step[k] = d[k] > 0 ? 1 : (d[k] < 0 ? -1 : 0);
    if (step[k] == 0) {
      t_max[k] = t_delta[k] = std::numeric_limits<float>::infinity();
    } else {
      t_max[k] = (float(cell[k] + (step[k] > 0 ? 1 : 0)) - a[k]) / d[k];
      t_delta[k] = float(step[k]) / d[k];
    }
  }
  const int max_steps =
      std::abs(last[0] - cell[0]) + std::abs(last[1] - cell[1]) + std::abs(last[2] - cell[2]) + 1;
  float t_entry = 0.f;
  BlockIndex cached_index{kMaxBlockCoord + 1, 0, 0};
  const TsdfBlock* cached = nullptr;
  for (int n = 0; n < max_steps; ++n) {
    const GlobalVoxelIndex g{cell[0], cell[1], cell[2]};
    const BlockIndex bi = BlockOf(g);
    if (!(bi == cached_index)) {
      cached_index = bi;
      cached = volume_->FindBlock(bi);
    }
    VoxelState state = VoxelState::kUnobserved;
    if (cached) {
      const int i = LinearIndex(LocalOf(g));
      state = ClassifyVoxel(cached->tsdf[i], cached->weight[i], trunc_vox_, params_.state);
    }
    if (state == VoxelState::kOccupied ||
        (stop_at_unobserved && state == VoxelState::kUnobserved)) {
      return {state == VoxelState::kOccupied ? RayHit::kOccupied : RayHit::kUnobserved, g,
              std::min(t_entry, 1.0f) * length_m};
    }
    if (cell[0] == last[0] && cell[1] == last[1] && cell[2] == last[2]) break;
    const int k =
        (t_max[0] < t_max[1]) ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    t_entry = t_max[k];
    cell[k] += step[k];
    t_max[k] += t_delta[k];
  }
  return {};
}

const PlanningBlock* PlanningMap::FindBlock(BlockIndex b) const {
  if (!InPackRange(b)) return nullptr;
  const auto it = blocks_.find(PackBlockIndex(b));
  return it == blocks_.end() ? nullptr : &it->second;
}

size_t PlanningMap::CountFrontier() const {
  size_t n = 0;
  for (const auto& [key, pb] : blocks_) n += size_t(Popcount(pb.frontier));
  return n;
}

size_t PlanningMap::CountSurface() const {
  size_t n = 0;
  for (const auto& [key, pb] : blocks_) n += size_t(Popcount(pb.surface));
  return n;
}

std::vector<GlobalVoxelIndex> PlanningMap::FrontierVoxels() const {
  std::vector<GlobalVoxelIndex> out;
  for (const auto& [key, pb] : blocks_) {
    const BlockIndex b = UnpackBlockIndex(key);
    ForEachBit(pb.frontier, [&](int i) { out.push_back(GlobalOf(b, VoxelOfLinear(i))); });
  }
  std::sort(out.begin(), out.end());
  return out;
}

PlanningMap::Neighbourhood PlanningMap::NeighbourhoodOf(BlockIndex b) const {
  Neighbourhood n;
  n.self = volume_->FindBlock(b);
  for (int k = 0; k < 6; ++k) n.faces[k] = volume_->FindBlock(Neighbour(b, k));
  return n;
}

Eigen::Vector3f PlanningMap::NormalAt(GlobalVoxelIndex g) const {
  return NormalIn(NeighbourhoodOf(BlockOf(g)), LocalOf(g));
}

Eigen::Vector3f PlanningMap::NormalIn(const Neighbourhood& n, VoxelIndex v) const {
  // TSDF at a voxel, when observed; central differences, one-sided next to unobserved voxels.
  // A difference steps along one axis at a time, so only face neighbours are ever read.
  auto tsdf = [&](int x, int y, int z) -> std::optional<float> {
    const TsdfBlock* b = n.self;
    if (x < 0) {
      b = n.faces[0], x += kBlockSide;
    } else if (x >= kBlockSide) {
      b = n.faces[1], x -= kBlockSide;
    } else if (y < 0) {
      b = n.faces[2], y += kBlockSide;
    } else if (y >= kBlockSide) {
      b = n.faces[3], y -= kBlockSide;
    } else if (z < 0) {
      b = n.faces[4], z += kBlockSide;
    } else if (z >= kBlockSide) {
      b = n.faces[5], z -= kBlockSide;
    }
    if (!b) return std::nullopt;
    const int i = LinearIndex(x, y, z);
    if (!Observed(*b, i)) return std::nullopt;
    return DecodeTsdf(b->tsdf[i]);
  };
  const std::optional<float> c = tsdf(v.x, v.y, v.z);
  Eigen::Vector3f grad = Eigen::Vector3f::Zero();
  for (int k = 0; k < 3; ++k) {
    const int dx = k == 0, dy = k == 1, dz = k == 2;
    const std::optional<float> m = tsdf(v.x - dx, v.y - dy, v.z - dz);
    const std::optional<float> p = tsdf(v.x + dx, v.y + dy, v.z + dz);
    if (m && p) {
      grad[k] = 0.5f * (*p - *m);
    } else if (p && c) {
      grad[k] = *p - *c;
    } else if (m && c) {
      grad[k] = *c - *m;
    }
  }
  const float norm = grad.norm();
  return norm > 0.f ? Eigen::Vector3f(grad / norm) : Eigen::Vector3f::Zero();
}

std::vector<MapSurfaceVoxel> PlanningMap::SurfaceVoxels() const {
  // Blocks holding surface voxels, in key order: the output's order.
  std::vector<std::pair<uint64_t, const PlanningBlock*>> blocks;
  for (const auto& [key, pb] : blocks_)
    if (Popcount(pb.surface) > 0) blocks.emplace_back(key, &pb);
  std::sort(blocks.begin(), blocks.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  // Entries of blocks still holding surface voxels carry over (a merge of two key-sorted lists);
  // stale ones are recomputed.
  std::vector<SurfaceCacheEntry> next(blocks.size());
  std::vector<size_t> stale;
  size_t c = 0;
  for (size_t k = 0; k < blocks.size(); ++k) {
    const auto& [key, pb] = blocks[k];
    while (c < surface_cache_.size() && surface_cache_[c].key < key) ++c;
    if (c < surface_cache_.size() && surface_cache_[c].key == key &&
        surface_cache_[c].revision == pb->revision) {
      next[k] = std::move(surface_cache_[c]);
    } else {
      next[k].key = key;
      next[k].revision = pb->revision;
      stale.push_back(k);
    }
  }
  const float s = volume_->voxel_size_m();
  ParallelFor(stale.size(), 8, [&](size_t begin, size_t end) {
    for (size_t j = begin; j < end; ++j) {
      const auto& [key, pb] = blocks[stale[j]];
      const BlockIndex b = UnpackBlockIndex(key);
      const Neighbourhood n = NeighbourhoodOf(b);
      const TsdfBlock* tb = n.self;
      if (!tb) continue;
      std::vector<MapSurfaceVoxel>& voxels = next[stale[j]].voxels;
      voxels.reserve(size_t(Popcount(pb->surface)));
      ForEachBit(pb->surface, [&](int i) {
        MapSurfaceVoxel v;
        v.index = GlobalOf(b, VoxelOfLinear(i));
        v.center_W = VoxelCenter(v.index, s);
        v.normal_W = NormalIn(n, VoxelOfLinear(i));
        v.weight = DecodeWeight(tb->weight[i]);
        v.uncertainty = 1.0f / v.weight;
        voxels.push_back(v);
      });
    }
  });
  surface_cache_ = std::move(next);
  // Each block into its own range of the output, in parallel.
  std::vector<size_t> first(surface_cache_.size() + 1, 0);
  for (size_t k = 0; k < surface_cache_.size(); ++k)
    first[k + 1] = first[k] + surface_cache_[k].voxels.size();
  std::vector<MapSurfaceVoxel> out(first.back());
  ParallelFor(surface_cache_.size(), 64, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      const std::vector<MapSurfaceVoxel>& voxels = surface_cache_[k].voxels;
      MapSurfaceVoxel* dst = out.data() + first[k];
      std::copy(voxels.begin(), voxels.end(), dst);
      // Labels change without a block update (FuseLabels), so they are read here, not cached.
      const auto lb = labels_.find(surface_cache_[k].key);
      if (lb == labels_.end()) continue;
      for (size_t i = 0; i < voxels.size(); ++i)
        dst[i].label = FusedLabel(*lb->second, LinearIndex(LocalOf(dst[i].index)));
    }
  });
  return out;
}

}  // namespace voxplan
