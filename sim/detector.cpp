#include "sim/detector.h"

#include <algorithm>
#include <array>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace voxplan {

namespace {

// A uniform draw in [0, 1) per (seed, stream, what, id): each decision has its own number, so
// one object's fate does not shift when another appears in the frame.
double Draw(uint64_t seed, uint64_t stream, uint64_t what, uint64_t id) {
  std::seed_seq seq{seed, stream >> 32, stream & 0xffffffffu, what, id};
  std::mt19937_64 rng(seq);
  return std::uniform_real_distribution<double>(0.0, 1.0)(rng);
}

uint32_t Find(std::vector<uint32_t>& parent, uint32_t id) {
  while (parent[id] != id) id = parent[id] = parent[parent[id]];
  return id;
}

}  // namespace

Status DetectorParams::Validate() const {
  if (!(dropout >= 0.f && dropout <= 1.f) ||
      !(merge_probability >= 0.f && merge_probability <= 1.f))
    return InvalidArgument("detector: dropout and merge probability must be in [0, 1]");
  if (erosion_px < 0 || erosion_px > 16)
    return InvalidArgument("detector: erosion must be 0 to 16 pixels");
  if (min_pixels < 0 || min_pixels > 320 * 240)
    return InvalidArgument("detector: min_pixels must be 0 to 76800 (at 320 x 240)");
  return Status::Ok();
}

bool IsStructureClass(const std::string& class_name) {
  static const std::array<const char*, 6> kStructure = {"wall", "floor",  "ceiling",
                                                        "door", "window", "structure"};
  return std::find(kStructure.begin(), kStructure.end(), class_name) != kStructure.end();
}

DetectorStats ApplyDetector(LabelImage& labels, const std::vector<uint8_t>& structure_by_id,
                            const DetectorParams& params, uint64_t seed, uint64_t stream) {
  DetectorStats stats;
  const int w = labels.width, h = labels.height;
  uint32_t max_id = 0;
  for (uint32_t id : labels.data) max_id = std::max(max_id, id);
  // Per id in this frame (ids are a world's dense instance numbers).
  std::vector<uint8_t> object(size_t(max_id) + 1, 0);
  std::vector<size_t> pixels(size_t(max_id) + 1, 0);
  for (uint32_t id : labels.data) ++pixels[id];
  for (uint32_t id = 1; id <= max_id; ++id)
    object[id] = pixels[id] > 0 && !(id < structure_by_id.size() && structure_by_id[id]);
  for (uint32_t id = 1; id <= max_id; ++id) stats.objects_in += object[id];
  if (!params.noise) {
    stats.objects_out = stats.objects_in;
    return stats;
  }

  // Merges: touching pairs (4-neighbours) in sorted order, each with its own draw.
  std::set<std::pair<uint32_t, uint32_t>> touching;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint32_t a = labels.at(x, y);
      if (!object[a]) continue;
      if (x + 1 < w) {
        const uint32_t b = labels.at(x + 1, y);
        if (b != a && object[b]) touching.emplace(std::min(a, b), std::max(a, b));
      }
      if (y + 1 < h) {
        const uint32_t b = labels.at(x, y + 1);
        if (b != a && object[b]) touching.emplace(std::min(a, b), std::max(a, b));
      }
    }
  std::vector<uint32_t> parent(size_t(max_id) + 1);
  for (uint32_t id = 0; id <= max_id; ++id) parent[id] = id;
  std::vector<size_t> blob = pixels;
  for (const auto& [a, b] : touching) {
    if (Draw(seed, stream, 1, (uint64_t(a) << 32) | b) >= params.merge_probability) continue;
    const uint32_t ra = Find(parent, a), rb = Find(parent, b);
    if (ra == rb) continue;
    // The larger keeps its id (ties: the lower id).
    const bool a_wins = blob[ra] > blob[rb] || (blob[ra] == blob[rb] && ra < rb);
    const uint32_t keep = a_wins ? ra : rb, gone = a_wins ? rb : ra;
    parent[gone] = keep;
    blob[keep] += blob[gone];
    ++stats.merged;
  }
  // Dropout per detection (after merging: a merged blob is one detection).
  std::vector<uint32_t> out_id(size_t(max_id) + 1, 0);
  for (uint32_t id = 0; id <= max_id; ++id) out_id[id] = id;
  for (uint32_t id = 1; id <= max_id; ++id) {
    if (!object[id]) continue;
    const uint32_t root = Find(parent, id);
    const bool dropped = Draw(seed, stream, 2, root) < params.dropout;
    out_id[id] = dropped ? 0u : root;
    stats.dropped += dropped && root == id;
  }
  const LabelImage rendered = labels;
  for (uint32_t& id : labels.data) id = out_id[id];

  // Erosion against the rendered boundaries: a pixel near another rendered label loses its own.
  const int r = params.erosion_px;
  if (r > 0) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const uint32_t own = rendered.at(x, y);
        if (own == 0 || labels.at(x, y) == 0) continue;
        bool boundary = false;
        for (int v = std::max(0, y - r); v <= std::min(h - 1, y + r) && !boundary; ++v)
          for (int u = std::max(0, x - r); u <= std::min(w - 1, x + r) && !boundary; ++u)
            boundary = rendered.at(u, v) != own;
        if (boundary) labels.at(x, y) = 0;
      }
  }
  // Minimum size, on what is left.
  std::vector<size_t> left(size_t(max_id) + 1, 0);
  for (uint32_t id : labels.data) ++left[id];
  const double min_pixels = double(params.min_pixels) * double(w) * double(h) / (320.0 * 240.0);
  std::vector<uint8_t> small(size_t(max_id) + 1, 0);
  for (uint32_t id = 1; id <= max_id; ++id) {
    if (!object[id] || left[id] == 0) continue;
    small[id] = double(left[id]) < min_pixels;
    stats.too_small += small[id];
    stats.objects_out += !small[id];
  }
  for (uint32_t& id : labels.data)
    if (small[id]) id = 0;
  return stats;
}

}  // namespace voxplan
