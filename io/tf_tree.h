#pragma once
// A ROS TF tree read from a bag's /tf and /tf_static: each frame's transform from its parent,
// stamped (interpolated in time as TUM ground truth is) or static. Looks up a frame's pose in the
// root of its tree. Internal to the ROS bag reader (io/dataset_rosbag.cpp).
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "io/dataset_internal.h"

namespace voxplan::dataset {

class TfTree {
 public:
  // T_parent_child at time t (ignored when static). A frame has one parent: transforms naming
  // another parent for a frame that has one are counted in conflicts() and not used.
  void Add(const std::string& parent, const std::string& child, double t, const Pose3d& T,
           bool is_static);
  // Sorts each frame's transforms by time; call once after the last Add.
  void Finish();

  bool Has(const std::string& frame) const { return edges_.count(Bare(frame)) > 0; }
  size_t conflicts() const { return conflicts_; }

  // T_root_frame at time t, composing the chain up to the root (at most kMaxDepth frames);
  // none when the frame is unknown, the chain loops, or a stamped link has no pose around t
  // within max_gap_s. *root names the root; *why says what failed, *in_gap whether that was a
  // gap longer than max_gap_s.
  std::optional<Pose3d> Lookup(const std::string& frame, double t, double max_gap_s,
                               std::string* root, std::string* why, bool* in_gap) const;

  static constexpr int kMaxDepth = 64;
  // Frame names without their leading '/', as tf2 compares them (ROS 1 bags mix both).
  static std::string Bare(const std::string& frame) {
    return frame.empty() || frame[0] != '/' ? frame : frame.substr(1);
  }

 private:
  struct Edge {
    std::string parent;
    bool is_static = false;
    Pose3d T_static = Pose3d::Identity();
    std::vector<StampedPose> stamped;  // T_parent_child over time
  };
  std::map<std::string, Edge> edges_;  // by child frame
  size_t conflicts_ = 0;
};

}  // namespace voxplan::dataset
