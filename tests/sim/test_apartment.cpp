// The apartment generator: determinism of the written files, and validity of many apartments
// checked through their floor plans (closed walls, rooms reachable by a 0.2 m robot, furniture
// clear of walls, areas within the size class).
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "sim/apartment.h"
#include "sim/floor_plan.h"
#include "sim/scene_loader.h"
#include "sim/world_io.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

std::string IndexPath() {
  return (test::SharedDataDir() / "objects/aws_furniture_index.tsv").string();
}

World Generate(ApartmentSize size, uint64_t seed, bool meshes = true) {
  ApartmentParams p;
  p.size = size;
  p.seed = seed;
  if (meshes) p.furniture_index = IndexPath();
  Result<World> w = GenerateApartment(p);
  EXPECT_TRUE(w.ok()) << w.status().message();
  return w.ok() ? std::move(w.value()) : World{};
}

std::string Bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool IsStructure(const std::string& cls) {
  return cls == "wall" || cls == "floor" || cls == "ceiling" || cls == "door";
}

TEST(Apartment, SameSeedSameBytes) {
  test::TempDir a("apt_a"), b("apt_b"), c("apt_c");
  const World w1 = Generate(ApartmentSize::kM, 3), w2 = Generate(ApartmentSize::kM, 3);
  const World w3 = Generate(ApartmentSize::kM, 4);
  Result<WrittenWorld> f1 = WriteWorld(w1, a.path().string());
  Result<WrittenWorld> f2 = WriteWorld(w2, b.path().string());
  Result<WrittenWorld> f3 = WriteWorld(w3, c.path().string());
  ASSERT_TRUE(f1.ok() && f2.ok() && f3.ok());
  ASSERT_EQ(f1->paths.size(), f2->paths.size());
  EXPECT_EQ(f1->paths.size(), 6u);  // ply, glb, instances, rooms, floor plan png + yaml
  for (size_t i = 0; i < f1->paths.size(); ++i) {
    EXPECT_EQ(fs::path(f1->paths[i]).filename(), fs::path(f2->paths[i]).filename());
    EXPECT_EQ(Bytes(f1->paths[i]), Bytes(f2->paths[i])) << f1->paths[i];
  }
  // Another seed: another apartment.
  for (const char* name : {"world.ply", "world_instances.tsv", "world_floor_plan.png"})
    EXPECT_NE(Bytes((a.path() / name).string()), Bytes((c.path() / name).string())) << name;
}

// Cells a robot centre of radius r can occupy: free cells farther than r from every cell that
// is not free.
std::vector<uint8_t> RobotSpace(const FloorPlan& plan, float radius) {
  const int rc = int(std::ceil(radius / plan.resolution_m));
  std::vector<std::array<int, 2>> offsets;
  for (int dj = -rc; dj <= rc; ++dj)
    for (int di = -rc; di <= rc; ++di) {
      const double dx = std::max(0.0, std::abs(di) - 0.5), dy = std::max(0.0, std::abs(dj) - 0.5);
      if (std::hypot(dx, dy) * plan.resolution_m < radius) offsets.push_back({di, dj});
    }
  std::vector<uint8_t> ok(plan.cells.size(), 0);
  for (int y = 0; y < plan.height; ++y)
    for (int x = 0; x < plan.width; ++x) {
      if (plan.at(x, y) != PlanCell::kFree) continue;
      bool clear = true;
      for (const auto& o : offsets) {
        const int a = x + o[0], b = y + o[1];
        if (!plan.Contains(a, b) || plan.at(a, b) != PlanCell::kFree) {
          clear = false;
          break;
        }
      }
      ok[size_t(y) * plan.width + x] = clear;
    }
  return ok;
}

