// Reconstruction view selection of Guo et al. 2022 §4.2 (G L135-141, Fig. 4): optic cones around
// the most incomplete predicted point, candidate arm-camera poses on them that the base can reach,
// greedy coverage of the incompleteness scores, and the give-up history (three scans near the same
// place without a completeness gain end the views there).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <span>
#include <vector>

#include "plugins/taskflow/algorithms/completion.h"

namespace voxplan::taskflow {

// Whether the robot's base centre may stand at base_xy (the plugin: floor raster + clearance).
using TraversableFn = std::function<bool(const Eigen::Vector2f& base_xy)>;
// Batch line of sight: visible[i] = 1 when points[i] can be seen from camera (the plugin: the
// host's ray cast against the map). Points are predicted, so they may lie in unobserved space.
using VisibilityFn =
    std::function<void(const Eigen::Vector3f& camera, std::span<const Eigen::Vector3f> points,
                       std::span<std::uint8_t> visible)>;

// Where the arm can put the camera (planner-wave.md §1.4 defaults; the paper's φ range).
struct ArmWorkspace {
  float camera_height_min_m = 0.4f;  // optical centre above the floor
  float camera_height_max_m = 1.5f;
  float reach_min_m = 0.3f;  // horizontal offset of the camera from the base centre
  float reach_max_m = 0.8f;
  float reach_half_angle_rad = 1.5707963f;  // offset bearing within ± this of the base heading
  float min_pitch_rad = -1.5707963f;        // positive looks up
  float max_pitch_rad = 1.5707963f;
};

// The reconstructor's sensor (host defaults: 58° HFOV, 0.2-2.5 m).
struct ReconSensor {
  float hfov_rad = 1.0122910f;
  float min_range_m = 0.2f;
  float max_range_m = 2.5f;
};

struct ReconViewParams {
  ArmWorkspace arm;
  ReconSensor sensor;
  // q's optic cone: half-angle hfov/2, range apex_range_factor × max range (G L139: doubled).
  float apex_range_factor = 2.0f;
  // Candidate cameras: directions in q's cone (its axis plus cone_tilts rings of cone_azimuths,
  // the outer ring on the cone's surface), candidate_distances from q in [distance_min_m,
  // distance_max_m].
  int cone_azimuths = 12;
  int cone_tilts = 2;
  int candidate_distances = 3;
  float distance_min_m = 0.6f;
  float distance_max_m = 1.5f;
  // Base positions tried per candidate camera: bearings across ± reach_half_angle (nearest to
  // straight ahead first) × reaches (longest first, keeping the base away from the object).
  int base_bearings = 7;
  int base_reaches = 3;
  // Greedy selection (G L139): at most this many views per call; a view must gain at least
  // max(min_gain, min_gain_fraction × the initial Σ S̄).
  int max_views_per_object = 3;
  float min_gain = 0.5f;
  float min_gain_fraction = 0.05f;
  // An apex whose cone yields no reachable, worthwhile view is dropped and the next-best point
  // tried, at most this many times per call.
  int max_apex_attempts = 8;
  // Predicted points whose known normal faces away from the camera are hidden (the predicted
  // cloud's self-occlusion; the visibility callback sees only the map).
  bool backface_cull = true;
  // q's cone axis is its predicted normal unless unknown or steeper than this; then the
  // horizontal direction from the object's centre through q (a top face's normal would put every
  // camera above the arm's reach).
  float max_axis_elevation_rad = 0.7853982f;
};

// One object's predicted cloud and scores (for instance a CompletionResult's fields).
struct ReconTarget {
  int object_id = -1;
  float floor_z_m = 0.0f;
  std::span<const Eigen::Vector3f> points;   // C
  std::span<const Eigen::Vector3f> normals;  // parallel to points, or empty; zero = unknown
  std::span<const float> scores;             // S̄_c, parallel to points
};

// Views into c (predicted points, normals, scores): c must outlive the target.
ReconTarget TargetFromCompletion(int object_id, float floor_z_m, const CompletionResult& c);

// A reconstruction task T^rec = (x, y, z, θ, φ) with the base pose that realises it.
struct ReconView {
  int object_id = -1;
  Eigen::Vector3f camera_m = Eigen::Vector3f::Zero();  // W, world frame
  Eigen::Vector3f target_m = Eigen::Vector3f::Zero();  // the predicted point looked at (the apex)
  float yaw_rad = 0.0f;                                // world yaw of the view direction
  float pitch_rad = 0.0f;                              // positive looks up
  Eigen::Vector2f base_xy_m = Eigen::Vector2f::Zero();
  float base_yaw_rad = 0.0f;      // the base faces the view's yaw
  float camera_forward_m = 0.0f;  // camera offset from the base centre, base frame
  float camera_left_m = 0.0f;
  float camera_height_m = 0.0f;  // above the floor
  float coverage = 0.0f;         // Σ S̄ of the predicted points this view newly covers
  int covered_points = 0;
};

// G8: a per-object record of chosen views and whether the object gained completeness after them.
struct HistoryParams {
  float neighbourhood_m = 0.5f;  // views within this distance are "neighbouring"
  int strikes = 3;               // no-gain rounds in a row that close a neighbourhood
  // A round gained when completeness > before × (1 + min_gain_rel) + min_gain_abs.
  double min_gain_abs = 0.0;
  double min_gain_rel = 0.01;
};

struct ScanRecord {
  enum Outcome : std::int8_t { kPending = -1, kNoGain = 0, kGain = 1 };
  Eigen::Vector3f camera_m = Eigen::Vector3f::Zero();
  int round = 0;                     // the object's RecordViews call that chose it
  double completeness_before = 0.0;  // the object's completeness when the view was chosen
  Outcome outcome = kPending;
};

struct ObjectHistory {
  std::vector<ScanRecord> scans;
  int rounds = 0;
};

struct ReconHistory {
  std::map<int, ObjectHistory> objects;  // ordered: deterministic iteration
};

// Start of a round: the object's current completeness (observed point count or a ratio) settles
// the outcome of its pending scans.
void ObserveCompleteness(ReconHistory* history, int object_id, double completeness,
                         const HistoryParams& params);
// End of a round: the views chosen for the object, with its completeness at that time.
void RecordViews(ReconHistory* history, int object_id, std::span<const ReconView> views,
                 double completeness);
// nullptr when the object has no record.
const ObjectHistory* FindHistory(const ReconHistory& history, int object_id);
// True when the latest `strikes` settled rounds with a scan within the neighbourhood of camera
// all gained nothing.
bool NeighbourhoodExhausted(const ObjectHistory& history, const Eigen::Vector3f& camera_m,
                            const HistoryParams& params);

// Greedy views for one object (G L135-139), best first. Deterministic. history (optional) closes
// exhausted neighbourhoods.
std::vector<ReconView> SelectReconViews(const ReconTarget& target, const ReconViewParams& params,
                                        const TraversableFn& traversable,
                                        const VisibilityFn& visible,
                                        const ObjectHistory* history = nullptr,
                                        const HistoryParams& history_params = {});

}  // namespace voxplan::taskflow
