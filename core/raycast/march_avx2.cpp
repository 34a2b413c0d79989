// All of the ray caster's AVX2 code, compiled for AVX2 by function attributes and chosen at run
// time (RaycastSimdAvailable): the packet march, whose lanes take the scalar march's samples
// with the same float operations in the same order (identical images), and the AVX2 builds of
// the range image's splatting. Its conditionals are all here; without AVX2, the scalar code.
#include <Eigen/Core>
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "core/raycast/march.h"
#include "core/raycast/range_image.h"

// Packets of 8 rays marched in AVX2 lanes, chosen at run time where the CPU has AVX2 (the
// define: build without them).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(VOXPLAN_RAYCAST_NO_AVX2)
#include <immintrin.h>
#define VOXPLAN_RAYCAST_AVX2 1
#define VOXPLAN_TARGET_AVX2 __attribute__((target("avx2")))
#else
#define VOXPLAN_RAYCAST_AVX2 0
#endif

namespace voxplan::raycast_detail {

#if VOXPLAN_RAYCAST_AVX2
namespace {

constexpr int kPacket = 8;   // rays an AVX2 packet marches
constexpr int kPackets = 2;  // packets a worker marches side by side (overlaps latencies)
constexpr int kPacketLanes = kPacket * kPackets;

// Small AVX2 helpers of the packet march (functions, since lambdas would not get its target).
namespace avx2 {
VOXPLAN_TARGET_AVX2 inline __m256i Load(const void* p) {
  return _mm256_loadu_si256(static_cast<const __m256i*>(p));
}
VOXPLAN_TARGET_AVX2 inline __m256 LoadF(const float* p) { return _mm256_loadu_ps(p); }
VOXPLAN_TARGET_AVX2 inline __m256 Set(float x) { return _mm256_set1_ps(x); }
// DecodeTsdf of each lane.
VOXPLAN_TARGET_AVX2 inline __m256 Decode(__m256i t) {
  return _mm256_mul_ps(_mm256_cvtepi32_ps(t), _mm256_set1_ps(1.0f / kTsdfScale));
}
// A trilinear weight as the SSE2 kernels form it: f where `upper`, 1 - f otherwise, each as
// a + b f (the same roundings).
VOXPLAN_TARGET_AVX2 inline __m256 Lerp(bool upper, __m256 f) {
  return _mm256_add_ps(_mm256_set1_ps(upper ? 0.f : 1.f),
                       _mm256_mul_ps(_mm256_set1_ps(upper ? 1.f : -1.f), f));
}
// (v0 + v1) + (v2 + v3): a transposed SSE2 horizontal sum, lane by lane.
VOXPLAN_TARGET_AVX2 inline __m256 Sum4(const __m256 v[4]) {
  return _mm256_add_ps(_mm256_add_ps(v[0], v[1]), _mm256_add_ps(v[2], v[3]));
}
VOXPLAN_TARGET_AVX2 inline void Store(void* p, __m256i v) {
  _mm256_storeu_si256(static_cast<__m256i*>(p), v);
}
VOXPLAN_TARGET_AVX2 inline __m256i AndNot(__m256i a, __m256i b) {  // ~a & b
  return _mm256_andnot_si256(a, b);
}
VOXPLAN_TARGET_AVX2 inline __m256 Blend(__m256 no, __m256 yes, __m256i mask) {
  return _mm256_blendv_ps(no, yes, _mm256_castsi256_ps(mask));
}
// floor(p) as Sampler::Gather and Step compute it: truncate, minus one where that rounded up.
VOXPLAN_TARGET_AVX2 inline __m256i Floor(__m256 p) {
  const __m256i truncated = _mm256_cvttps_epi32(p);
  return _mm256_add_epi32(
      truncated, _mm256_castps_si256(_mm256_cmp_ps(p, _mm256_cvtepi32_ps(truncated), _CMP_LT_OQ)));
}
// The zero of the line through (z_a, f_a) and (z_b, f_b), as Refine and Bracket compute it.
VOXPLAN_TARGET_AVX2 inline __m256 Secant(__m256 z_a, __m256 z_b, __m256 f_a, __m256 f_b) {
  return _mm256_add_ps(
      z_a, _mm256_div_ps(_mm256_mul_ps(_mm256_sub_ps(z_b, z_a), f_a), _mm256_sub_ps(f_a, f_b)));
}
// The linear index inside its block of each lane's voxel g.
VOXPLAN_TARGET_AVX2 inline __m256i LinearIndex(const __m256i g[3]) {
  const __m256i mask = _mm256_set1_epi32(kBlockMask);
  return _mm256_add_epi32(
      _mm256_and_si256(g[0], mask),
      _mm256_add_epi32(_mm256_slli_epi32(_mm256_and_si256(g[1], mask), kBlockShift),
                       _mm256_slli_epi32(_mm256_and_si256(g[2], mask), 2 * kBlockShift)));
}
}  // namespace avx2

// The packet march (MarchPackets) and its refinement of crossings in lanes (RefineCrossings,
// BracketCrossings); crossings it cannot refine in lanes go to RayCaster::Cross.
class PacketCaster : public RayCaster {
 public:
  using RayCaster::RayCaster;

  void March(const RayTask* tasks, size_t num_tasks, const BatchWriter& write) override {
    MarchPackets(tasks, num_tasks, write);
  }

