// Worlds from files: the AWS small house with its instance table, round trips through WriteWorld,
// refusals of bad input, and RasterizeFloorPlan on hand-made rooms with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "sim/apartment.h"
#include "sim/floor_plan.h"
#include "sim/scene_loader.h"
#include "sim/world_io.h"
#include "tests/sim/world_boxes.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

using test::AddBox;

// An upward-facing quad at height z over [x0, x1] x [y0, y1].
void AddFloorQuad(World* world, float x0, float y0, float x1, float y1, float z, uint32_t id) {
  Mesh& m = world->mesh;
  const uint32_t b = uint32_t(m.positions.size());
  m.positions.emplace_back(x0, y0, z);
  m.positions.emplace_back(x1, y0, z);
  m.positions.emplace_back(x1, y1, z);
  m.positions.emplace_back(x0, y1, z);
  m.triangles.push_back({b, b + 1, b + 2});
  m.triangles.push_back({b, b + 2, b + 3});
  world->triangle_instance.push_back(id);
  world->triangle_instance.push_back(id);
  world->instances.push_back(
      {id, "floor", "floor",
       Eigen::AlignedBox3f(Eigen::Vector3f(x0, y0, z), Eigen::Vector3f(x1, y1, z))});
}

// A 4 x 3 m room: floor [0, 4] x [0, 3], 0.1 m walls around it (closed boxes, no floor under
// them), a table top slab in the band, a low box below the band, a shelf above it.
World BoxRoom() {
  World w;
  w.name = "box_room";
  AddFloorQuad(&w, 0, 0, 4, 3, 0, 1);
  AddBox(&w, {-0.1f, -0.1f, 0}, {4.1f, 0, 2.5f}, 2, "wall");
  AddBox(&w, {-0.1f, 3, 0}, {4.1f, 3.1f, 2.5f}, 3, "wall");
  AddBox(&w, {-0.1f, 0, 0}, {0, 3, 2.5f}, 4, "wall");
  AddBox(&w, {4, 0, 0}, {4.1f, 3, 2.5f}, 5, "wall");
  AddBox(&w, {1, 1, 0.7f}, {2, 1.5f, 0.75f}, 6, "table");
  AddBox(&w, {3, 2, 0}, {3.5f, 2.5f, 0.05f}, 7, "carpet");
  AddBox(&w, {0.5f, 0.5f, 2.0f}, {1, 1, 2.2f}, 8, "shelf");
  return w;
}

std::map<PlanCell, int> Count(const FloorPlan& plan) {
  std::map<PlanCell, int> n;
  for (PlanCell c : plan.cells) ++n[c];
  return n;
}

PlanCell CellAt(const FloorPlan& plan, float x, float y) {
  const int ix = int(std::floor((x - plan.origin_W.x()) / plan.resolution_m));
  const int iy = int(std::floor((y - plan.origin_W.y()) / plan.resolution_m));
  EXPECT_TRUE(plan.Contains(ix, iy)) << x << ", " << y;
  return plan.Contains(ix, iy) ? plan.at(ix, iy) : PlanCell::kOutside;
}