// 4-connected component labels of the set cells (0 where unset).
std::vector<int> Components(const std::vector<uint8_t>& set, int width, int height, int* count) {
  std::vector<int> label(set.size(), 0);
  int next = 0;
  std::vector<size_t> stack;
  for (size_t s = 0; s < set.size(); ++s) {
    if (!set[s] || label[s]) continue;
    label[s] = ++next;
    stack.push_back(s);
    while (!stack.empty()) {
      const size_t c = stack.back();
      stack.pop_back();
      const int x = int(c % width), y = int(c / width);
      const int nx[4] = {x + 1, x - 1, x, x}, ny[4] = {y, y, y + 1, y - 1};
      for (int k = 0; k < 4; ++k) {
        if (nx[k] < 0 || ny[k] < 0 || nx[k] >= width || ny[k] >= height) continue;
        const size_t n = size_t(ny[k]) * width + nx[k];
        if (set[n] && !label[n]) {
          label[n] = next;
          stack.push_back(n);
        }
      }
    }
  }
  *count = next;
  return label;
}

void CheckApartment(const World& w, ApartmentSize size, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_FALSE(w.mesh.empty());
  ASSERT_EQ(w.triangle_instance.size(), w.mesh.num_triangles());
  EXPECT_EQ(w.mesh.colors.size(), w.mesh.positions.size());
  // Instances: ids 1..n in order, each with a class and triangles; every triangle labelled.
  std::map<uint32_t, size_t> tris;
  for (uint32_t id : w.triangle_instance) ++tris[id];
  EXPECT_EQ(tris.count(kNoInstance), 0u);
  for (size_t i = 0; i < w.instances.size(); ++i) {
    EXPECT_EQ(w.instances[i].id, i + 1);
    EXPECT_FALSE(w.instances[i].class_name.empty());
    EXPECT_GT(tris[w.instances[i].id], 0u) << w.instances[i].model;
  }
  EXPECT_LT(w.mesh.num_triangles(), 150000u);

  // Area: the outer walls' extent (gross) in the size class; rooms cover most of it.
  float lo_m2, hi_m2;
  ApartmentAreaRange(size, &lo_m2, &hi_m2);
  Eigen::AlignedBox3f box;
  for (const Instance& i : w.instances)
    if (i.class_name == "wall") box.extend(i.bounds_W);
  const float gross = box.sizes().x() * box.sizes().y();
  EXPECT_GE(gross, lo_m2);
  EXPECT_LE(gross, hi_m2);
  float rooms_m2 = 0.0f;
  std::set<std::string> names;
  for (const Room& r : w.rooms) {
    rooms_m2 += r.footprint_W.volume();
    names.insert(r.name);
    EXPECT_GE(r.footprint_W.sizes().minCoeff(), 1.19f) << r.name;
  }
  EXPECT_GT(rooms_m2, 0.75f * gross);
  EXPECT_EQ(names.size(), w.rooms.size());  // unique names
  if (size == ApartmentSize::kR) {
    EXPECT_EQ(w.rooms.size(), 1u);  // one room, no corridor
  } else {
    for (const char* must : {"living", "corridor", "kitchen"})
      EXPECT_TRUE(names.count(must)) << must;
    bool bedroom = false, bathroom = false;
    for (const std::string& n : names) {
      bedroom |= n.rfind("bedroom", 0) == 0;
      bathroom |= n.rfind("bathroom", 0) == 0;
    }
    EXPECT_TRUE(bedroom);
    EXPECT_TRUE(bathroom);
  }

  // Furniture: inside a room footprint, and its triangles' boxes clear of every wall box (wall
  // instances are single boxes).
  std::vector<Eigen::AlignedBox3f> walls;
  for (const Instance& i : w.instances)
    if (i.class_name == "wall") {
      Eigen::AlignedBox3f b = i.bounds_W;
      b.min().array() += 1e-3f;
      b.max().array() -= 1e-3f;
      walls.push_back(b);
    }
  std::set<uint32_t> furniture;
  int placed = 0;
  for (const Instance& i : w.instances) {
    if (IsStructure(i.class_name)) continue;
    furniture.insert(i.id);
    ++placed;
    bool inside = false;
    for (const Room& r : w.rooms) {
      Eigen::AlignedBox2f fp = r.footprint_W;
      fp.min().array() -= 1e-3f;
      fp.max().array() += 1e-3f;
      inside |= fp.contains(Eigen::Vector2f(i.bounds_W.min().head<2>())) &&
                fp.contains(Eigen::Vector2f(i.bounds_W.max().head<2>()));
    }
    EXPECT_TRUE(inside) << i.class_name << " " << i.model << " " << i.bounds_W.min().transpose()
                        << " / " << i.bounds_W.max().transpose();
  }
  EXPECT_GE(placed, int(w.rooms.size()) * 2);
  for (size_t t = 0; t < w.mesh.num_triangles(); ++t) {
    if (!furniture.count(w.triangle_instance[t])) continue;
    Eigen::AlignedBox3f tb;
    for (uint32_t v : w.mesh.triangles[t]) tb.extend(w.mesh.positions[v]);
    for (const Eigen::AlignedBox3f& b : walls)
      ASSERT_FALSE(tb.intersects(b))
          << "furniture triangle " << t << " (instance " << w.triangle_instance[t] << ") in a wall";
  }

  // Floor plan: the free space is sealed (no free cell touches an outside cell, diagonals
  // included), and a robot of radius 0.2 m can get from every room to every other one.
  Result<FloorPlan> plan = RasterizeFloorPlan(w);
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  for (int y = 0; y < plan->height; ++y)
    for (int x = 0; x < plan->width; ++x) {
      if (plan->at(x, y) != PlanCell::kFree) continue;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          ASSERT_TRUE(plan->Contains(x + dx, y + dy) &&
                      plan->at(x + dx, y + dy) != PlanCell::kOutside)
              << "free cell " << x << "," << y << " at " << plan->CellCenter(x, y).transpose()
              << " touches the outside";
    }
  const std::vector<uint8_t> space = RobotSpace(*plan, 0.2f);
  int count = 0;
  const std::vector<int> label = Components(space, plan->width, plan->height, &count);
  std::map<int, int> sizes;
  for (int l : label)
    if (l) ++sizes[l];
  int main = 0;
  for (const auto& [l, n] : sizes)
    if (!main || n > sizes[main]) main = l;
  for (const Room& r : w.rooms) {
    int in_main = 0, total = 0;
    for (int y = 0; y < plan->height; ++y)
      for (int x = 0; x < plan->width; ++x) {
        const size_t c = size_t(y) * plan->width + x;
        if (!space[c] || !r.footprint_W.contains(plan->CellCenter(x, y))) continue;
        ++total;
        in_main += label[c] == main;
      }
    EXPECT_GT(total, 0) << r.name << " has no room for the robot";
    EXPECT_GE(in_main, 0.97 * total)
        << r.name << ": " << in_main << " of " << total << " robot cells reachable";
  }
}

