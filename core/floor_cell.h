#pragma once
// The class of one 2-D floor cell, shared by the planning layer's floor map
// (planning/floor_map.h) and the planner host (plugins/host), which sits on core alone; the
// values match the C ABI's VP_FLOOR_* (asserted in the host).
#include <cstdint>

namespace voxplan {

enum class FloorCell : uint8_t { kUnknown = 0, kFree = 1, kFrontier = 2, kObstacle = 3 };

inline bool IsFree(FloorCell c) { return c == FloorCell::kFree || c == FloorCell::kFrontier; }

}  // namespace voxplan