TEST(FloorPlan, BoxRoomKnownAnswer) {
  const World w = BoxRoom();
  Result<FloorPlan> plan = RasterizeFloorPlan(w);
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  EXPECT_FLOAT_EQ(plan->resolution_m, 0.05f);
  const auto n = Count(*plan);
  // Free: the 80 x 60 floor cells minus the 20 x 10 under the table top.
  EXPECT_EQ(n.at(PlanCell::kFree), 80 * 60 - 20 * 10);
  // Obstacles: the table and the two-cell wall ring (84 x 64 - 80 x 60 cells), no cell more:
  // faces on cell borders do not spill into the neighbouring cell.
  EXPECT_EQ(n.at(PlanCell::kObstacle), 20 * 10 + (84 * 64 - 80 * 60));
  EXPECT_EQ(CellAt(*plan, 1.5f, 1.25f), PlanCell::kObstacle);   // under the table
  EXPECT_EQ(CellAt(*plan, 3.25f, 2.25f), PlanCell::kFree);      // low box below the band
  EXPECT_EQ(CellAt(*plan, 0.75f, 0.75f), PlanCell::kFree);      // under the high shelf
  EXPECT_EQ(CellAt(*plan, -0.05f, 1.5f), PlanCell::kObstacle);  // wall core
  EXPECT_EQ(CellAt(*plan, 0.02f, 1.5f), PlanCell::kFree);       // against the wall
  EXPECT_EQ(CellAt(*plan, -0.12f, 1.5f), PlanCell::kOutside);   // outside the wall

  // Without filling solids the wall cores, which no face in the band crosses, read as free (the
  // walls' bottom faces are floor-like): what fill_solids is for.
  FloorPlanParams no_fill;
  no_fill.fill_solids = false;
  Result<FloorPlan> open = RasterizeFloorPlan(w, no_fill);
  ASSERT_TRUE(open.ok());
  EXPECT_EQ(Count(*open).at(PlanCell::kFree), 80 * 60 - 20 * 10 + (84 * 64 - 80 * 60));
  EXPECT_EQ(CellAt(*open, -0.05f, 1.5f), PlanCell::kFree);

  // A coarser, misaligned grid is conservative: every cell the table touches is an obstacle.
  FloorPlanParams coarse;
  coarse.resolution_m = 0.07f;
  Result<FloorPlan> c = RasterizeFloorPlan(w, coarse);
  ASSERT_TRUE(c.ok());
  for (float x = 1.0f; x <= 2.0f; x += 0.01f)
    for (float y = 1.0f; y <= 1.5f; y += 0.01f)
      ASSERT_EQ(CellAt(*c, x, y), PlanCell::kObstacle) << x << ", " << y;
}

TEST(FloorPlan, SlantedAndDiagonalGeometry) {
  World w;
  AddFloorQuad(&w, 0, 0, 4, 4, 0, 1);
  // A single-sided vertical panel along a diagonal, 0..2.5 m high.
  Mesh& m = w.mesh;
  uint32_t b = uint32_t(m.positions.size());
  m.positions.emplace_back(0.5f, 0.5f, 0.0f);
  m.positions.emplace_back(3.5f, 2.5f, 0.0f);
  m.positions.emplace_back(3.5f, 2.5f, 2.5f);
  m.positions.emplace_back(0.5f, 0.5f, 2.5f);
  m.triangles.push_back({b, b + 1, b + 2});
  m.triangles.push_back({b, b + 2, b + 3});
  w.triangle_instance.insert(w.triangle_instance.end(), 2, 2);
  w.instances.push_back({2, "panel", "panel", {}});
  // A ramp from z = 0 at x = 0 to z = 4 at x = 4 over y in [3, 4], facing down (its underside
  // is what an upward ray meets: a single-sided face seen from its back would read as the inside
  // of a solid): only x in [0.1, 1.8] crosses the band.
  b = uint32_t(m.positions.size());
  m.positions.emplace_back(0.0f, 3.0f, 0.0f);
  m.positions.emplace_back(4.0f, 3.0f, 4.0f);
  m.positions.emplace_back(4.0f, 4.0f, 4.0f);
  m.positions.emplace_back(0.0f, 4.0f, 0.0f);
  m.triangles.push_back({b, b + 2, b + 1});
  m.triangles.push_back({b, b + 3, b + 2});
  w.triangle_instance.insert(w.triangle_instance.end(), 2, 3);
  w.instances.push_back({3, "ramp", "ramp", {}});
  Result<FloorPlan> plan = RasterizeFloorPlan(w);
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  for (float t = 0.0f; t <= 1.0f; t += 0.002f) {
    const Eigen::Vector2f p = Eigen::Vector2f(0.5f, 0.5f) + t * Eigen::Vector2f(3.0f, 2.0f);
    ASSERT_EQ(CellAt(*plan, p.x(), p.y()), PlanCell::kObstacle) << p.transpose();
  }
  EXPECT_EQ(CellAt(*plan, 2.0f, 0.5f), PlanCell::kFree);
  EXPECT_EQ(CellAt(*plan, 0.05f, 3.5f), PlanCell::kFree);     // ramp below the band
  EXPECT_EQ(CellAt(*plan, 1.0f, 3.5f), PlanCell::kObstacle);  // ramp in the band
  EXPECT_EQ(CellAt(*plan, 1.77f, 3.5f), PlanCell::kObstacle);
  EXPECT_EQ(CellAt(*plan, 1.87f, 3.5f), PlanCell::kFree);  // ramp above the band
  EXPECT_EQ(CellAt(*plan, 3.0f, 3.5f), PlanCell::kFree);
}

