// MapScene: bounds from the allocated blocks, one core ray cast per view.
#include "viewer_offscreen/map_scene.h"

#include <algorithm>
#include <utility>

#include "core/index.h"

namespace voxplan {

MapScene::MapScene(TsdfVolume volume, const MapSceneParams& params) : volume_(std::move(volume)) {
  params_.min_weight = params.min_weight;
  params_.simd = params.simd;
  params_.min_depth_m = params.near_m > 0.0f ? params.near_m : 0.01f;
  // From outside a room the walls' backs come first: look through them at the inside.
  params_.stop_at_back_faces = false;
  const float block_m = volume_.block_size_m();
  volume_.ForEachBlock([&](BlockIndex b, const TsdfBlock&) {
    const Eigen::Vector3f lo = BlockOrigin(b, block_m);
    bounds_.extend(lo);
    bounds_.extend(Eigen::Vector3f(lo + Eigen::Vector3f::Constant(block_m)));
  });
}

SurfaceImages MapScene::Render(const PinholeCamera& camera, const Pose3f& T_W_C) const {
  RaycastParams params = params_;
  // Far enough to reach every allocated block from this camera.
  float farthest_m = 0.0f;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3f corner = bounds_.corner(static_cast<Eigen::AlignedBox3f::CornerType>(c));
    farthest_m = std::max(farthest_m, (corner - T_W_C.translation()).norm());
  }
  params.max_depth_m = std::max(farthest_m, params.min_depth_m + 0.1f);
  RaycastImages r = Raycast(volume_, camera, T_W_C, params);
  SurfaceImages s;
  s.depth = std::move(r.depth);
  s.vertex_W = std::move(r.vertex_W);
  s.normal_W = std::move(r.normal_W);
  // A map fused without colour stores black: shade it neutral grey instead.
  bool any_colour = false;
  for (size_t i = 0; i < s.depth.data.size() && !any_colour; ++i)
    any_colour = s.depth.data[i] > 0.0f && (r.color.data[i] & 0xffffffu) != 0;
  if (any_colour) s.color = std::move(r.color);
  return s;
}

}  // namespace voxplan