 private:
  // The same march over packets of kPacket rays in AVX2 lanes: every lane takes the sample Step
  // would take, with the same float operations in the same order (no FMA: the caster's files are
  // built with -ffp-contract=off), so the images are identical to MarchInterleaved's. The steps
  // have no per-ray branch; block lookups and new rays are handled lane by lane. A lane that meets
  // a crossing hands it on and takes the next ray: crossings are refined kPacket at a time
  // (RefineCrossings). A worker marches kPackets packets in turn, so that one packet's loads
  // and lookups overlap another's.
  VOXPLAN_TARGET_AVX2 void MarchPackets(const RayTask* tasks, size_t num_tasks,
                                        const BatchWriter& write) {
    struct alignas(32) Lanes {
      float z[kPacketLanes], z_end[kPacketLanes], voxel_z[kPacketLanes], step_z[kPacketLanes],
          prev_z[kPacketLanes];
      float dir_vox[3][kPacketLanes], dir_W[3][kPacketLanes];
      int32_t block_index[3][kPacketLanes];
      int32_t prev_tsdf[kPacketLanes], tsdf[kPacketLanes];
      int32_t live[kPacketLanes], has_block[kPacketLanes], have_prev[kPacketLanes],
          met[kPacketLanes];  // 0 or -1
      const TsdfBlock* block[kPacketLanes];
      size_t pixel[kPacketLanes];
      float z_skipped[kPacketLanes], z_begin[kPacketLanes];
    } lanes;
    std::memset(&lanes, 0, sizeof(lanes));
    for (auto& block : lanes.block) block = &kNoBlock;
    for (auto& x : lanes.block_index[0]) x = kMaxBlockCoord + 1;  // out of range: no block
    // Starts lane l's march of the ray through `pixel` from z_begin to z_end. The lane keeps
    // its last block (index and pointer): the next ray, a nearby pixel's, often starts in it.
    auto start = [&](int l, const Eigen::Vector3f& dir_W, float z_begin, float z_end,
                     float z_skipped, size_t pixel) {
      Ray ray;
      Start(dir_W, z_begin, z_end, &ray);
      const Eigen::Vector3f dir_vox = dir_W * sampler_.inv_voxel();  // as Start computes it
      lanes.z[l] = ray.z, lanes.z_end[l] = ray.z_end;
      lanes.voxel_z[l] = ray.voxel_z, lanes.step_z[l] = ray.step_scale_z;
      for (int a = 0; a < 3; ++a) {
        lanes.dir_vox[a][l] = dir_vox[a];
        lanes.dir_W[a][l] = dir_W[a];
      }
      lanes.live[l] = -1, lanes.have_prev[l] = 0, lanes.met[l] = 0;
      lanes.pixel[l] = pixel;
      lanes.z_skipped[l] = z_skipped, lanes.z_begin[l] = z_begin;
    };
    // Crossings wait for refinement in `crossings`; a ray whose crossing had no zero resumes
    // its march from there once a lane is free, as if it had never stopped.
    Crossings crossings;
    std::vector<Resume>& resumes = resumes_;
    resumes.clear();
    size_t next = 0;
    auto start_next = [&](int l) {
      if (next < num_tasks) {
        const RayTask& task = tasks[next++];
        start(l, Direction(task), task.z_begin, task.z_end, task.z_skipped, task.pixel);
        return true;
      }
      if (!resumes.empty()) {
        const Resume r = resumes.back();
        resumes.pop_back();
        start(l, r.dir_W, r.z_b, r.z_end, -1.f, r.pixel);
        // The state Step leaves after a crossing without a zero: the negative sample is the
        // previous one, one step on.
        lanes.have_prev[l] = -1, lanes.met[l] = -1;
        lanes.prev_z[l] = r.z_b;
        lanes.prev_tsdf[l] = r.tsdf_b;
        lanes.z[l] = r.z_b + std::max(float(r.tsdf_b) * lanes.step_z[l], lanes.voxel_z[l]);
        return true;
      }
      lanes.live[l] = 0;
      return false;
    };
    // Results of a batch: written, or resumed where the crossing had no zero; lanes in `skip`
    // are not done yet.
    auto handle = [&](const Crossings& batch, unsigned found, const RayResult* results,
                      unsigned skip) {
      for (int j = 0; j < batch.count; ++j) {
        if ((skip >> j) & 1) continue;
        const Eigen::Vector3f dir_W(batch.dir_W[0][j], batch.dir_W[1][j], batch.dir_W[2][j]);
        if ((found >> j) & 1)
          write(batch.pixel[j], results[j], dir_W);
        else
          resumes.push_back(
              {dir_W, batch.z_b[j], batch.z_end[j], int16_t(batch.tsdf_b[j]), batch.pixel[j]});
      }
    };
    // Crossings whose Newton steps left their path wait in `brackets` for the bracket, which
    // is refined kPacket at a time too.
    Crossings brackets;
    auto refine_brackets = [&] {
      RayResult results[kPacket];
      handle(brackets, BracketCrossings(brackets, results), results, 0);
      brackets.count = 0;
    };
    auto refine = [&] {
      RayResult results[kPacket];
      unsigned deferred = 0;
      const unsigned found = RefineCrossings(crossings, results, &deferred);
      handle(crossings, found, results, deferred);
      for (; deferred; deferred &= deferred - 1) {
        brackets.Append(crossings, std::countr_zero(deferred));
        if (brackets.count == kPacket) refine_brackets();
      }
      crossings.count = 0;
    };
    // Lane l's ray ended with `result`: march the range it skipped when it met nothing observed
    // (as MarchInterleaved does), else write it and start the next ray. False when the lane is
    // left without a ray.
    auto finish = [&](int l, const Eigen::Vector3f& dir_W, const RayResult& result) {
      if (result.status == RayStatus::kUnobserved && lanes.z_skipped[l] >= 0.f) {
        start(l, dir_W, lanes.z_skipped[l], lanes.z_begin[l], -1.f, lanes.pixel[l]);
        return true;
      }
      write(lanes.pixel[l], result, dir_W);
      return start_next(l);
    };
    int num_live = 0;
    for (int l = 0; l < kPacketLanes; ++l) num_live += start_next(l);

    const __m256 origin_vox[3] = {_mm256_set1_ps(origin_vox_.x()), _mm256_set1_ps(origin_vox_.y()),
                                  _mm256_set1_ps(origin_vox_.z())};
    const __m256 origin_W[3] = {_mm256_set1_ps(origin_W_.x()), _mm256_set1_ps(origin_W_.y()),
                                _mm256_set1_ps(origin_W_.z())};
    const __m256 block_m = _mm256_set1_ps(sampler_.voxel_m() * kBlockSide);
    const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
    const __m256i zero = _mm256_setzero_si256(), minus_one = _mm256_set1_epi32(-1);
    const __m256i min_weight_minus_one =
        _mm256_set1_epi32(int32_t(sampler_.min_weight_fixed()) - 1);
    const __m256i stop_at_back_faces = params_.stop_at_back_faces ? minus_one : zero;

    while (num_live > 0 || crossings.count > 0 || brackets.count > 0 || !resumes.empty()) {
      if (num_live == 0) {  // the last crossings, then the rays they resume
        if (crossings.count > 0) refine();
        if (brackets.count > 0) refine_brackets();
        for (int l = 0; l < kPacketLanes; ++l) num_live += start_next(l);
        continue;
      }
      for (int base = 0; base < kPacketLanes; base += kPacket) {  // lanes [base, base + 8)
        const __m256i live = avx2::Load(lanes.live + base);
        const __m256 z = avx2::LoadF(lanes.z + base);
        const __m256i in_range = _mm256_and_si256(
            live,
            _mm256_castps_si256(_mm256_cmp_ps(z, avx2::LoadF(lanes.z_end + base), _CMP_LE_OQ)));
        // The sample's voxel and block, as Step computes them.
        __m256i g[3], changed = zero;
        for (int a = 0; a < 3; ++a) {
          const __m256 p =
              _mm256_add_ps(origin_vox[a], _mm256_mul_ps(z, avx2::LoadF(lanes.dir_vox[a] + base)));
          g[a] = avx2::Floor(p);
          const __m256i b = _mm256_srai_epi32(g[a], kBlockShift);
          changed = _mm256_or_si256(
              changed, avx2::AndNot(_mm256_cmpeq_epi32(b, avx2::Load(lanes.block_index[a] + base)),
                                    minus_one));
          // Lanes out of range keep theirs, which stays their block's index for the next ray.
          avx2::Store(lanes.block_index[a] + base,
                      _mm256_blendv_epi8(avx2::Load(lanes.block_index[a] + base), b, in_range));
        }
        changed = _mm256_and_si256(changed, in_range);
        for (int bits = _mm256_movemask_ps(_mm256_castsi256_ps(changed)); bits; bits &= bits - 1) {
          const int l = base + std::countr_zero(unsigned(bits));
          const TsdfBlock* block = sampler_.FindUncached(BlockIndex{
              lanes.block_index[0][l], lanes.block_index[1][l], lanes.block_index[2][l]});
          lanes.has_block[l] = block ? -1 : 0;
          lanes.block[l] = block ? block : &kNoBlock;
        }
        // tsdf[i] and weight[i] of each lane's block, loaded lane by lane (faster here than two
        // AVX2 gathers).
        alignas(32) int32_t index[kPacket], lane_tsdf[kPacket], lane_weight[kPacket];
        avx2::Store(index, avx2::LinearIndex(g));
        for (int l = 0; l < kPacket; ++l) {
          const TsdfBlock& block = *lanes.block[base + l];
          lane_tsdf[l] = block.tsdf[index[l]];
          lane_weight[l] = block.weight[index[l]];
        }
        const __m256i tsdf = avx2::Load(lane_tsdf), weight = avx2::Load(lane_weight);

        const __m256i has_block = avx2::Load(lanes.has_block + base);
        const __m256i no_block = avx2::AndNot(has_block, in_range);
        const __m256i observed = _mm256_and_si256(_mm256_and_si256(in_range, has_block),
                                                  _mm256_cmpgt_epi32(weight, min_weight_minus_one));
        const __m256i unobserved = avx2::AndNot(observed, _mm256_and_si256(in_range, has_block));
        const __m256i have_prev = avx2::Load(lanes.have_prev + base);
        const __m256i prev_tsdf = avx2::Load(lanes.prev_tsdf + base);
        const __m256i tsdf_nonneg = _mm256_cmpgt_epi32(tsdf, minus_one);
        const __m256i cross = _mm256_and_si256(
            _mm256_and_si256(observed, have_prev),
            _mm256_xor_si256(_mm256_cmpgt_epi32(prev_tsdf, minus_one), tsdf_nonneg));
        // A zero after a positive sample: one voxel on, the positive one kept (as Step does).
        const __m256i on_surface = _mm256_and_si256(
            _mm256_and_si256(observed, have_prev),
            _mm256_and_si256(_mm256_cmpeq_epi32(tsdf, zero), _mm256_cmpgt_epi32(prev_tsdf, zero)));
        const __m256i back_face = _mm256_and_si256(cross, tsdf_nonneg);
        const __m256i stop = _mm256_and_si256(back_face, stop_at_back_faces);
        const __m256i front_face = avx2::AndNot(tsdf_nonneg, cross);  // refined below
        const __m256i advance = avx2::AndNot(_mm256_or_si256(cross, on_surface), observed);
        const __m256i one_voxel = _mm256_or_si256(unobserved, avx2::AndNot(stop, back_face));

        // Where a lane without a block leaves it (nudged past the face).
        __m256 z_exit = inf;
        for (int a = 0; a < 3; ++a) {
          const __m256 d = avx2::LoadF(lanes.dir_W[a] + base);
          const __m256i face = _mm256_sub_epi32(
              avx2::Load(lanes.block_index[a] + base),
              _mm256_castps_si256(_mm256_cmp_ps(d, _mm256_setzero_ps(), _CMP_GT_OQ)));
          __m256 t = _mm256_div_ps(
              _mm256_sub_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(face), block_m), origin_W[a]), d);
          t = _mm256_blendv_ps(t, inf, _mm256_cmp_ps(d, _mm256_setzero_ps(), _CMP_EQ_OQ));
          z_exit = _mm256_min_ps(t, z_exit);
        }
        const __m256 voxel_z = avx2::LoadF(lanes.voxel_z + base);
        const __m256 tsdf_f = _mm256_cvtepi32_ps(tsdf);
        __m256 z_next = z;
        z_next = avx2::Blend(
            z_next,
            _mm256_add_ps(_mm256_max_ps(z, z_exit), _mm256_mul_ps(_mm256_set1_ps(0.01f), voxel_z)),
            no_block);
        z_next =
            avx2::Blend(z_next, _mm256_add_ps(z, voxel_z), _mm256_or_si256(one_voxel, on_surface));
        z_next = avx2::Blend(
            z_next,
            _mm256_add_ps(
                z, _mm256_max_ps(voxel_z, _mm256_mul_ps(tsdf_f, avx2::LoadF(lanes.step_z + base)))),
            advance);
        _mm256_storeu_ps(lanes.z + base, z_next);
        _mm256_storeu_ps(lanes.prev_z + base,
                         avx2::Blend(avx2::LoadF(lanes.prev_z + base), z, advance));
        avx2::Store(lanes.prev_tsdf + base, _mm256_blendv_epi8(prev_tsdf, tsdf, advance));
        avx2::Store(lanes.tsdf + base, tsdf);
        // have_prev: set by an advance, cleared by a jump or a one-voxel step, kept otherwise (on
        // the surface too).
        const __m256i cleared = _mm256_or_si256(no_block, one_voxel);
        avx2::Store(lanes.have_prev + base,
                    _mm256_or_si256(advance, avx2::AndNot(cleared, have_prev)));
        avx2::Store(lanes.met + base, _mm256_or_si256(avx2::Load(lanes.met + base), observed));

        const __m256i done =
            _mm256_or_si256(avx2::AndNot(in_range, live), _mm256_or_si256(stop, front_face));
        const int front_bits = _mm256_movemask_ps(_mm256_castsi256_ps(front_face));
        for (int bits = _mm256_movemask_ps(_mm256_castsi256_ps(done)); bits; bits &= bits - 1) {
          const int l = base + std::countr_zero(unsigned(bits));
          if ((front_bits >> (l - base)) & 1) {
            // A crossing: queued for refinement, and the lane takes the next ray.
            const int j = crossings.count++;
            for (int a = 0; a < 3; ++a) crossings.dir_W[a][j] = lanes.dir_W[a][l];
            crossings.z_a[j] = lanes.prev_z[l], crossings.z_b[j] = lanes.z[l];
            crossings.tsdf_a[j] = lanes.prev_tsdf[l], crossings.tsdf_b[j] = lanes.tsdf[l];
            crossings.voxel_z[j] = lanes.voxel_z[l], crossings.z_end[j] = lanes.z_end[l];
            crossings.pixel[j] = lanes.pixel[l];
            for (int a = 0; a < 3; ++a) crossings.block_index[a][j] = lanes.block_index[a][l];
            crossings.block[j] = lanes.block[l];
            if (crossings.count == kPacket) refine();
            num_live -= !start_next(l);
            continue;
          }
          const Eigen::Vector3f dir_W(lanes.dir_W[0][l], lanes.dir_W[1][l], lanes.dir_W[2][l]);
          RayResult result;
          if (lanes.met[l]) result.status = RayStatus::kFree;
          num_live -= !finish(l, dir_W, result);
        }
      }
    }
  }