TEST(FloorPlan, RefusesBadParams) {
  const World w = BoxRoom();
  FloorPlanParams p;
  p.resolution_m = 0.0f;
  EXPECT_FALSE(RasterizeFloorPlan(w, p).ok());
  p = {};
  p.min_z_m = 2.0f;
  EXPECT_FALSE(RasterizeFloorPlan(w, p).ok());
  p = {};
  p.resolution_m = 1e-5f;  // billions of cells
  EXPECT_FALSE(RasterizeFloorPlan(w, p).ok());
  EXPECT_FALSE(RasterizeFloorPlan(World{}).ok());
}

std::string AwsHouse() {
  return (test::SharedDataDir() / "scenes/aws_small_house/derived/small_house_visual.ply").string();
}

TEST(LoadWorld, AwsSmallHouseInstances) {
  Result<World> w = LoadWorld(AwsHouse());
  ASSERT_TRUE(w.ok()) << w.status().message();
  EXPECT_EQ(w->mesh.num_triangles(), 145844u);
  // 87 rows, two of them (Ball_01) without triangles in the assembled mesh.
  EXPECT_EQ(w->instances.size(), 85u);
  ASSERT_EQ(w->triangle_instance.size(), w->mesh.num_triangles());
  for (uint32_t id : w->triangle_instance) ASSERT_NE(id, kNoInstance);  // the table covers all
  std::map<std::string, const Instance*> by_model;
  std::map<std::string, int> classes;
  for (size_t i = 0; i < w->instances.size(); ++i) {
    EXPECT_EQ(w->instances[i].id, i + 1);
    EXPECT_FALSE(w->instances[i].bounds_W.isEmpty());
    by_model[w->instances[i].model] = &w->instances[i];
    ++classes[w->instances[i].class_name];
  }
  ASSERT_TRUE(by_model.count("Bed_01"));
  const Instance& bed = *by_model["Bed_01"];
  EXPECT_EQ(bed.class_name, "bed");
  EXPECT_NEAR(bed.bounds_W.min().x(), -7.18f, 0.01f);
  EXPECT_NEAR(bed.bounds_W.max().y(), 3.03f, 0.01f);
  EXPECT_NEAR(bed.bounds_W.max().z(), 1.26f, 0.01f);
  EXPECT_EQ(by_model["HouseWallB_01"]->class_name, "wall");
  EXPECT_EQ(by_model["FloorB_01"]->class_name, "floor");
  EXPECT_EQ(by_model["SofaC_01"]->class_name, "sofa");
  EXPECT_EQ(by_model["ReadingDesk_01"]->class_name, "desk");
  EXPECT_EQ(classes["chair"], 8);
  EXPECT_EQ(classes["window"], 9);
  // Triangles of one instance lie in its bounds; the bed's triangles are the table's 5th run.
  size_t first_bed = 0;
  while (w->triangle_instance[first_bed] != bed.id) ++first_bed;
  EXPECT_EQ(first_bed, 190u + 520u);
  for (size_t t = 0; t < w->mesh.num_triangles(); ++t) {
    if (w->triangle_instance[t] != bed.id) continue;
    for (uint32_t v : w->mesh.triangles[t])
      ASSERT_TRUE(bed.bounds_W.contains(w->mesh.positions[v]));
  }
}

TEST(LoadWorld, AwsSmallHouseFloorPlan) {
  Result<World> w = LoadWorld(AwsHouse());
  ASSERT_TRUE(w.ok()) << w.status().message();
  Result<FloorPlan> plan = RasterizeFloorPlan(w.value());
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  const auto n = Count(*plan);
  const double free_m2 = n.at(PlanCell::kFree) * 0.05 * 0.05;
  EXPECT_GT(free_m2, 120.0);
  EXPECT_LT(free_m2, 190.0);
  EXPECT_EQ(CellAt(*plan, -6.2f, 2.0f), PlanCell::kObstacle);  // the bed
  EXPECT_EQ(CellAt(*plan, 0.3f, 0.5f), PlanCell::kFree);       // the living room
  EXPECT_EQ(CellAt(*plan, 6.5f, 0.95f), PlanCell::kObstacle);  // the kitchen table
  EXPECT_EQ(CellAt(*plan, -8.0f, 5.0f), PlanCell::kOutside);   // beside the north wing
  EXPECT_EQ(CellAt(*plan, 8.0f, 5.0f), PlanCell::kOutside);
  EXPECT_EQ(CellAt(*plan, 0.0f, 5.62f), PlanCell::kObstacle);  // north wall
}

