#include "plugins/host/planner_world.h"

#include <cmath>

namespace voxplan {

Eigen::Vector2i PlannerFloor::CellOf(const Eigen::Vector2f& p_W) const {
  const Eigen::Vector2f q = (p_W - origin_m) / cell_size_m;
  return {int(std::floor(q.x())), int(std::floor(q.y()))};
}

bool PlannerFloor::Traversable(int ix, int iy, float min_clearance_m) const {
  if (!Contains(ix, iy)) return false;
  const size_t i = Linear(ix, iy);
  return IsFree(cells[i]) && clearance_m[i] >= min_clearance_m;
}

}  // namespace voxplan
