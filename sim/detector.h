#pragma once
// The object detector a planner's object map is built from. Guo 2022 segments frames with Mask
// R-CNN (GPU); voxplan labels pixels with the simulator's instance ids and then degrades them
// the way a learned instance segmenter does, per frame:
//   merges     two touching objects come out as one (the smaller takes the larger's id),
//   dropout    an object is missed in this frame,
//   erosion    mask boundaries are unsure: pixels within erosion_px of another label lose theirs,
//   min size   objects smaller than a pixel count (at 320 x 240, scaled by image area) are missed.
// Scene structure (walls, floors, ...: IsStructureClass) is segmented too but never merged,
// dropped or size-filtered: what a detector misses there is not an object either way.
// Deterministic for (seed, stream): the same frame gives the same labels.
#include <cstdint>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/status.h"

namespace voxplan {

struct DetectorParams {
  bool noise = true;  // false: the renderer's labels as they are (the clean bracket)
  float dropout = 0.1f;
  int erosion_px = 2;
  float merge_probability = 0.05f;  // per touching pair of objects, per frame
  int min_pixels = 300;             // at 320 x 240

  Status Validate() const;
};

// The structure classes, as eval/eval_objects.h excludes them: "wall", "floor", "ceiling",
// "door", "window", "structure".
bool IsStructureClass(const std::string& class_name);

struct DetectorStats {
  size_t objects_in = 0;   // object ids in the rendered frame
  size_t objects_out = 0;  // after the noise
  size_t merged = 0, dropped = 0, too_small = 0;
};

// Degrades `labels` in place (kNoInstance = 0 is unlabelled). structure_by_id[id] != 0 marks
// structure ids (ids past its end are objects); stream separates frames (robot and frame).
DetectorStats ApplyDetector(LabelImage& labels, const std::vector<uint8_t>& structure_by_id,
                            const DetectorParams& params, uint64_t seed, uint64_t stream);

}  // namespace voxplan