TEST(LoadWorld, RoundTripThroughWriteWorld) {
  test::TempDir dir("worlds");
  World w = BoxRoom();
  w.rooms.push_back({"room", Eigen::AlignedBox2f(Eigen::Vector2f(0, 0), Eigen::Vector2f(4, 3))});
  // Interleave: the writer groups triangles by instance.
  std::swap(w.mesh.triangles[0], w.mesh.triangles[5]);
  std::swap(w.triangle_instance[0], w.triangle_instance[5]);
  w.triangle_instance[7] = kNoInstance;
  Result<WrittenWorld> written = WriteWorld(w, dir.path().string());
  ASSERT_TRUE(written.ok()) << written.status().message();
  for (const std::string& p : written->paths) EXPECT_TRUE(fs::is_regular_file(p)) << p;
  const World grouped = GroupTrianglesByInstance(w);
  for (const char* ext : {".ply", ".glb"}) {
    Result<World> back = LoadWorld((dir / (std::string("world") + ext)).string());
    ASSERT_TRUE(back.ok()) << back.status().message();
    ASSERT_EQ(back->mesh.num_triangles(), grouped.mesh.num_triangles());
    EXPECT_EQ(back->triangle_instance, grouped.triangle_instance) << ext;
    ASSERT_EQ(back->instances.size(), w.instances.size());
    for (size_t i = 0; i < w.instances.size(); ++i) {
      EXPECT_EQ(back->instances[i].id, w.instances[i].id);
      EXPECT_EQ(back->instances[i].class_name, w.instances[i].class_name);
    }
    for (size_t t = 0; t < grouped.mesh.num_triangles(); ++t)
      for (int k = 0; k < 3; ++k)
        ASSERT_TRUE(back->mesh.positions[back->mesh.triangles[t][k]].isApprox(
            grouped.mesh.positions[grouped.mesh.triangles[t][k]], 1e-6f));
    ASSERT_EQ(back->rooms.size(), 1u);
    EXPECT_EQ(back->rooms[0].name, "room");
    EXPECT_TRUE(back->rooms[0].footprint_W.isApprox(w.rooms[0].footprint_W));
  }
}

