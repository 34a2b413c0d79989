// The ray caster's driver (core/raycast.h): image tiles in parallel, each batch of tiles
// planned into ray tasks over the range image's depth ranges, marched by the scalar reference
// or the AVX2 packet march (one choice per cast), and copied row by row into the images.
#include "core/raycast.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>

#include "core/parallel.h"
#include "core/raycast/march.h"
#include "core/raycast/raycast_internal.h"

namespace voxplan {
namespace {

using raycast_detail::BatchImages;
using raycast_detail::BatchWriter;
using raycast_detail::BuildRangeImage;
using raycast_detail::kBatchPixels;
using raycast_detail::kNaN;
using raycast_detail::kRangeCell;
using raycast_detail::kSurfaceCell;
using raycast_detail::kTile;
using raycast_detail::kTilesPerBatch;
using raycast_detail::MakePacketCaster;
using raycast_detail::MakeScalarCaster;
using raycast_detail::MarchStart;
using raycast_detail::RangeImage;
using raycast_detail::RayCaster;
using raycast_detail::RayResult;
using raycast_detail::RayTask;

// n pixels of an image row. Eigen's fixed-size vectors are plain floats, but not trivially
// copy-assignable by the letter of the type: memcpy through void*.
template <class T>
void CopyPixels(T* dst, const T* src, size_t n) {
  static_assert(std::is_standard_layout_v<T> && std::is_trivially_destructible_v<T>);
  constexpr size_t kRowBytes = kTile * sizeof(T);
#if defined(__SSE2__)
  // A whole tile row of whole cache lines (images start on one, so with a width divisible by
  // 16 every such row does) in streaming stores: the outputs, 10 MB at 640 x 480, are far
  // larger than the caches, and a plain store first reads each line in.
  if (kRowBytes % 64 == 0 && n == size_t(kTile) && reinterpret_cast<uintptr_t>(dst) % 64 == 0) {
    auto* d = static_cast<__m128i*>(static_cast<void*>(dst));
    const auto* s = static_cast<const __m128i*>(static_cast<const void*>(src));
    for (size_t k = 0; k < kRowBytes / 16; ++k) _mm_stream_si128(d + k, _mm_loadu_si128(s + k));
    return;
  }
#endif
  // Otherwise a whole row as a copy of known size, which the compiler inlines as vector moves:
  // a library call per row of 16 to 192 bytes cost more than the copy.
  if (n == size_t(kTile)) {
    std::memcpy(static_cast<void*>(dst), static_cast<const void*>(src), kRowBytes);
    return;
  }
  std::memcpy(static_cast<void*>(dst), static_cast<const void*>(src), n * sizeof(T));
}

}  // namespace

void Raycast(const TsdfVolume& volume, const PinholeCamera& camera, const Pose3f& T_W_C,
             const RaycastParams& params, RaycastImages& images) {
  if (!camera.Valid()) {
    images = RaycastImages{};
    return;
  }
  const int w = camera.width, h = camera.height;
  auto fit = [w, h](auto& image, auto fill) {
    if (image.width != w || image.height != h) image = std::decay_t<decltype(image)>(w, h, fill);
  };
  const Eigen::Vector3f nan3(kNaN, kNaN, kNaN);
  fit(images.depth, 0.f);
  fit(images.vertex_W, nan3);
  fit(images.normal_W, nan3);
  fit(images.color, uint32_t{0});
  fit(images.status, uint8_t(RayStatus::kUnobserved));

  const bool usable = T_W_C.matrix().allFinite() && params.min_depth_m <= params.max_depth_m &&
                      std::isfinite(params.min_depth_m) && std::isfinite(params.max_depth_m) &&
                      volume.num_blocks() > 0;
  // The one choice between the AVX2 code (march_avx2.cpp) and the scalar reference, for the
  // range image's splatting and for the march; both give the same images.
  const bool avx2 = params.simd && RaycastSimdAvailable();
  const RangeImage range =
      usable ? BuildRangeImage(volume, camera, T_W_C.inverse(), params, avx2) : RangeImage{};
  const float z_start = MarchStart(volume, params);
  const Eigen::Matrix3f R_W_C = T_W_C.linear();
  const Eigen::Vector3f origin_W = T_W_C.translation();
  // The ray through pixel (u, v), scaled to unit optical depth: d0 + u du + v dv.
  const Eigen::Vector3f du_W = R_W_C.col(0) / camera.fx, dv_W = R_W_C.col(1) / camera.fy;
  const Eigen::Vector3f d0_W = R_W_C.col(2) - camera.cx * du_W - camera.cy * dv_W;
  // surface_z_min already bounds every negative voxel's cube, so the first sample in front of
  // it is never negative; half a voxel more absorbs rounding, and more only adds steps.
  const float surface_margin = 0.5f * volume.voxel_size_m();
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  static_assert(kTile % kRangeCell == 0 && kRangeCell % kSurfaceCell == 0);
  const float max_depth_m = params.max_depth_m;

  // Results go to a batch's own images first (a pixel's index there is its tile's place in
  // the batch, then its row and column in the tile) and then row by row to `images`: scattered
  // stores of a few bytes into images far larger than the caches were the slower way.
  ParallelFor(size_t(tiles_x) * size_t(tiles_y), kTilesPerBatch, [&](size_t begin, size_t end) {
    const std::unique_ptr<RayCaster> caster =
        avx2 ? MakePacketCaster(volume, params, origin_W, d0_W, du_W, dv_W)
             : MakeScalarCaster(volume, params, origin_W, d0_W, du_W, dv_W);
    const RayResult unobserved;
    RayTask tasks[kBatchPixels];
    auto batch = std::make_unique<BatchImages>();
    BatchImages& out = *batch;
    const BatchWriter write{out, origin_W, nan3};
    for (size_t first = begin; first < end; first += kTilesPerBatch) {
      const size_t last = std::min(first + kTilesPerBatch, end);
      // First the pixels whose rays have a range to march, tile by tile and row by row; the
      // others are written as unobserved at once.
      size_t num_tasks = 0;
      for (size_t tile = first; tile < last; ++tile) {
        const int u0 = int(tile % size_t(tiles_x)) * kTile,
                  v0 = int(tile / size_t(tiles_x)) * kTile;
        const int u_end = std::min(u0 + kTile, w), v_end = std::min(v0 + kTile, h);
        for (int v = v0; v < v_end; ++v) {
          const size_t row_i = (tile - first) * kTile * kTile + size_t(v - v0) * kTile;
          auto write_unobserved = [&](int u_begin, int u_stop) {
            for (int u = u_begin; u < u_stop; ++u) write(row_i + size_t(u - u0), unobserved, d0_W);
          };
          if (!usable) {
            write_unobserved(u0, u_end);
            continue;
          }
          const size_t range_row = size_t(v / kRangeCell) * size_t(range.cols);
          const float* z_min_row = range.z_min.data() + range_row;
          const float* z_max_row = range.z_max.data() + range_row;
          const float* surface_row =
              range.surface_z_min.data() + size_t(v / kSurfaceCell) * size_t(range.surface_cols);
          // A range cell's pixels of the row share its depth range (tiles start on a cell edge).
          for (int u_cell = u0; u_cell < u_end; u_cell += kRangeCell) {
            const int u_cell_end = std::min(u_cell + kRangeCell, u_end);
            const float z_all = std::max(z_min_row[u_cell / kRangeCell], z_start);
            const float z_end = std::min(z_max_row[u_cell / kRangeCell], max_depth_m);
            if (!(z_all <= z_end)) {
              write_unobserved(u_cell, u_cell_end);
              continue;
            }
            for (int u = u_cell; u < u_cell_end; ++u) {
              // Start just in front of the nearest cube of a negative voxel: no crossing can end
              // before it.
              const float z_surface =
                  std::max(surface_row[u / kSurfaceCell] - surface_margin, z_all);
              const bool skip = z_surface <= z_end && z_surface > z_all;
              const float z_begin = skip ? z_surface : z_all, z_skipped = skip ? z_all : -1.f;
              tasks[num_tasks++] = {row_i + size_t(u - u0), u, v, z_begin, z_end, z_skipped};
            }
          }
        }
      }
      caster->March(tasks, num_tasks, write);
      for (size_t tile = first; tile < last; ++tile) {
        const int u0 = int(tile % size_t(tiles_x)) * kTile,
                  v0 = int(tile / size_t(tiles_x)) * kTile;
        const size_t n = size_t(std::min(u0 + kTile, w) - u0);
        for (int v = v0; v < std::min(v0 + kTile, h); ++v) {
          const size_t i = (tile - first) * kTile * kTile + size_t(v - v0) * kTile;
          const size_t px = size_t(v) * size_t(w) + size_t(u0);
          CopyPixels(&images.status.data[px], &out.status[i], n);
          CopyPixels(&images.depth.data[px], &out.depth[i], n);
          CopyPixels(&images.vertex_W.data[px], &out.vertex_W[i], n);
          CopyPixels(&images.normal_W.data[px], &out.normal_W[i], n);
          CopyPixels(&images.color.data[px], &out.color[i], n);
        }
      }
    }
#if defined(__SSE2__)
    _mm_sfence();  // the streaming stores are weakly ordered: done before the work item ends
#endif
  });
}

RaycastImages Raycast(const TsdfVolume& volume, const PinholeCamera& camera, const Pose3f& T_W_C,
                      const RaycastParams& params) {
  RaycastImages images;
  Raycast(volume, camera, T_W_C, params, images);
  return images;
}

}  // namespace voxplan
