#pragma once
// A Dataset (io/dataset.h) whose frames are rendered on demand from a mesh at given poses:
// noise-free depth and colour with true poses, so a simulated camera run goes through the same
// fusion pipeline (pipeline/fuse_dataset.h) as a recorded sequence.
#include <memory>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/pose.h"
#include "io/dataset.h"
#include "sim/raycaster.h"

namespace voxplan {

class RenderedDataset : public Dataset {
 public:
  // `raycaster` must outlive the dataset; frame i is rendered at T_W_C[i], timestamp i / 30 s.
  RenderedDataset(const MeshRaycaster& raycaster, const PinholeCamera& camera,
                  std::vector<Pose3d> T_W_C, std::string name);
  const DatasetInfo& info() const override { return info_; }
  Result<Frame> Load(size_t i) const override;

 private:
  const MeshRaycaster& raycaster_;
  std::vector<Pose3d> T_W_C_;
  DatasetInfo info_;
};

}  // namespace voxplan