void WriteText(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

TEST(LoadWorld, RefusesBadInput) {
  test::TempDir dir("worlds_bad");
  Result<World> missing = LoadWorld((dir / "nope.ply").string());
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);

  WriteText(dir / "points.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
  Result<World> no_tri = LoadWorld((dir / "points.ply").string());
  ASSERT_FALSE(no_tri.ok());
  EXPECT_NE(no_tri.status().message().find("points.ply"), std::string::npos);

  WriteText(dir / "garbage.ply", "this is not a mesh\n");
  EXPECT_FALSE(LoadWorld((dir / "garbage.ply").string()).ok());

  SceneLoadOptions km;
  km.scale = 100.0f;  // the house in centimetres read as metres: 1.9 km wide
  Result<World> huge = LoadWorld(AwsHouse(), km);
  ASSERT_FALSE(huge.ok());
  EXPECT_EQ(huge.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(huge.status().message().find("1 km"), std::string::npos) << huge.status().message();
  SceneLoadOptions tiny;
  tiny.scale = 0.01f;
  EXPECT_FALSE(LoadWorld(AwsHouse(), tiny).ok());
  SceneLoadOptions negative;
  negative.scale = -1.0f;
  EXPECT_EQ(LoadWorld(AwsHouse(), negative).status().code(), StatusCode::kInvalidArgument);

  // An instance table listing more triangles than the mesh has belongs to another mesh.
  World w = BoxRoom();
  ASSERT_TRUE(WriteWorld(w, dir.path().string()).ok());
  WriteText(dir / "world_instances.tsv", "id\tclass\tmodel\ttriangles\n1\tfloor\tfloor\t9999\n");
  Result<World> mismatch = LoadWorld((dir / "world.ply").string());
  ASSERT_FALSE(mismatch.ok());
  EXPECT_EQ(mismatch.status().code(), StatusCode::kCorruptData);
  WriteText(dir / "world_instances.tsv", "id\tclass\tmodel\n1\tfloor\tfloor\n");
  EXPECT_FALSE(LoadWorld((dir / "world.ply").string()).ok());  // no triangles column
}

TEST(LoadWorld, MultiNodeFileGivesInstances) {
  // The Cornell box OBJ (Y-up) has one group per object.
  const std::string path =
      (test::SharedDataDir() / "scenes/cornell_box/CornellBox-Original.obj").string();
  SceneLoadOptions opt;
  opt.up = UpAxis::kY;
  Result<World> w = LoadWorld(path, opt);
  ASSERT_TRUE(w.ok()) << w.status().message();
  EXPECT_GE(w->instances.size(), 6u);
  std::set<std::string> classes;
  for (const Instance& i : w->instances) classes.insert(i.class_name);
  EXPECT_TRUE(classes.count("floor"));
  EXPECT_TRUE(classes.count("wall"));
  EXPECT_TRUE(classes.count("ceiling"));
  for (uint32_t id : w->triangle_instance) EXPECT_NE(id, kNoInstance);
  // Z-up: the floor is the lowest instance.
  for (const Instance& i : w->instances)
    if (i.class_name == "floor") {
      EXPECT_NEAR(i.bounds_W.max().z(), 0.0f, 0.02f);
    }
}

TEST(FurnitureIndex, ReadsAndClassifies) {
  Result<std::vector<FurnitureModel>> index =
      ReadFurnitureIndex((test::SharedDataDir() / "objects/aws_furniture_index.tsv").string());
  ASSERT_TRUE(index.ok()) << index.status().message();
  EXPECT_EQ(index->size(), 140u);
  for (const FurnitureModel& m : *index) EXPECT_TRUE(fs::is_regular_file(m.path)) << m.path;
  EXPECT_EQ(ClassForModel("RoomWindow_01", "structure"), "window");
  EXPECT_EQ(ClassForModel("FoldingDoor_02", "structure"), "door");
  EXPECT_EQ(ClassForModel("Carpet_01", "floor covering"), "carpet");
  EXPECT_EQ(ClassForModel("Chair_07.001", ""), "chair");
  EXPECT_EQ(FindFurnitureIndex(AwsHouse()),
            fs::absolute(test::SharedDataDir() / "objects/aws_furniture_index.tsv")
                .lexically_normal()
                .string());
}

TEST(WorldFingerprint, SurvivesWriteAndLoadAndTellsWorldsApart) {
  test::TempDir dir("world_fingerprint");
  ApartmentParams ap;
  ap.size = ApartmentSize::kR;
  ap.seed = 1;
  Result<World> world = GenerateApartment(ap);
  ASSERT_TRUE(world.ok()) << world.status().message();
  WorldWriteOptions o;
  o.write_glb = false;
  ASSERT_TRUE(WriteWorld(*world, dir.path().string(), o).ok());
  Result<World> back = LoadWorld((dir / "world.ply").string());
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(WorldFingerprint(*back), WorldFingerprint(*world));  // the PLY shares vertices
  EXPECT_EQ(WorldFingerprintHex(*world).size(), 16u);
  ap.seed = 2;
  Result<World> other = GenerateApartment(ap);
  ASSERT_TRUE(other.ok());
  EXPECT_NE(WorldFingerprint(*other), WorldFingerprint(*world));
  World moved = *world;
  for (Eigen::Vector3f& p : moved.mesh.positions) p.z() += 0.5f;
  EXPECT_NE(WorldFingerprint(moved), WorldFingerprint(*world));
  World relabelled = *world;
  relabelled.triangle_instance[0] = kNoInstance;
  EXPECT_NE(WorldFingerprint(relabelled), WorldFingerprint(*world));
}

}  // namespace
}  // namespace voxplan
