// PlanningMap's label fusion: per-voxel instance label candidates fused from labelled frames
// (space-saving counts), and the object instances they add up to. Kept apart from the state,
// frontier and surface maps of planning_map.cpp, which never read labels.
#include <algorithm>
#include <limits>
#include <map>

#include "core/parallel.h"
#include "planning/planning_map.h"

namespace voxplan {

namespace {

// Candidates of one voxel, strongest first (ties: smaller label); zero counts dropped.
std::vector<std::pair<uint32_t, uint16_t>> Candidates(const LabelBlock& lb, int i) {
  std::vector<std::pair<uint32_t, uint16_t>> c;
  for (int k = 0; k < kLabelCandidates; ++k)
    if (lb.count[i][k] > 0) c.emplace_back(lb.label[i][k], lb.count[i][k]);
  std::sort(c.begin(), c.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
  return c;
}

void AddLabel(LabelBlock& lb, int i, uint32_t label) {
  int empty = -1, weakest = -1;
  for (int k = 0; k < kLabelCandidates; ++k) {
    if (lb.count[i][k] == 0) {
      if (empty < 0) empty = k;
      continue;
    }
    if (lb.label[i][k] == label) {
      if (lb.count[i][k] < std::numeric_limits<uint16_t>::max()) ++lb.count[i][k];
      return;
    }
    if (weakest < 0 || lb.count[i][k] < lb.count[i][weakest]) weakest = k;
  }
  if (empty >= 0) {
    lb.label[i][empty] = label;
    lb.count[i][empty] = 1;
    return;
  }
  // Full: the newcomer wears down the weakest candidate and replaces it at zero.
  if (--lb.count[i][weakest] == 0) {
    lb.label[i][weakest] = label;
    lb.count[i][weakest] = 1;
  }
}

}  // namespace

uint32_t FusedLabel(const LabelBlock& lb, int i) {
  uint32_t best = 0;
  uint16_t best_count = 0;
  for (int k = 0; k < kLabelCandidates; ++k) {
    const uint16_t c = lb.count[i][k];
    if (c > best_count || (c == best_count && c > 0 && lb.label[i][k] < best)) {
      best = lb.label[i][k];
      best_count = c;
    }
  }
  return best;
}

Status PlanningMap::FuseLabels(const DepthImage& depth, const LabelImage& labels,
                               const PinholeCamera& camera, const Pose3f& T_W_C,
                               const std::vector<BlockIndex>& blocks, float min_depth_m,
                               float max_depth_m) {
  if (!camera.Valid()) return InvalidArgument("camera intrinsics are invalid");
  if (depth.width != camera.width || depth.height != camera.height)
    return InvalidArgument("depth image size differs from the camera's");
  if (labels.width != depth.width || labels.height != depth.height)
    return InvalidArgument("label image is " + std::to_string(labels.width) + "x" +
                           std::to_string(labels.height) + " but the depth image is " +
                           std::to_string(depth.width) + "x" + std::to_string(depth.height));
  if (!T_W_C.matrix().allFinite()) return InvalidArgument("camera pose has NaN or infinite values");

  const Pose3f T_C_W = T_W_C.inverse();
  const Eigen::Matrix3f R = T_C_W.linear();
  const Eigen::Vector3f t = T_C_W.translation();
  const float s = volume_->voxel_size_m();
  const float band_m = params_.label_band_vox * s;
  // Phase 1, per block in parallel: the (voxel, label) observations, in voxel order.
  std::vector<std::vector<std::pair<uint16_t, uint32_t>>> obs(blocks.size());
  ParallelFor(blocks.size(), 8, [&](size_t begin, size_t end) {
    for (size_t j = begin; j < end; ++j) {
      const BlockIndex b = blocks[j];
      for (int i = 0; i < kBlockVoxels; ++i) {
        const Eigen::Vector3f p_C = R * VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), s) + t;
        if (!(p_C.z() > 0.f)) continue;
        const float uf = camera.fx * p_C.x() / p_C.z() + camera.cx + 0.5f;
        const float vf = camera.fy * p_C.y() / p_C.z() + camera.cy + 0.5f;
        if (!(uf >= 0.f && uf < float(depth.width) && vf >= 0.f && vf < float(depth.height)))
          continue;
        const size_t pixel = size_t(int(vf)) * size_t(depth.width) + size_t(int(uf));
        const float d = depth.data[pixel];
        const uint32_t label = labels.data[pixel];
        if (label == 0 || !(d >= min_depth_m && d <= max_depth_m)) continue;
        if (std::abs(d - p_C.z()) <= band_m) obs[j].emplace_back(uint16_t(i), label);
      }
    }
  });
  // Phase 2: label blocks allocated serially, then filled in parallel.
  std::vector<LabelBlock*> targets(blocks.size(), nullptr);
  bool any = false;
  for (size_t j = 0; j < blocks.size(); ++j) {
    if (obs[j].empty() || !InPackRange(blocks[j])) continue;
    auto& slot = labels_[PackBlockIndex(blocks[j])];
    if (!slot) slot = std::make_unique<LabelBlock>(LabelBlock{});
    targets[j] = slot.get();
    any = true;
  }
  ParallelFor(blocks.size(), 16, [&](size_t begin, size_t end) {
    for (size_t j = begin; j < end; ++j)
      if (targets[j])
        for (const auto& [i, label] : obs[j]) AddLabel(*targets[j], i, label);
  });
  if (any) ++revision_;
  return Status::Ok();
}

