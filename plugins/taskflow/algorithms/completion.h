// GPU-free shape completion and the incompleteness score of Guo et al. 2022 §4.2 (G eq. 1). The
// paper predicts an object's complete cloud with GR-Net; here a geometric prior stands in for it
// (planner-wave.md §1.4, F.2 item 2): the union of a floor-supported box, a mirror image about a
// vertical plane and the footprint's extruded hull, minus whatever lands in observed free space.
// The paper notes the prediction "doesn't have to be very precise": it only points at the holes.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace voxplan::taskflow {

// What the map says about a point: never observed, observed free, or observed occupied.
enum SpaceState : std::uint8_t { kUnobserved = 0, kObservedFree = 1, kObservedOccupied = 2 };

// Batch query of the observed map: fills state[i] (a SpaceState) for points[i], world frame.
using SpaceQuery =
    std::function<void(std::span<const Eigen::Vector3f> points, std::span<std::uint8_t> state)>;

// How the box's footprint orientation is found.
enum class BoxFit {
  kMinAreaRect,  // smallest rectangle around the footprint hull (exact for boxes)
  kPca,          // principal axes of the footprint (the design's wording; ill-posed when square)
};

struct CompletionParams {
  int sample_count = 2048;          // N of G eq. 1: observed points kept (all of them when fewer)
  int max_predicted = 2048;         // the predicted cloud C is farthest-point sampled to this size
  int max_part_points = 8192;       // a part's raw samples; its spacing grows to stay under this
  float surface_spacing_m = 0.03f;  // spacing of synthesised surface samples

  bool use_box = true;       // (a) floor-supported oriented box
  bool use_symmetry = true;  // (b) mirror image about a vertical plane through the box centre
  bool use_hull = true;      // (c) the footprint's convex hull, extruded floor to top
  BoxFit box_fit = BoxFit::kMinAreaRect;

  // The box grows each side face outward into space that is not observed free, in steps, by at
  // most box_max_growth times its extent along that axis (1: the hidden part may be as deep as
  // the seen one). Without this a half-seen object's box ends where the observation does.
  bool box_grow = true;
  float box_grow_step_m = 0.025f;
  float box_max_growth = 1.0f;
  float box_grow_max_free = 0.1f;  // a step is refused when this share of its face is free

  // Mirror symmetry: symmetry_angles plane normals over [0, π). A plane is accepted when at
  // least symmetry_min_plausible of the reflected points land on occupied or unobserved space
  // and fewer than symmetry_max_free in observed free space (planner-wave.md F.2). A reflected
  // point within symmetry_support_m of an observed one counts as occupied whatever the map says
  // (a voxelised map calls half the points next to a surface free).
  int symmetry_angles = 36;
  float symmetry_min_plausible = 0.6f;
  float symmetry_max_free = 0.1f;
  float symmetry_support_m = 0.04f;

  // Completeness filter (G L133) and the absolute floor added to it (see CompletionResult).
  float tau = 0.2f;
  float min_max_distance_m = 0.10f;
  // missing_share counts predicted points farther than this from every observed point.
  float missing_distance_m = 0.05f;
};

// One candidate mirror plane: vertical, through `centre`, with normal (cos a, sin a, 0).
struct MirrorPlaneCheck {
  float angle_rad = 0.0f;
  float plausible_share = 0.0f;  // reflected points on occupied or unobserved space
  float free_share = 0.0f;       // reflected points in observed free space
  int new_points = 0;            // plausible reflections farther than symmetry_support_m from P
  int outside_box = 0;           // reflections outside the grown box (CompleteObject only)
  bool accepted = false;
};

struct CompletionResult {
  std::vector<Eigen::Vector3f> observed;   // P: the sampled observed points
  std::vector<Eigen::Vector3f> predicted;  // C: the predicted complete cloud
  std::vector<Eigen::Vector3f> normals;    // per predicted point, outward; zero when unknown
  std::vector<float> distance_m;           // S_c(q) = min_p |q - p| (G eq. 1)
  std::vector<float> score;                // S̄_c(q) = S_c(q) / max S_c
  float mean_score = 0.0f;                 // mean S̄_c over C
  float max_distance_m = 0.0f;             // max S_c
  float missing_share = 0.0f;              // share of C farther than missing_distance_m from P
  // Deviation from the paper: the max-normalised mean is scale-free, so a nearly complete object
  // with millimetre residuals can still score ≥ τ. Incomplete = mean ≥ τ AND max S_c ≥ the
  // absolute floor (min_max_distance_m, two planning voxels by default).
  bool incomplete = false;
  // For ranking objects (G L133 ranks by the mean): mean_score when incomplete, else 0.
  float incompleteness = 0.0f;

  // Which parts contributed (before the free-space drop).
  bool used_box = false;
  bool used_symmetry = false;
  bool used_hull = false;
  MirrorPlaneCheck symmetry;  // the best plane tried (accepted or not)
  int dropped_free = 0;       // predicted samples removed for lying in observed free space

  // The (grown) box: centre at mid-height, axes in xy, half extents along (axis0, axis1, z).
  Eigen::Vector3f box_centre = Eigen::Vector3f::Zero();
  Eigen::Vector2f box_axis0 = Eigen::Vector2f::UnitX();
  Eigen::Vector3f box_half_extent = Eigen::Vector3f::Zero();
};

// Shape completion and G eq. 1 for one object. points (world frame, Z up) are the object's
// observed surface; normals are parallel to them or empty (zero rows mean unknown). floor_z_m is
// the floor under the object. Deterministic for a given input and seed. Empty input gives an
// empty, complete result.
CompletionResult CompleteObject(std::span<const Eigen::Vector3f> points,
                                std::span<const Eigen::Vector3f> normals, float floor_z_m,
                                const SpaceQuery& space, const CompletionParams& params,
                                std::uint64_t seed);

// Reflection of every point about one vertical plane, scored against the map (used by
// CompleteObject for each candidate angle; exposed for tests and diagnostics).
MirrorPlaneCheck CheckMirrorPlane(std::span<const Eigen::Vector3f> points,
                                  const Eigen::Vector2f& centre_xy, float angle_rad,
                                  const SpaceQuery& space, const CompletionParams& params);

// Farthest-point sampling of at most `count` indices, starting from a seeded index: a uniform,
// deterministic spread (ties go to the lower index).
std::vector<int> FarthestPointSample(std::span<const Eigen::Vector3f> points, int count,
                                     std::uint64_t seed);

// Distance from each query to its nearest reference point (a k-d tree); +inf when there are no
// reference points.
std::vector<float> NearestDistances(std::span<const Eigen::Vector3f> reference,
                                    std::span<const Eigen::Vector3f> queries);

// Convex hull of 2-D points, counter-clockwise, no collinear points (Andrew's monotone chain).
std::vector<Eigen::Vector2f> ConvexHull2d(std::vector<Eigen::Vector2f> points);

}  // namespace voxplan::taskflow
