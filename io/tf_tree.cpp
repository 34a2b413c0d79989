#include "io/tf_tree.h"

#include <algorithm>

#include "io/text_file.h"

namespace voxplan::dataset {

void TfTree::Add(const std::string& parent, const std::string& child, double t, const Pose3d& T,
                 bool is_static) {
  auto [it, inserted] = edges_.try_emplace(Bare(child));
  Edge& e = it->second;
  if (inserted) e.parent = Bare(parent);
  if (e.parent != Bare(parent)) {
    ++conflicts_;
    return;
  }
  if (is_static) {
    e.is_static = true;
    e.T_static = T;
  } else {
    e.stamped.push_back({t, T.translation(), Eigen::Quaterniond(T.linear())});
  }
}

void TfTree::Finish() {
  for (auto& [child, e] : edges_)
    std::stable_sort(e.stamped.begin(), e.stamped.end(),
                     [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; });
}

std::optional<Pose3d> TfTree::Lookup(const std::string& frame, double t, double max_gap_s,
                                     std::string* root, std::string* why, bool* in_gap) const {
  *in_gap = false;
  Pose3d T_root_frame = Pose3d::Identity();
  std::string at = Bare(frame);
  for (int depth = 0; depth <= kMaxDepth; ++depth) {
    auto it = edges_.find(at);
    if (it == edges_.end()) {
      if (depth == 0) {
        *why = "frame '" + frame + "' is not in the TF tree";
        return std::nullopt;
      }
      *root = at;
      return T_root_frame;
    }
    const Edge& e = it->second;
    Pose3d T_parent_child = e.T_static;
    // A frame with stamped transforms follows them (a static one alone is fixed).
    if (!e.stamped.empty()) {
      double gap_from = 0.0, gap_to = 0.0;
      std::optional<Pose3d> T = InterpolatePose(e.stamped, t, max_gap_s, &gap_from, &gap_to);
      if (!T) {
        *in_gap = gap_to > gap_from;
        *why = gap_to > gap_from ? "TF " + e.parent + " -> " + at + " has a gap from " +
                                       NumberText(gap_from) + " to " + NumberText(gap_to) + " s"
                                 : "TF " + e.parent + " -> " + at + " has no transforms around " +
                                       NumberText(t) + " s";
        return std::nullopt;
      }
      T_parent_child = *T;
    }
    T_root_frame = T_parent_child * T_root_frame;
    at = e.parent;
  }
  *why = "TF chain from '" + frame + "' is longer than " + std::to_string(kMaxDepth) +
         " frames (a loop?)";
  return std::nullopt;
}

}  // namespace voxplan::dataset
