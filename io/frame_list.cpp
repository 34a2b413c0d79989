#include "io/frame_list.h"

#include <nlohmann/json.hpp>

#include "io/file_util.h"
#include "io/text_file.h"

namespace voxplan {

std::string FrameListJson(const FrameListParams& params, const std::vector<FrameListEntry>& frames,
                          int indent) {
  nlohmann::json list = nlohmann::json::array();
  for (const FrameListEntry& f : frames) {
    const Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T = f.T_W_C;
    list.push_back({{"depth", f.depth_path},
                    {"color", f.color_path},
                    {"T_W_C", std::vector<double>(T.data(), T.data() + 16)}});
  }
  const PinholeCamera& c = params.camera;
  const nlohmann::json j = {{"width", c.width},
                            {"height", c.height},
                            {"fx", ShortestDouble(c.fx)},
                            {"fy", ShortestDouble(c.fy)},
                            {"cx", ShortestDouble(c.cx)},
                            {"cy", ShortestDouble(c.cy)},
                            {"depth_scale", params.depth_scale},
                            {"voxel_size_m", params.voxel_size_m},
                            {"trunc_m", params.trunc_m},
                            {"min_depth_m", params.min_depth_m},
                            {"max_depth_m", params.max_depth_m},
                            {"frames", std::move(list)}};
  return j.dump(indent) + "\n";
}

Status WriteFrameList(const std::string& path, const FrameListParams& params,
                      const std::vector<FrameListEntry>& frames) {
  const std::string text = FrameListJson(params, frames, 2);
  return WriteFileAtomically(path, text);
}

}  // namespace voxplan
