#pragma once
// Grid worlds for the plugin host and planner tests.
//
// RasterWorld: a PlannerWorld over a floor raster of any size drawn from rectangles. Voxel states
// and rays read the floor column at any z; surface voxels are the obstacle cells with a free
// 4-neighbour (at z 0.5 m, facing that neighbour, one weight for all); frontier cells (free and
// 8-adjacent to unknown) and clearance (cell centre to the nearest obstacle cell centre) are
// derived by Finish(), which must follow the drawing. Geodesic queries are an 8-connected
// Dijkstra over the floor raster (diagonals never cut an obstacle corner; ties pop in cell order).
//
// FakeWorld: a small hand-made RasterWorld, 20 x 12 floor cells of 0.25 m, two rooms joined by a
// 3-cell door, an enclosed free pocket no robot can reach, and an unknown patch in the right room
// whose free neighbours are frontier.
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

class RasterWorld : public PlannerWorld {
 public:
  // All cells free until drawn; the raster's origin is the world origin.
  RasterWorld(int width, int height, float cell_m);

  // Sets the cells x0..x1, y0..y1 (inclusive, clipped to the raster).
  void Fill(int x0, int y0, int x1, int y1, FloorCell cell);
  // Obstacle cells on the raster's border.
  void Walls();
  // Derives frontier cells and clearance from the drawing; call again after drawing more.
  void Finish();
  // A robot of the given radius at a cell centre, with an explorer (0.6 m/s) and a
  // reconstructor (0.2 m/s) mode; idle with an empty queue.
  PlannerRobot& AddRobot(int ix, int iy, float radius_m);
  void set_surface_weight(float weight) { surface_weight_ = weight; }

  PlannerMapInfo MapInfo() const override;
  void VoxelStates(std::span<const Eigen::Vector3f> points,
                   std::span<VoxelState> out) const override;
  void Raycast(std::span<const PlannerRay> rays, std::span<PlannerRayHit> out) const override;
  std::vector<Eigen::Vector3f> FrontierVoxels() const override;
  std::vector<SurfaceVoxel> SurfaceVoxels() const override;
  const PlannerFloor& Floor() const override { return floor_; }
  std::vector<PlannerRobot> Robots() const override { return robots_; }
  Result<std::vector<float>> GeodesicField(const Eigen::Vector2f& source_m,
                                           float min_clearance_m) const override;
  Result<std::vector<float>> DistanceMatrix(std::span<const Eigen::Vector2f> points_m,
                                            float min_clearance_m) const override;
  Result<std::vector<Eigen::Vector2f>> ShortestPath(const Eigen::Vector2f& from_m,
                                                    const Eigen::Vector2f& to_m,
                                                    float min_clearance_m) const override;

  // Cell centre in world metres.
  Eigen::Vector2f Center(int ix, int iy) const { return floor_.CellCenter(ix, iy); }
  FloorCell CellAt(const Eigen::Vector2f& p) const;
  std::vector<PlannerRobot>& robots() { return robots_; }

 protected:
  PlannerFloor floor_;
  std::vector<PlannerRobot> robots_;
  float surface_weight_ = 2.f;
};

class FakeWorld : public RasterWorld {
 public:
  static constexpr int kWidth = 20, kHeight = 12;
  static constexpr float kCell = 0.25f;
  static constexpr float kRobotRadius = 0.3f;  // a cell next to a wall (0.25 m) is too close

  FakeWorld();
  std::vector<ObjectInstance> Instances() const override;
};

// An apartment for planner tests and timing: border and room walls 2 cells thick, rooms about
// room_m wide joined by 1 m doors, everything from known_x_m on unknown, and `robots` robots of
// radius 0.18 m spread over the known rooms' centres (deterministic). Finished.
RasterWorld ApartmentWorld(float width_m, float height_m, float cell_m, int robots, float known_x_m,
                           float room_m = 3.75f);

}  // namespace voxplan::test