  // Crossings the packet march found, refined kPacket at a time (RefineCrossings).
  struct alignas(32) Crossings {
    float dir_W[3][kPacket], z_a[kPacket], z_b[kPacket], voxel_z[kPacket], z_end[kPacket];
    int32_t tsdf_a[kPacket], tsdf_b[kPacket];
    int32_t block_index[3][kPacket];  // the block the march sampled at z_b
    const TsdfBlock* block[kPacket];
    size_t pixel[kPacket];
    int count = 0;

    // The lanes holding a crossing (all bits set), for AVX2 code.
    VOXPLAN_TARGET_AVX2 __m256i Lanes() const {
      return _mm256_cmpgt_epi32(_mm256_set1_epi32(count),
                                _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    }

    // Appends crossing j of `other`.
    void Append(const Crossings& other, int j) {
      const int i = count++;
      for (int a = 0; a < 3; ++a) {
        dir_W[a][i] = other.dir_W[a][j];
        block_index[a][i] = other.block_index[a][j];
      }
      z_a[i] = other.z_a[j], z_b[i] = other.z_b[j], voxel_z[i] = other.voxel_z[j];
      z_end[i] = other.z_end[j];
      tsdf_a[i] = other.tsdf_a[j], tsdf_b[i] = other.tsdf_b[j];
      block[i] = other.block[j];
      pixel[i] = other.pixel[j];
    }
  };
  // A ray whose crossing had no zero, to march on from it.
  struct Resume {
    Eigen::Vector3f dir_W;
    float z_b, z_end;
    int16_t tsdf_b;
    size_t pixel;
  };

