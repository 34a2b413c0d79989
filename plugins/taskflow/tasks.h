// The two task generators of the task-flow planner (Guo et al. 2022 §4) over the host's world:
// exploration views on the floor raster's frontiers (G§4.1) and reconstruction views of the
// objects the geometric completion finds incomplete (G§4.2), with the memories that keep a round
// from offering what earlier rounds already tried in vain.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "plugins/planner_cpp.h"
#include "plugins/taskflow/algorithms/completion.h"
#include "plugins/taskflow/algorithms/explore_tasks.h"
#include "plugins/taskflow/algorithms/recon_views.h"

namespace voxplan::taskflow {

struct TaskOptions {
  ExploreParams explore;
  CompletionParams completion;
  // A view must cover a tenth of the object's initial incompleteness (the library's 5 % sends
  // views that add a handful of points, at a reconstructor's 0.2 m/s).
  ReconViewParams views = [] {
    ReconViewParams p;
    p.min_gain_fraction = 0.1f;
    return p;
  }();
  // A round gains when the object's observed surface grows by 5 %: fewer new voxels are what
  // depth noise adds to any surface seen again.
  HistoryParams history = {
      .neighbourhood_m = 0.5f, .strikes = 3, .min_gain_abs = 0.0, .min_gain_rel = 0.05};
  bool completion_on = true;         // "completion": "none" gives frontier tasks only
  double clearance_margin_m = 0.05;  // beyond the robot radius, as the host routes
  int min_object_voxels = 20;        // smaller instances are detector noise, not objects
  // Incomplete objects are served most incomplete first until the round holds this many views
  // per robot, trying at most max_objects_per_round of them.
  int recon_views_per_robot = 2;
  int max_objects_per_round = 12;
  // Rounds of views an object gets at most; and none after a round that gained nothing (its
  // surface grew by less than history.min_gain_rel since the views were sent). The paper's
  // history (three no-gain scans close a neighbourhood) never closes an object whose hidden
  // side faces a wall: the completion keeps predicting it, every new neighbourhood looks worth
  // a try, and a run of 60 objects does not end.
  int max_rounds_per_object = 2;
  // The completion is recomputed when an object's surface grew (or shrank) by this share since
  // it was last completed: every frame adds a voxel or two, and a completion costs ~30 ms.
  double recomplete_share = 0.05;
  int frontier_tries = 2;             // a frontier covered this often and still there is settled
  float frontier_key_m = 0.25f;       // frontier memory cell
  float view_dwell_s = 0.5f;          // explorer: at the view, before the sweep
  float sweep_half_rad = 0.5235988f;  // the head's tilt up and down at a view: +-30 deg ...
  float sweep_step_rad = 0.5235988f;  // ... in 30 deg steps (G L97 gives no angles)
  float recon_dwell_s = 1.0f;
};

// One object's state across rounds: its last completion (recomputed when its surface changed).
struct ObjectState {
  size_t voxels = 0;
  CompletionResult completion;
  // The surface size at which view selection last found nothing (a hidden side against a wall):
  // not tried again until the object's surface changes.
  size_t no_views_at = 0;
  int rounds = 0;          // rounds it was given views in
  size_t voxels_sent = 0;  // its surface when its last views were sent
};

// A generated task before assignment.
struct Candidate {
  Eigen::Vector2d xy_m = Eigen::Vector2d::Zero();
  float theta_rad = 0.f;
  bool reconstruction = false;
  ReconView recon;          // with reconstruction
  std::vector<int> covers;  // exploration: frontier memory keys it covers (index into a table)
};

struct GenerationStats {
  int frontier_samples = 0, exploration_views = 0, settled_frontiers = 0;
  int objects = 0, objects_completed = 0, objects_incomplete = 0, reconstruction_views = 0;
  double explore_ms = 0.0, completion_ms = 0.0, recon_ms = 0.0;
  std::vector<std::pair<int, double>> incompleteness;  // per object id, the completion's mean S̄
};

class TaskGenerator {
 public:
  explicit TaskGenerator(TaskOptions options) : options_(std::move(options)) {}

  // This round's candidates. queued_objects: objects some robot already has a task for.
  std::vector<Candidate> Generate(const vp::WorldView& world, float radius_m,
                                  const std::set<int>& queued_objects, uint64_t seed,
                                  GenerationStats* stats);
  // The exploration candidates that were sent: their frontiers count one more try.
  void Sent(const std::vector<Candidate>& sent);
  // The reconstruction views that were sent, per object (the history's round).
  void SentViews(int object_id, const std::vector<ReconView>& views);

 private:
  using Key = std::pair<long, long>;
  Key KeyOf(const Eigen::Vector2d& xy) const;
  std::vector<Candidate> Exploration(const vp::WorldView& world, float clearance_m,
                                     GenerationStats* stats);
  std::vector<Candidate> Reconstruction(const vp::WorldView& world, float clearance_m,
                                        const std::set<int>& queued_objects, uint64_t seed,
                                        GenerationStats* stats);

  TaskOptions options_;
  std::map<Key, int> frontier_tries_;  // frontier memory cell -> views sent that covered it
  std::vector<Key> keys_;              // this round's frontier sample keys (Candidate::covers)
  std::map<int, ObjectState> objects_;
  ReconHistory history_;
};

// Whether an instance label is scene structure (walls, floors, ...), the host's convention
// (sim/detector.h): never an object to reconstruct.
bool IsStructureLabel(const std::string& label);

}  // namespace voxplan::taskflow