class ApartmentValidity : public ::testing::TestWithParam<std::tuple<ApartmentSize, int>> {};

TEST_P(ApartmentValidity, ClosedReachableClear) {
  const auto [size, seed] = GetParam();
  const World w = Generate(size, uint64_t(seed));
  CheckApartment(w, size, std::string(ApartmentSizeName(size)) + " seed " + std::to_string(seed));
}

INSTANTIATE_TEST_SUITE_P(Seeds, ApartmentValidity,
                         ::testing::Combine(::testing::Values(ApartmentSize::kS, ApartmentSize::kM,
                                                              ApartmentSize::kL),
                                            ::testing::Range(0, 8)));

// XL on its own, so the sanitizer run can take two of its seeds (scripts/sanitize, for time).
class ApartmentValidityXL : public ::testing::TestWithParam<int> {};

TEST_P(ApartmentValidityXL, ClosedReachableClear) {
  const World w = Generate(ApartmentSize::kXL, uint64_t(GetParam()));
  CheckApartment(w, ApartmentSize::kXL, "XL seed " + std::to_string(GetParam()));
}

INSTANTIATE_TEST_SUITE_P(Seeds, ApartmentValidityXL, ::testing::Range(0, 8));

// Single rooms (size R, Xu 2017's scenes): the same guarantees with one room.
class ApartmentValidityRoom : public ::testing::TestWithParam<int> {};

TEST_P(ApartmentValidityRoom, ClosedReachableClear) {
  const World w = Generate(ApartmentSize::kR, uint64_t(GetParam()));
  CheckApartment(w, ApartmentSize::kR, "R seed " + std::to_string(GetParam()));
}