  // The cells a packet of crossings last sampled, lane by lane: corner 0, its block (first the
  // block the march last sampled), the corners of a cell across block faces; the corners'
  // distances and weights are in rows_, as x-pairs (corner 2p in the low 16 bits of pair p,
  // corner 2p + 1 in the high ones), loaded lane by lane into rows that AVX2 then reads.
  struct PacketCells {
    alignas(32) int32_t base[3][kPacket] = {}, i0[kPacket] = {}, block_index[3][kPacket];
    alignas(32) const TsdfBlock* block[kPacket];
    const TsdfBlock* across_block[kPacket][8];
    int across_index[kPacket][8];
    unsigned one_block = 0;  // bit l: lane l's cell lies in block[l]
    unsigned loaded = 0;     // bit l: lane l's rows hold its cell (else an earlier batch's)

    // No cell loaded yet; each lane's block the one the march sampled last.
    explicit PacketCells(const Crossings& c) {
      std::memcpy(block_index, c.block_index, sizeof(block_index));
      std::memcpy(block, c.block, sizeof(block));
    }
  };

  // Sample (Sampler::Gather, then ValueAndGradientSse2 lane by lane) at depth z on the rays of
  // the active lanes; the other lanes' cells stay. The value, the position in the cell and the
  // gradient are those of the active lanes; returns the lanes whose eight corners are observed.
  VOXPLAN_TARGET_AVX2 __m256i SampleCells(PacketCells& cells, const __m256 dir[3], __m256 z,
                                          __m256i active, __m256* value, __m256 frac[3],
                                          __m256 gradient[3]) {
    using namespace avx2;
    const __m256i zero = _mm256_setzero_si256(), minus_one = _mm256_set1_epi32(-1);
    __m256i g[3], changed = zero, moved = zero, inside_block = minus_one;
    for (int a = 0; a < 3; ++a) {
      const __m256 p = _mm256_add_ps(Set(origin_W_[a]), _mm256_mul_ps(z, dir[a]));
      const __m256 q = _mm256_sub_ps(_mm256_mul_ps(p, Set(sampler_.inv_voxel())), Set(0.5f));
      g[a] = Floor(q);
      frac[a] = _mm256_sub_ps(q, _mm256_cvtepi32_ps(g[a]));
      moved =
          _mm256_or_si256(moved, AndNot(_mm256_cmpeq_epi32(g[a], Load(cells.base[a])), minus_one));
      Store(cells.base[a], _mm256_blendv_epi8(Load(cells.base[a]), g[a], active));
      const __m256i b = _mm256_srai_epi32(g[a], kBlockShift);
      changed = _mm256_or_si256(
          changed, AndNot(_mm256_cmpeq_epi32(b, Load(cells.block_index[a])), minus_one));
      Store(cells.block_index[a], _mm256_blendv_epi8(Load(cells.block_index[a]), b, active));
      // All eight corners in the block: corner 0 below its last voxel on every axis.
      inside_block = _mm256_and_si256(
          inside_block, _mm256_cmpgt_epi32(_mm256_set1_epi32(kBlockMask),
                                           _mm256_and_si256(g[a], _mm256_set1_epi32(kBlockMask))));
    }
    Store(cells.i0, _mm256_blendv_epi8(Load(cells.i0), LinearIndex(g), active));
    changed = _mm256_and_si256(changed, active);
    for (int bits = _mm256_movemask_ps(_mm256_castsi256_ps(changed)); bits; bits &= bits - 1) {
      const int l = std::countr_zero(unsigned(bits));
      const TsdfBlock* found = sampler_.FindUncached(
          BlockIndex{cells.block_index[0][l], cells.block_index[1][l], cells.block_index[2][l]});
      cells.block[l] = found ? found : &kNoBlock;
    }
    // The corners of the lanes whose cell moved (LoadCorners, LoadCornersAcross).
    auto& tsdf_pairs = rows_.tsdf_pairs;
    auto& weight_pairs = rows_.weight_pairs;
    const unsigned active_bits = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(active)));
    const unsigned inside_bits = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(inside_block)));
    unsigned load =
        (unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(moved))) | ~cells.loaded) & active_bits;
    cells.loaded |= active_bits;
    for (; load; load &= load - 1) {
      const int l = std::countr_zero(load);
      if ((inside_bits >> l) & 1) {
        cells.one_block |= 1u << l;
        const int16_t* tsdf = cells.block[l]->tsdf + cells.i0[l];
        const uint16_t* weight = cells.block[l]->weight + cells.i0[l];
        for (int p = 0; p < 4; ++p) {
          std::memcpy(&tsdf_pairs[p][l], tsdf + kCornerOffset[2 * p], sizeof(uint32_t));
          std::memcpy(&weight_pairs[p][l], weight + kCornerOffset[2 * p], sizeof(uint32_t));
        }
        continue;
      }
      cells.one_block &= ~(1u << l);
      const TsdfBlock** blocks = cells.across_block[l];
      const int* index = cells.across_index[l];
      sampler_.CornersAcross(GlobalVoxelIndex{cells.base[0][l], cells.base[1][l], cells.base[2][l]},
                             blocks, cells.across_index[l]);
      for (int p = 0; p < 4; ++p) {
        const int lo = 2 * p, hi = 2 * p + 1;
        tsdf_pairs[p][l] = uint32_t(uint16_t(blocks[lo]->tsdf[index[lo]])) |
                           uint32_t(uint16_t(blocks[hi]->tsdf[index[hi]])) << 16;
        weight_pairs[p][l] =
            uint32_t(blocks[lo]->weight[index[lo]]) | uint32_t(blocks[hi]->weight[index[hi]]) << 16;
      }
    }
    // Decoded as LoadCorners does.
    const __m256i min_weight_minus_one =
        _mm256_set1_epi32(int32_t(sampler_.min_weight_fixed()) - 1);
    __m256 t[8];
    __m256i complete = minus_one;
    const __m256i low16 = _mm256_set1_epi32(0xffff);
    for (int p = 0; p < 4; ++p) {
      const __m256i tsdf = Load(tsdf_pairs[p]), weight = Load(weight_pairs[p]);
      t[2 * p] = Decode(_mm256_srai_epi32(_mm256_slli_epi32(tsdf, 16), 16));
      t[2 * p + 1] = Decode(_mm256_srai_epi32(tsdf, 16));
      complete = _mm256_and_si256(
          complete, _mm256_and_si256(
                        _mm256_cmpgt_epi32(_mm256_and_si256(weight, low16), min_weight_minus_one),
                        _mm256_cmpgt_epi32(_mm256_srli_epi32(weight, 16), min_weight_minus_one)));
    }
    // ValueAndGradientSse2, lane by lane: edge j of four per axis, then the four summed in
    // pairs.
    const __m256 fx = frac[0], fy = frac[1], fz = frac[2];
    __m256 v[4], gx[4], gy[4], gz[4];
    for (int j = 0; j < 4; ++j) {
      const bool odd = j & 1, high = j >= 2;
      const __m256 wx = Lerp(odd, fx), wy = Lerp(high, fy), wz = Lerp(high, fz);
      const __m256 wy_edge = Lerp(odd, fy);
      const __m256 d_z = _mm256_sub_ps(t[j + 4], t[j]);
      static constexpr int kX[4][2] = {{1, 0}, {3, 2}, {5, 4}, {7, 6}};
      static constexpr int kY[4][2] = {{2, 0}, {3, 1}, {6, 4}, {7, 5}};
      const __m256 d_x = _mm256_sub_ps(t[kX[j][0]], t[kX[j][1]]);
      const __m256 d_y = _mm256_sub_ps(t[kY[j][0]], t[kY[j][1]]);
      const __m256 wxy = _mm256_mul_ps(wx, wy);
      v[j] = _mm256_mul_ps(wxy, _mm256_add_ps(t[j], _mm256_mul_ps(fz, d_z)));
      gx[j] = _mm256_mul_ps(_mm256_mul_ps(wy_edge, wz), d_x);
      gy[j] = _mm256_mul_ps(_mm256_mul_ps(wx, wz), d_y);
      gz[j] = _mm256_mul_ps(wxy, d_z);
    }
    *value = Sum4(v);
    gradient[0] = Sum4(gx), gradient[1] = Sum4(gy), gradient[2] = Sum4(gz);
    return complete;
  }

  // SampleCells for the bracket: a lane whose cell has an unobserved corner leaves `live` for
  // `scalar` (Cross then refines it itself).
  VOXPLAN_TARGET_AVX2 __m256 SampleLive(PacketCells& cells, const __m256 dir[3], __m256 z,
                                        __m256i* live, __m256i* scalar, __m256 frac[3],
                                        __m256 gradient[3]) {
    __m256 value;
    const __m256i complete = SampleCells(cells, dir, z, *live, &value, frac, gradient);
    *scalar = _mm256_or_si256(*scalar, avx2::AndNot(complete, *live));
    *live = _mm256_and_si256(*live, complete);
    return value;
  }

  // Cross for each of the crossings, as if called one by one: bit j of the result set when
  // crossing j has its result in results[j], clear when the interpolant has no zero there.
  // Refine runs in AVX2 lanes with the scalar code's float operations in its order, so the
  // results are the same bytes: two Newton steps on complete cells, then normal and colour. The
  // lanes that leave that path (a grazing slope, a step out of bounds, an unobserved corner)
  // are set in `deferred`, for BracketCrossings.
  VOXPLAN_TARGET_AVX2 unsigned RefineCrossings(const Crossings& c, RayResult results[kPacket],
                                               unsigned* deferred) {
    using namespace avx2;
    const __m256i zero = _mm256_setzero_si256();
    const __m256 dir[3] = {LoadF(c.dir_W[0]), LoadF(c.dir_W[1]), LoadF(c.dir_W[2])};
    const __m256 z_a = LoadF(c.z_a), z_b = LoadF(c.z_b), voxel_z = LoadF(c.voxel_z);
    const __m256 nearest_a = Decode(Load(c.tsdf_a)), nearest_b = Decode(Load(c.tsdf_b));
    const __m256 max_slope = Set(MaxSlope());
    const __m256 dq_dz = Set(sampler_.inv_voxel());
    const __m256i valid = c.Lanes();
    // Lanes on the Newton path (`ok`) and those done with their Newton steps.
    __m256i ok = valid, converged = zero;
    __m256 z = Secant(z_a, z_b, nearest_a, nearest_b);
    PacketCells cells(c);
    __m256 frac[3] = {}, gradient[3] = {};
    for (int k = 0; k < kNewtonIterations; ++k) {
      const __m256i active = AndNot(converged, ok);
      if (!_mm256_movemask_ps(_mm256_castsi256_ps(active))) break;
      __m256 f, f_new[3], g_new[3];
      const __m256i complete = SampleCells(cells, dir, z, active, &f, f_new, g_new);
      ok = AndNot(AndNot(complete, active), ok);
      // Refine's Newton step; Eigen's dot sums x + (y + z).
      const __m256 slope = _mm256_mul_ps(
          _mm256_add_ps(
              _mm256_mul_ps(g_new[0], dir[0]),
              _mm256_add_ps(_mm256_mul_ps(g_new[1], dir[1]), _mm256_mul_ps(g_new[2], dir[2]))),
          dq_dz);
      const __m256 dz = _mm256_div_ps(_mm256_sub_ps(_mm256_setzero_ps(), f), slope);
      const __m256 z_next = _mm256_add_ps(z, dz);
      const __m256 steep = _mm256_cmp_ps(_mm256_mul_ps(slope, voxel_z), max_slope, _CMP_LT_OQ);
      const __m256 inside =
          _mm256_and_ps(_mm256_cmp_ps(z_next, _mm256_sub_ps(z_a, voxel_z), _CMP_GT_OQ),
                        _mm256_cmp_ps(z_next, _mm256_add_ps(z_b, voxel_z), _CMP_LT_OQ));
      ok = AndNot(AndNot(_mm256_castps_si256(_mm256_and_ps(steep, inside)), active), ok);
      const __m256i stepped = _mm256_and_si256(active, ok);
      z = Blend(z, z_next, stepped);
      for (int a = 0; a < 3; ++a) {
        frac[a] = Blend(frac[a], f_new[a], stepped);
        gradient[a] = Blend(gradient[a], g_new[a], stepped);
      }
      const __m256 abs_dz = _mm256_andnot_ps(Set(-0.f), dz);
      const __m256i small = _mm256_castps_si256(
          _mm256_cmp_ps(abs_dz, _mm256_mul_ps(Set(kConvergedVoxels), voxel_z), _CMP_LT_OQ));
      converged = _mm256_or_si256(
          converged, k + 1 == kNewtonIterations ? stepped : _mm256_and_si256(stepped, small));
    }
    ok = _mm256_and_si256(ok, converged);

    *deferred = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(AndNot(ok, valid))));
    return FinishCrossings(c, cells, ok, zero, z, frac, gradient, results);
  }

  // Refine's bracket (regula falsi on the trilinear interpolant, Bracket) for each of the
  // crossings, then normal and colour, in AVX2 lanes with the scalar code's float operations in
  // its order; bit j of the result as RefineCrossings'. A lane that meets an unobserved corner
  // is refined by Cross itself.
  VOXPLAN_TARGET_AVX2 unsigned BracketCrossings(const Crossings& c, RayResult results[kPacket]) {
    using namespace avx2;
    const __m256 dir[3] = {LoadF(c.dir_W[0]), LoadF(c.dir_W[1]), LoadF(c.dir_W[2])};
    const __m256 voxel_z = LoadF(c.voxel_z);
    __m256i live = c.Lanes();
    __m256i scalar = _mm256_setzero_si256();
    PacketCells cells(c);
    const __m256 zero_f = _mm256_setzero_ps();
    __m256 frac[3], gradient[3];
    __m256 za = LoadF(c.z_a), zb = LoadF(c.z_b);
    __m256 fa = SampleLive(cells, dir, za, &live, &scalar, frac, gradient);
    __m256 fb = SampleLive(cells, dir, zb, &live, &scalar, frac, gradient);
    // Moved back while f_a < 0, then on while f_b >= 0, a voxel at a time.
    for (int side = 0; side < 2; ++side)
      for (int k = 0; k < kMaxBracketShifts; ++k) {
        const __m256i shift = _mm256_and_si256(
            live, _mm256_castps_si256(side == 0 ? _mm256_cmp_ps(fa, zero_f, _CMP_LT_OQ)
                                                : _mm256_cmp_ps(fb, zero_f, _CMP_GE_OQ)));
        if (!_mm256_movemask_ps(_mm256_castsi256_ps(shift))) break;
        __m256i sampled = shift;
        if (side == 0) {
          zb = Blend(zb, za, shift), fb = Blend(fb, fa, shift);
          za = Blend(za, _mm256_sub_ps(za, voxel_z), shift);
          fa = Blend(fa, SampleLive(cells, dir, za, &sampled, &scalar, frac, gradient), sampled);
        } else {
          za = Blend(za, zb, shift), fa = Blend(fa, fb, shift);
          zb = Blend(zb, _mm256_add_ps(zb, voxel_z), shift);
          fb = Blend(fb, SampleLive(cells, dir, zb, &sampled, &scalar, frac, gradient), sampled);
        }
        live = AndNot(AndNot(sampled, shift), live);
      }
    const __m256i straddles = _mm256_castps_si256(_mm256_and_ps(
        _mm256_cmp_ps(fa, zero_f, _CMP_GE_OQ), _mm256_cmp_ps(fb, zero_f, _CMP_LT_OQ)));
    live = _mm256_and_si256(live, straddles);  // the others have no zero
    // Regula falsi; a lane meeting an unobserved corner goes to Cross.
    for (int k = 0; k < kSecantIterations; ++k) {
      const __m256 zr = Secant(za, zb, fa, fb);
      const __m256 f = SampleLive(cells, dir, zr, &live, &scalar, frac, gradient);
      const __m256 positive = _mm256_cmp_ps(f, zero_f, _CMP_GE_OQ);
      const __m256i to_a = _mm256_and_si256(live, _mm256_castps_si256(positive));
      const __m256i to_b = AndNot(_mm256_castps_si256(positive), live);
      za = Blend(za, zr, to_a), fa = Blend(fa, f, to_a);
      zb = Blend(zb, zr, to_b), fb = Blend(fb, f, to_b);
    }
    // The cell at the final point gives the gradient and the colour.
    const __m256 z_out = Secant(za, zb, fa, fb);
    SampleLive(cells, dir, z_out, &live, &scalar, frac, gradient);
    return FinishCrossings(c, cells, live, scalar, z_out, frac, gradient, results);
  }

  // The results of a batch of crossings: for the `ok` lanes the hit at z with the normal from
  // `gradient` and the colour of the cell at `frac`, for the `scalar` ones Cross; bit j of the
  // result as RefineCrossings'.
  VOXPLAN_TARGET_AVX2 unsigned FinishCrossings(const Crossings& c, const PacketCells& cells,
                                               __m256i ok, __m256i scalar, __m256 z,
                                               const __m256 frac[3], const __m256 gradient[3],
                                               RayResult results[kPacket]) {
    using namespace avx2;
    const __m256i zero = _mm256_setzero_si256();
    alignas(32) float z_out[kPacket], normal[3][kPacket];
    alignas(32) uint32_t color[kPacket];
    _mm256_store_ps(z_out, z);
    if (params_.with_normals) {
      const __m256 norm =
          _mm256_sqrt_ps(_mm256_add_ps(_mm256_mul_ps(gradient[0], gradient[0]),
                                       _mm256_add_ps(_mm256_mul_ps(gradient[1], gradient[1]),
                                                     _mm256_mul_ps(gradient[2], gradient[2]))));
      const __m256 positive = _mm256_cmp_ps(norm, _mm256_setzero_ps(), _CMP_GT_OQ);
      for (int a = 0; a < 3; ++a)
        _mm256_store_ps(normal[a],
                        _mm256_blendv_ps(Set(kNaN), _mm256_div_ps(gradient[a], norm), positive));
    }
    if (params_.with_color) {
      // BlendChannelsSse2, lane by lane: corner-pair j of each channel, the pairs summed in
      // pairs.
      const __m256 fx = frac[0], fy = frac[1], fz = frac[2];
      __m256 w_lo[4], w_hi[4];
      for (int j = 0; j < 4; ++j) {
        const __m256 wxy = _mm256_mul_ps(Lerp(j & 1, fx), Lerp(j >= 2, fy));
        w_lo[j] = _mm256_mul_ps(wxy, _mm256_sub_ps(Set(1.f), fz));
        w_hi[j] = _mm256_mul_ps(wxy, fz);
      }
      __m256 w[4];
      for (int j = 0; j < 4; ++j) w[j] = _mm256_add_ps(w_lo[j], w_hi[j]);
      const __m256 sum_w = Sum4(w);
      const __m256 inv = _mm256_div_ps(Set(1.f), sum_w);
      // The corners' colours as x-pairs (corner 2p in the low byte of pair p, 2p + 1 next).
      auto& color_pairs = rows_.color_pairs;
      for (int bits = _mm256_movemask_ps(_mm256_castsi256_ps(ok)); bits; bits &= bits - 1) {
        const int l = std::countr_zero(unsigned(bits));
        if ((cells.one_block >> l) & 1) {
          const uint8_t* channel[3] = {cells.block[l]->r, cells.block[l]->g, cells.block[l]->b};
          for (int ch = 0; ch < 3; ++ch)
            for (int p = 0; p < 4; ++p) {
              uint16_t pair;
              std::memcpy(&pair, channel[ch] + cells.i0[l] + kCornerOffset[2 * p], sizeof(pair));
              color_pairs[ch][p][l] = pair;
            }
          continue;
        }
        for (int p = 0; p < 4; ++p) {
          const TsdfBlock &lo = *cells.across_block[l][2 * p],
                          &hi = *cells.across_block[l][2 * p + 1];
          const int i_lo = cells.across_index[l][2 * p], i_hi = cells.across_index[l][2 * p + 1];
          color_pairs[0][p][l] = uint32_t(lo.r[i_lo]) | uint32_t(hi.r[i_hi]) << 8;
          color_pairs[1][p][l] = uint32_t(lo.g[i_lo]) | uint32_t(hi.g[i_hi]) << 8;
          color_pairs[2][p][l] = uint32_t(lo.b[i_lo]) | uint32_t(hi.b[i_hi]) << 8;
        }
      }
      __m256i rgb = zero;
      for (int ch = 0; ch < 3; ++ch) {
        __m256 corner[8], pair[4];
        for (int p = 0; p < 4; ++p) {
          const __m256i pairs = Load(color_pairs[ch][p]);
          corner[2 * p] = _mm256_cvtepi32_ps(_mm256_and_si256(pairs, _mm256_set1_epi32(0xff)));
          corner[2 * p + 1] = _mm256_cvtepi32_ps(_mm256_srli_epi32(pairs, 8));
        }
        for (int j = 0; j < 4; ++j)
          pair[j] = _mm256_add_ps(_mm256_mul_ps(corner[j], w_lo[j]),
                                  _mm256_mul_ps(corner[j + 4], w_hi[j]));
        const __m256 scaled = _mm256_add_ps(_mm256_mul_ps(Sum4(pair), inv), Set(0.5f));
        const __m256i c8 = _mm256_cvttps_epi32(
            _mm256_min_ps(_mm256_max_ps(scaled, _mm256_setzero_ps()), Set(255.f)));
        rgb = _mm256_or_si256(rgb, _mm256_slli_epi32(c8, 8 * ch));
      }
      const __m256i positive =
          _mm256_castps_si256(_mm256_cmp_ps(sum_w, _mm256_setzero_ps(), _CMP_GT_OQ));
      Store(color, _mm256_and_si256(rgb, positive));
    }

    const int ok_bits = _mm256_movemask_ps(_mm256_castsi256_ps(ok));
    const int scalar_bits = _mm256_movemask_ps(_mm256_castsi256_ps(scalar));
    unsigned found = 0;
    for (int j = 0; j < c.count; ++j) {
      const Eigen::Vector3f dir_W(c.dir_W[0][j], c.dir_W[1][j], c.dir_W[2][j]);
      RayResult& result = results[j];
      result = RayResult{};
      result.status = RayStatus::kFree;  // the march met observed voxels
      if ((scalar_bits >> j) & 1) {
        found |= unsigned(Cross(dir_W, c.z_a[j], c.z_b[j], int16_t(c.tsdf_a[j]),
                                int16_t(c.tsdf_b[j]), c.voxel_z[j], &result, /*newton=*/false))
                 << j;
        continue;
      }
      if (!((ok_bits >> j) & 1)) continue;  // the bracket found no zero
      found |= 1u << j;
      if (z_out[j] < params_.min_depth_m || z_out[j] > params_.max_depth_m) continue;  // kFree
      result.status = RayStatus::kHit;
      result.z = z_out[j];
      if (params_.with_normals) result.normal_W = {normal[0][j], normal[1][j], normal[2][j]};
      if (params_.with_color) result.color = color[j];
    }
    return found;
  }

  std::vector<Resume> resumes_;  // MarchPackets', kept for its capacity
  // RefineCrossings' rows of corner values, kept between batches (zeroing them per batch cost
  // 5 % of the refinement): a lane reads only what its own crossing loaded.
  struct alignas(32) Rows {
    uint32_t tsdf_pairs[4][kPacket] = {}, weight_pairs[4][kPacket] = {};
    uint32_t color_pairs[3][4][kPacket] = {};
  } rows_;
};

}  // namespace

