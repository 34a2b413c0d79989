#include "sim/rendered_dataset.h"

#include <utility>

namespace voxplan {

namespace {
constexpr double kFrameRateHz = 30.0;
}

RenderedDataset::RenderedDataset(const MeshRaycaster& raycaster, const PinholeCamera& camera,
                                 std::vector<Pose3d> T_W_C, std::string name)
    : raycaster_(raycaster), T_W_C_(std::move(T_W_C)) {
  info_.root = std::move(name);
  info_.camera = camera;
  info_.num_frames = T_W_C_.size();
  info_.has_color = true;
  info_.intrinsics_source = "simulated";
  info_.pose_source = "simulated";
  info_.up = WorldUp::kPlusZ;  // sim worlds are z-up metres
  info_.up_source = "sim convention (worlds are z-up)";
}

Result<Frame> RenderedDataset::Load(size_t i) const {
  if (i >= T_W_C_.size())
    return InvalidArgument("frame " + std::to_string(i) + " of " + std::to_string(T_W_C_.size()) +
                           " rendered frames");
  RenderOutput rendered = raycaster_.Render(info_.camera, T_W_C_[i].cast<float>());
  Frame frame;
  frame.index = i;
  frame.timestamp = double(i) / kFrameRateHz;
  frame.depth = std::move(rendered.depth);
  frame.color = std::move(rendered.color);
  frame.T_W_C = T_W_C_[i];
  return frame;
}

}  // namespace voxplan