INSTANTIATE_TEST_SUITE_P(Seeds, ApartmentValidityRoom, ::testing::Range(0, 8));

TEST(Apartment, ParametricOnlyWithoutIndex) {
  const World w = Generate(ApartmentSize::kS, 11, /*meshes=*/false);
  CheckApartment(w, ApartmentSize::kS, "parametric S seed 11");
  for (const Instance& i : w.instances)
    if (!IsStructure(i.class_name)) {
      EXPECT_EQ(i.model.rfind("param_", 0), 0u) << i.model;
    }
}

TEST(Apartment, UsesFurnitureMeshesAndCeilingInstances) {
  std::set<std::string> models, classes;
  for (int seed = 0; seed < 4; ++seed) {
    const World w = Generate(ApartmentSize::kM, uint64_t(seed));
    int ceilings = 0, floors = 0;
    for (const Instance& i : w.instances) {
      models.insert(i.model);
      classes.insert(i.class_name);
      ceilings += i.class_name == "ceiling";
      floors += i.class_name == "floor";
      // The ceiling is a downward-facing quad at the wall height, above the robot's band.
      if (i.class_name == "ceiling") {
        EXPECT_GT(i.bounds_W.min().z(), 2.4f);
      }
    }
    EXPECT_EQ(ceilings, int(w.rooms.size()));
    EXPECT_EQ(floors, int(w.rooms.size()));
  }
  EXPECT_TRUE(models.count("Bed_01") || models.count("ChairA_01") || models.count("ChairD_01"));
  for (const char* cls : {"wall", "floor", "ceiling", "door", "bed", "chair", "table", "sofa"})
    EXPECT_TRUE(classes.count(cls)) << cls;

  ApartmentParams no_ceiling;
  no_ceiling.ceiling = false;
  Result<World> w = GenerateApartment(no_ceiling);
  ASSERT_TRUE(w.ok());
  for (const Instance& i : w->instances) EXPECT_NE(i.class_name, "ceiling");
}

TEST(Apartment, FastForSizeM) {
  const auto start = std::chrono::steady_clock::now();
  const World w = Generate(ApartmentSize::kM, 5);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_FALSE(w.mesh.empty());
  EXPECT_LT(s, 3.0);  // ~0.05 s in Release; generous for Debug and loaded machines
}

TEST(Apartment, WrittenWorldLoadsBack) {
  test::TempDir dir("apt_rt");
  const World w = Generate(ApartmentSize::kS, 2);
  ASSERT_TRUE(WriteWorld(w, dir.path().string()).ok());
  Result<World> back = LoadWorld((dir / "world.glb").string());
  ASSERT_TRUE(back.ok()) << back.status().message();
  ASSERT_EQ(back->instances.size(), w.instances.size());
  for (size_t i = 0; i < w.instances.size(); ++i) {
    EXPECT_EQ(back->instances[i].class_name, w.instances[i].class_name);
    EXPECT_EQ(back->instances[i].model, w.instances[i].model);
    EXPECT_TRUE(back->instances[i].bounds_W.isApprox(w.instances[i].bounds_W, 1e-5f));
  }
  const World grouped = GroupTrianglesByInstance(w);
  EXPECT_EQ(back->triangle_instance, grouped.triangle_instance);
  ASSERT_EQ(back->rooms.size(), w.rooms.size());
  for (size_t r = 0; r < w.rooms.size(); ++r) EXPECT_EQ(back->rooms[r].name, w.rooms[r].name);
}

TEST(Apartment, RefusesBadInput) {
  EXPECT_FALSE(ParseApartmentSize("XXL").ok());
  EXPECT_EQ(*ParseApartmentSize("xl"), ApartmentSize::kXL);
  EXPECT_EQ(*ParseApartmentSize("R"), ApartmentSize::kR);
  EXPECT_TRUE(ParseApartmentSize("m").ok());
  ApartmentParams p;
  p.furniture_index = "/nonexistent/aws_furniture_index.tsv";
  EXPECT_FALSE(GenerateApartment(p).ok());
  p = {};
  p.mesh_probability = 2.0f;
  EXPECT_FALSE(GenerateApartment(p).ok());
}

}  // namespace
}  // namespace voxplan