std::unique_ptr<RayCaster> MakePacketCaster(const TsdfVolume& volume, const RaycastParams& params,
                                            const Eigen::Vector3f& origin_W,
                                            const Eigen::Vector3f& d0_W,
                                            const Eigen::Vector3f& du_W,
                                            const Eigen::Vector3f& dv_W) {
  return std::make_unique<PacketCaster>(volume, params, origin_W, d0_W, du_W, dv_W);
}

// range_image.h's splatting for AVX2 CPUs (see CullChunk there).
VOXPLAN_TARGET_AVX2 void CullChunkAvx2(const Splatter& splatter, const BlockIndex* blocks,
                                       const TsdfBlock* const* data, size_t first, size_t last,
                                       Chunk& chunk) {
  splatter.CullBlocks(blocks, data, first, last, chunk);
}
VOXPLAN_TARGET_AVX2 void SplatChunkAvx2(const Splatter& splatter, const BrickMaskTable& table,
                                        Chunk& chunk) {
  splatter.SplatBricks(table, chunk);
}

#else  // no AVX2 code here: RaycastSimdAvailable() is false, so Raycast never calls these
std::unique_ptr<RayCaster> MakePacketCaster(const TsdfVolume& volume, const RaycastParams& params,
                                            const Eigen::Vector3f& origin_W,
                                            const Eigen::Vector3f& d0_W,
                                            const Eigen::Vector3f& du_W,
                                            const Eigen::Vector3f& dv_W) {
  return MakeScalarCaster(volume, params, origin_W, d0_W, du_W, dv_W);
}
void CullChunkAvx2(const Splatter& splatter, const BlockIndex* blocks, const TsdfBlock* const* data,
                   size_t first, size_t last, Chunk& chunk) {
  CullChunk(splatter, blocks, data, first, last, chunk);
}
void SplatChunkAvx2(const Splatter& splatter, const BrickMaskTable& table, Chunk& chunk) {
  SplatChunk(splatter, table, chunk);
}
#endif

}  // namespace voxplan::raycast_detail

namespace voxplan {

bool RaycastSimdAvailable() {
#if VOXPLAN_RAYCAST_AVX2
  static const bool available = __builtin_cpu_supports("avx2");
  return available;
#else
  return false;
#endif
}

}  // namespace voxplan
