#pragma once
// A small grid world for the plugin host tests: 20 x 12 floor cells of 0.25 m, two rooms joined
// by a 3-cell door, an enclosed free pocket no robot can reach, and an unknown patch in the right
// room whose free neighbours are frontier. Voxel states and rays read the floor column at any z.
//
//   y=11  ####################    # obstacle   . free   ? unknown   f frontier
//   y=10  #.#####..#.........#    0, 1 the robots (radius 0.3 m: a cell next to a wall,
//   y= 9  #.#...#..#.........#         0.25 m from it, is too close)
//   y= 8  #.#...#..#....1....#    the pocket x 3..5, y 7..9 is free but sealed
//   y= 7  #.#...#............#    the door x 9, y 5..7
//   y= 6  #.#####............#
//   y= 5  #...........fffffff#
//   y= 4  #........#..f?????f#
//   y= 3  #........#..f?????f#
//   y= 2  #..0.....#..f?????f#
//   y= 1  #........#..f?????f#
//   y= 0  ####################    x = 0 .. 19 left to right

#include <vector>

#include "plugins/host/planner_world.h"

namespace voxplan::test {

class FakeWorld : public PlannerWorld {
 public:
  static constexpr int kWidth = 20, kHeight = 12;
  static constexpr float kCell = 0.25f;
  static constexpr float kRobotRadius = 0.3f;  // a cell next to a wall (0.25 m) is too close

  FakeWorld();

  PlannerMapInfo MapInfo() const override;
  void VoxelStates(std::span<const Eigen::Vector3f> points,
                   std::span<VoxelState> out) const override;
  void Raycast(std::span<const PlannerRay> rays, std::span<PlannerRayHit> out) const override;
  std::vector<Eigen::Vector3f> FrontierVoxels() const override;
  std::vector<SurfaceVoxel> SurfaceVoxels() const override;
  const PlannerFloor& Floor() const override { return floor_; }
  std::vector<ObjectInstance> Instances() const override;
  std::vector<PlannerRobot> Robots() const override { return robots_; }

  // Cell centre in world metres.
  Eigen::Vector2f Center(int ix, int iy) const { return floor_.CellCenter(ix, iy); }
  FloorCell CellAt(const Eigen::Vector2f& p) const;
  std::vector<PlannerRobot>& robots() { return robots_; }

 private:
  PlannerFloor floor_;
  std::vector<PlannerRobot> robots_;
};

}  // namespace voxplan::test