void PlanningMap::SetInstanceClass(uint32_t id, std::string class_name) {
  classes_[id] = std::move(class_name);
}

uint32_t PlanningMap::LabelAt(GlobalVoxelIndex g) const {
  const BlockIndex b = BlockOf(g);
  if (!InPackRange(b)) return 0;
  const auto it = labels_.find(PackBlockIndex(b));
  return it == labels_.end() ? 0 : FusedLabel(*it->second, LinearIndex(LocalOf(g)));
}

std::vector<std::pair<uint32_t, uint16_t>> PlanningMap::LabelCandidatesAt(
    GlobalVoxelIndex g) const {
  const BlockIndex b = BlockOf(g);
  if (!InPackRange(b)) return {};
  const auto it = labels_.find(PackBlockIndex(b));
  return it == labels_.end() ? std::vector<std::pair<uint32_t, uint16_t>>{}
                             : Candidates(*it->second, LinearIndex(LocalOf(g)));
}

std::vector<InstanceRecord> PlanningMap::Instances() const {
  std::vector<uint64_t> keys;
  keys.reserve(labels_.size());
  for (const auto& [key, lb] : labels_) keys.push_back(key);
  // Block order, then voxel order inside: the point lists are then sorted after one final
  // sort per instance by voxel index.
  std::sort(keys.begin(), keys.end(),
            [](uint64_t a, uint64_t b) { return UnpackBlockIndex(a) < UnpackBlockIndex(b); });
  const float s = volume_->voxel_size_m();
  std::map<uint32_t, InstanceRecord> records;
  std::map<uint32_t, std::vector<GlobalVoxelIndex>> surface_voxels;
  for (uint64_t key : keys) {
    const BlockIndex b = UnpackBlockIndex(key);
    const PlanningBlock* pb = FindBlock(b);
    if (!pb) continue;
    const LabelBlock& lb = *labels_.at(key);
    ForEachBit(pb->occupied, [&](int i) {
      const uint32_t id = FusedLabel(lb, i);
      if (id == 0) return;
      const GlobalVoxelIndex g = GlobalOf(b, VoxelOfLinear(i));
      const Eigen::Vector3f lo = VoxelCenter(g, s) - Eigen::Vector3f::Constant(0.5f * s);
      const Eigen::Vector3f hi = lo + Eigen::Vector3f::Constant(s);
      auto [it, fresh] = records.try_emplace(id);
      InstanceRecord& r = it->second;
      if (fresh) {
        r.id = id;
        r.bbox_min_W = lo;
        r.bbox_max_W = hi;
        const auto c = classes_.find(id);
        if (c != classes_.end()) r.class_name = c->second;
      }
      ++r.voxel_count;
      r.bbox_min_W = r.bbox_min_W.cwiseMin(lo);
      r.bbox_max_W = r.bbox_max_W.cwiseMax(hi);
      if (TestBit(pb->surface, i)) surface_voxels[id].push_back(g);
    });
  }
  std::vector<InstanceRecord> out;
  out.reserve(records.size());
  for (auto& [id, r] : records) {
    auto& voxels = surface_voxels[id];
    std::sort(voxels.begin(), voxels.end());
    for (const GlobalVoxelIndex& g : voxels) {
      r.surface_points_W.push_back(VoxelCenter(g, s));
      r.surface_normals_W.push_back(NormalAt(g));
    }
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace voxplan
