#pragma once
// Per-object reconstruction quality, Guo et al. 2022 sec. 6.2:
//   O-Comp (eq. 6): share of an object's ground-truth samples within threshold_m of the
//                   reconstruction, averaged over the objects of the scene;
//   O-RMS  (eq. 7): mean distance from an object's reconstructed samples to its ground truth,
//                   averaged over the objects that were reconstructed at all.
// Guo segments the reconstruction by instance labels; ours has none, so each reconstruction
// sample belongs to the instance of the closest ground-truth triangle (over the whole world,
// walls included, so wall surface is never counted against a chair beside it). Samples farther
// than max_attribution_distance_m from any ground truth belong to no object.
// Sampling and distances are those of EvaluateMesh (eval/eval_mesh.h).
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/status.h"
#include "sim/world.h"

namespace voxplan {

struct ObjectEvalParams {
  // Guo gives no value for the distance threshold; this is EvaluateMesh's default.
  float threshold_m = 0.05f;
  // More thresholds to report completeness at (ObjectEvalResult::completeness_extra), from the
  // same samples: one evaluation gives Guo's O-Comp at, e.g., 2 cm and 5 cm.
  std::vector<float> extra_thresholds_m;
  float samples_per_m2 = 10000.0f;
  // Small objects still get enough ground-truth samples for a share to mean something.
  size_t min_samples_per_object = 200;
  uint64_t seed = 1;
  float max_attribution_distance_m = std::numeric_limits<float>::infinity();
  // Instances of these classes are scene structure, not objects: not evaluated.
  std::vector<std::string> excluded_classes = {"wall", "floor",  "ceiling",
                                               "door", "window", "structure"};
  // Called with (steps done, steps in all): one step per instance sampled, then one each for the
  // completeness distances, the reconstruction's samples and the accuracy distances. Optional.
  std::function<void(size_t done, size_t total)> progress;
};

struct ObjectEvalResult {
  uint32_t id = kNoInstance;
  std::string class_name;
  std::string model;
  double ground_truth_area_m2 = 0.0;
  size_t ground_truth_samples = 0;
  double completeness = 0.0;               // 0..1 (eq. 6)
  std::vector<double> completeness_extra;  // at each of ObjectEvalParams::extra_thresholds_m
  size_t reconstruction_samples = 0;       // reconstruction samples attributed to this object
  double accuracy_mean_m = 0.0;            // eq. 7; 0 when reconstruction_samples == 0
  double accuracy_rms_m = 0.0;             // root mean square of the same distances
};

struct ObjectsEvalResult {
  std::vector<ObjectEvalResult> objects;  // evaluated instances, in world.instances order
  double o_comp = 0.0;                    // mean completeness over `objects`
  std::vector<double> o_comp_extra;       // the same at each extra threshold
  double o_rms_m = 0.0;  // mean accuracy_mean_m over objects with reconstruction samples (Guo)
  double mean_object_rms_m = 0.0;         // mean accuracy_rms_m over the same objects
  double completeness_all_objects = 0.0;  // share of all object samples covered (area-weighted)
  size_t objects_reconstructed = 0;       // objects with reconstruction samples
  size_t reconstruction_samples = 0;      // all of them, objects or not
  size_t reconstruction_samples_unattributed = 0;  // beyond max_attribution_distance_m
  std::vector<uint32_t> skipped;                   // not excluded, but without triangles with area
};

// Refuses an empty reconstruction, a world whose triangle_instance does not match its mesh, bad
// parameters, and a world with no object left after the exclusions.
Result<ObjectsEvalResult> EvaluateObjects(const Mesh& reconstruction, const World& world,
                                          const ObjectEvalParams& params = {});

}  // namespace voxplan
