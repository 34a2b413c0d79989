// EvaluateObjects (Guo 2022 O-Comp, O-RMS) and the shared sampling / distance blocks, on
// hand-made worlds whose answers are known.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>

#include "core/parallel.h"
#include "eval/eval_mesh.h"
#include "eval/eval_objects.h"

namespace voxplan {
namespace {

constexpr double kDistanceTolerance_m = 1e-4;
// About 60,000 samples on a unit cube: binomial standard deviation of a 0.5 share ~0.002;
// the strip of width threshold_m beside a reconstructed face adds ~0.005.
constexpr double kShareTolerance = 0.02;

// Appends `part` to `mesh`, its triangles labelled `id` in `labels`.
void Append(const Mesh& part, uint32_t id, Mesh* mesh, std::vector<uint32_t>* labels) {
  const uint32_t base = uint32_t(mesh->positions.size());
  mesh->positions.insert(mesh->positions.end(), part.positions.begin(), part.positions.end());
  for (const auto& t : part.triangles) {
    mesh->triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    if (labels) labels->push_back(id);
  }
}

Mesh Rectangle(float x0, float y0, float x1, float y1, float z0) {
  Mesh mesh;
  mesh.positions = {{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

// Axis-aligned cube [lo, lo + size]^3 as six faces of two triangles; `faces` picks which
// (bit k: face k in the order -x, +x, -y, +y, -z, +z).
Mesh Cube(const Eigen::Vector3f& lo, float size, unsigned faces = 0x3f) {
  Mesh mesh;
  for (int i = 0; i < 8; ++i)
    mesh.positions.push_back(
        lo + size * Eigen::Vector3f(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)));
  // Corner i has x = bit 0, y = bit 1, z = bit 2; each face as a quad.
  const std::array<std::array<uint32_t, 4>, 6> quads = {
      {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}}};
  for (int f = 0; f < 6; ++f) {
    if (!(faces & (1u << f))) continue;
    const auto& q = quads[size_t(f)];
    mesh.triangles.push_back({q[0], q[1], q[2]});
    mesh.triangles.push_back({q[0], q[2], q[3]});
  }
  return mesh;
}

Instance MakeInstance(uint32_t id, const std::string& class_name) {
  Instance instance;
  instance.id = id;
  instance.class_name = class_name;
  instance.model = class_name + "_" + std::to_string(id);
  return instance;
}

// A floor (id 1) and two unit cubes standing apart on it (ids 2 and 3).
World TwoCubes() {
  World world;
  world.name = "two_cubes";
  Append(Rectangle(-1.f, -1.f, 5.f, 3.f, 0.f), 1, &world.mesh, &world.triangle_instance);
  // No bottom faces: 5 m^2 each.
  Append(Cube({0.f, 0.f, 0.f}, 1.f, 0x2f), 2, &world.mesh, &world.triangle_instance);
  Append(Cube({3.f, 0.f, 0.f}, 1.f, 0x2f), 3, &world.mesh, &world.triangle_instance);
  world.instances = {MakeInstance(1, "floor"), MakeInstance(2, "box"), MakeInstance(3, "box")};
  return world;
}

ObjectEvalParams Params(float threshold_m) {
  ObjectEvalParams params;
  params.threshold_m = threshold_m;
  params.samples_per_m2 = 4000.f;
  return params;
}

TEST(EvaluateObjects, PerfectReconstructionExcludesTheFloor) {
  const World world = TwoCubes();
  auto result = EvaluateObjects(world.mesh, world, Params(0.01f));
  ASSERT_TRUE(result.ok()) << result.status().message();
  ASSERT_EQ(result->objects.size(), 2u);  // the floor is structure
  EXPECT_EQ(result->objects[0].id, 2u);
  EXPECT_EQ(result->objects[1].id, 3u);
  EXPECT_EQ(result->objects[0].class_name, "box");
  EXPECT_NEAR(result->objects[0].ground_truth_area_m2, 5.0, 1e-9);
  EXPECT_EQ(result->objects[0].ground_truth_samples, 20000u);  // 5 m^2 * 4000
  EXPECT_DOUBLE_EQ(result->o_comp, 1.0);
  EXPECT_NEAR(result->o_rms_m, 0.0, 1e-6);
  EXPECT_EQ(result->objects_reconstructed, 2u);
  EXPECT_GT(result->objects[1].reconstruction_samples, 0u);
  EXPECT_TRUE(result->skipped.empty());
}

TEST(EvaluateObjects, HalfOfOneCubeGivesKnownObjectCompleteness) {
  const World world = TwoCubes();
  // Cube 2 whole; of cube 3 only its -x, +x and top faces: 3 of its 5 faces, 0.6 of its surface.
  Mesh recon;
  Append(Cube({0.f, 0.f, 0.f}, 1.f, 0x2f), 0, &recon, nullptr);
  Append(Cube({3.f, 0.f, 0.f}, 1.f, 0x23), 0, &recon, nullptr);
  auto result = EvaluateObjects(recon, world, Params(0.005f));
  ASSERT_TRUE(result.ok()) << result.status().message();
  ASSERT_EQ(result->objects.size(), 2u);
  EXPECT_DOUBLE_EQ(result->objects[0].completeness, 1.0);
  EXPECT_NEAR(result->objects[1].completeness, 0.6, kShareTolerance);
  EXPECT_NEAR(result->o_comp, 0.8, kShareTolerance);
  // Area-weighted over both cubes' 10 m^2: 8 m^2 covered.
  EXPECT_NEAR(result->completeness_all_objects, 0.8, kShareTolerance);
  // Everything reconstructed lies on the truth.
  EXPECT_NEAR(result->o_rms_m, 0.0, 1e-6);
  EXPECT_NEAR(result->objects[1].accuracy_rms_m, 0.0, 1e-6);
}

TEST(EvaluateObjects, ShiftAlongTheNormalIsTheObjectAccuracy) {
  // Two horizontal panels (table tops) at different heights, reconstructed 2 cm and 4 cm high.
  World world;
  Append(Rectangle(0.f, 0.f, 1.f, 1.f, 0.5f), 1, &world.mesh, &world.triangle_instance);
  Append(Rectangle(3.f, 0.f, 4.f, 1.f, 0.8f), 2, &world.mesh, &world.triangle_instance);
  world.instances = {MakeInstance(1, "table"), MakeInstance(2, "table")};
  Mesh recon;
  Append(Rectangle(0.f, 0.f, 1.f, 1.f, 0.52f), 0, &recon, nullptr);
  Append(Rectangle(3.f, 0.f, 4.f, 1.f, 0.84f), 0, &recon, nullptr);

  auto result = EvaluateObjects(recon, world, Params(0.03f));
  ASSERT_TRUE(result.ok()) << result.status().message();
  ASSERT_EQ(result->objects.size(), 2u);
  EXPECT_NEAR(result->objects[0].accuracy_mean_m, 0.02, kDistanceTolerance_m);
  EXPECT_NEAR(result->objects[0].accuracy_rms_m, 0.02, kDistanceTolerance_m);
  EXPECT_NEAR(result->objects[1].accuracy_mean_m, 0.04, kDistanceTolerance_m);
  EXPECT_NEAR(result->o_rms_m, 0.03, kDistanceTolerance_m);  // mean over objects
  EXPECT_NEAR(result->mean_object_rms_m, 0.03, kDistanceTolerance_m);
  // Within 3 cm: the first panel is complete, the second not at all.
  EXPECT_DOUBLE_EQ(result->objects[0].completeness, 1.0);
  EXPECT_DOUBLE_EQ(result->objects[1].completeness, 0.0);
  EXPECT_DOUBLE_EQ(result->o_comp, 0.5);
  EXPECT_EQ(result->objects[0].reconstruction_samples + result->objects[1].reconstruction_samples,
            result->reconstruction_samples);
}

TEST(EvaluateObjects, ExtraThresholdsReportCompletenessFromTheSameSamples) {
  // The panels of the test above, 2 cm and 4 cm off: within 1 cm neither, within 3 cm the first,
  // within 5 cm both; the primary threshold's numbers are those of a run without extras.
  World world;
  Append(Rectangle(0.f, 0.f, 1.f, 1.f, 0.5f), 1, &world.mesh, &world.triangle_instance);
  Append(Rectangle(3.f, 0.f, 4.f, 1.f, 0.8f), 2, &world.mesh, &world.triangle_instance);
  world.instances = {MakeInstance(1, "table"), MakeInstance(2, "table")};
  Mesh recon;
  Append(Rectangle(0.f, 0.f, 1.f, 1.f, 0.52f), 0, &recon, nullptr);
  Append(Rectangle(3.f, 0.f, 4.f, 1.f, 0.84f), 0, &recon, nullptr);
  ObjectEvalParams params = Params(0.03f);
  params.extra_thresholds_m = {0.01f, 0.05f};
  auto result = EvaluateObjects(recon, world, params);
  ASSERT_TRUE(result.ok()) << result.status().message();
  ASSERT_EQ(result->o_comp_extra.size(), 2u);
  ASSERT_EQ(result->objects[0].completeness_extra.size(), 2u);
  EXPECT_DOUBLE_EQ(result->objects[0].completeness_extra[0], 0.0);
  EXPECT_DOUBLE_EQ(result->objects[0].completeness_extra[1], 1.0);
  EXPECT_DOUBLE_EQ(result->objects[1].completeness_extra[1], 1.0);
  EXPECT_DOUBLE_EQ(result->o_comp_extra[0], 0.0);
  EXPECT_DOUBLE_EQ(result->o_comp_extra[1], 1.0);
  EXPECT_DOUBLE_EQ(result->o_comp, 0.5);
  params.extra_thresholds_m = {-0.01f};
  EXPECT_FALSE(EvaluateObjects(recon, world, params).ok());
}

TEST(EvaluateObjects, UnseenObjectCountsInCompletenessButNotInAccuracy) {
  World world;
  Append(Rectangle(0.f, 0.f, 1.f, 1.f, 0.5f), 1, &world.mesh, &world.triangle_instance);
  Append(Rectangle(3.f, 0.f, 4.f, 1.f, 0.5f), 2, &world.mesh, &world.triangle_instance);
  world.instances = {MakeInstance(1, "table"), MakeInstance(2, "table")};
  const Mesh recon = Rectangle(0.f, 0.f, 1.f, 1.f, 0.51f);
  auto result = EvaluateObjects(recon, world, Params(0.02f));
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_DOUBLE_EQ(result->objects[1].completeness, 0.0);
  EXPECT_EQ(result->objects[1].reconstruction_samples, 0u);
  EXPECT_EQ(result->objects_reconstructed, 1u);
  EXPECT_DOUBLE_EQ(result->o_comp, 0.5);
  EXPECT_NEAR(result->o_rms_m, 0.01, kDistanceTolerance_m);  // object 1 only
}

TEST(EvaluateObjects, StructureSurfaceIsNotCountedAgainstANearbyObject) {
  // A wall and a cabinet front 10 cm in front of it; the reconstruction is the wall.
  World world;
  Mesh wall = Rectangle(0.f, 0.f, 2.f, 2.f, 0.f);  // orientation does not matter here
  Mesh front = Rectangle(0.5f, 0.5f, 1.5f, 1.5f, 0.1f);
  Append(wall, 1, &world.mesh, &world.triangle_instance);
  Append(front, 2, &world.mesh, &world.triangle_instance);
  world.instances = {MakeInstance(1, "wall"), MakeInstance(2, "cabinet")};
  auto result = EvaluateObjects(wall, world, Params(0.05f));
  ASSERT_TRUE(result.ok()) << result.status().message();
  ASSERT_EQ(result->objects.size(), 1u);
  EXPECT_EQ(result->objects[0].reconstruction_samples, 0u);  // all went to the wall
  EXPECT_DOUBLE_EQ(result->o_comp, 0.0);

  // With the wall counted as an object (no exclusions) both are evaluated.
  ObjectEvalParams all = Params(0.05f);
  all.excluded_classes.clear();
  auto both = EvaluateObjects(wall, world, all);
  ASSERT_TRUE(both.ok()) << both.status().message();
  ASSERT_EQ(both->objects.size(), 2u);
  EXPECT_DOUBLE_EQ(both->objects[0].completeness, 1.0);
}

TEST(EvaluateObjects, FarReconstructionIsUnattributed) {
  World world;
  Append(Rectangle(0.f, 0.f, 1.f, 1.f, 0.5f), 1, &world.mesh, &world.triangle_instance);
  world.instances = {MakeInstance(1, "table")};
  Mesh recon = Rectangle(0.f, 0.f, 1.f, 1.f, 0.5f);
  Append(Rectangle(0.f, 0.f, 1.f, 1.f, 2.5f), 0, &recon, nullptr);  // 2 m above: clutter
  ObjectEvalParams params = Params(0.05f);
  params.max_attribution_distance_m = 0.5f;
  auto result = EvaluateObjects(recon, world, params);
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_NEAR(result->objects[0].accuracy_mean_m, 0.0, 1e-6);
  // Samples fall on the two equal rectangles by chance: about half on the clutter.
  EXPECT_NEAR(
      double(result->reconstruction_samples_unattributed) / double(result->reconstruction_samples),
      0.5, kShareTolerance);

  params.max_attribution_distance_m = std::numeric_limits<float>::infinity();
  auto everything = EvaluateObjects(recon, world, params);
  ASSERT_TRUE(everything.ok());
  // About half of the samples at 2 m.
  EXPECT_NEAR(everything->objects[0].accuracy_mean_m, 1.0, 2.0 * kShareTolerance);
}

TEST(EvaluateObjects, OneThreadAndManyGiveTheSameResult) {
  const World world = TwoCubes();
  Mesh recon;
  Append(Cube({0.f, 0.f, 0.01f}, 1.f, 0x27), 0, &recon, nullptr);
  Result<ObjectsEvalResult> one = InvalidArgument("not run");
  {
    ThreadLimit single(1);
    one = EvaluateObjects(recon, world, Params(0.02f));
  }
  auto many = EvaluateObjects(recon, world, Params(0.02f));
  ASSERT_TRUE(one.ok() && many.ok());
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(one->objects[k].completeness, many->objects[k].completeness);
    EXPECT_EQ(one->objects[k].accuracy_mean_m, many->objects[k].accuracy_mean_m);
    EXPECT_EQ(one->objects[k].reconstruction_samples, many->objects[k].reconstruction_samples);
  }
  EXPECT_GT(one->o_rms_m, 0.0);  // the reconstruction is 1 cm off
}

TEST(EvaluateObjects, RefusesBadInput) {
  World world = TwoCubes();
  EXPECT_FALSE(EvaluateObjects(Mesh{}, world).ok());
  World mismatched = world;
  mismatched.triangle_instance.pop_back();
  auto r = EvaluateObjects(world.mesh, mismatched);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("triangle instance ids"), std::string::npos);
  World unknown = world;
  unknown.triangle_instance[0] = 42;
  EXPECT_FALSE(EvaluateObjects(world.mesh, unknown).ok());
  World only_structure = world;
  for (Instance& instance : only_structure.instances) instance.class_name = "wall";
  auto none = EvaluateObjects(world.mesh, only_structure);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.status().message().find("no object"), std::string::npos);
  ObjectEvalParams bad;
  bad.samples_per_m2 = 0.f;
  EXPECT_FALSE(EvaluateObjects(world.mesh, world, bad).ok());
}

TEST(SampleSurface, SubsetSamplesStayOnTheSubset) {
  const World world = TwoCubes();
  std::vector<uint32_t> cube3;
  for (uint32_t t = 0; t < world.triangle_instance.size(); ++t)
    if (world.triangle_instance[t] == 3) cube3.push_back(t);
  auto samples = SampleSurface(world.mesh, 100.0, 7, cube3, 1000);
  ASSERT_TRUE(samples.ok()) << samples.status().message();
  EXPECT_EQ(samples->points.size(), 1000u);  // min_samples beats 5 m^2 * 100
  EXPECT_NEAR(samples->area_m2, 5.0, 1e-9);
  for (const Eigen::Vector3d& p : samples->points) {
    EXPECT_GE(p.x(), 3.0 - 1e-9);
    EXPECT_LE(p.x(), 4.0 + 1e-9);
  }
  EXPECT_FALSE(SampleSurface(world.mesh, 100.0, 7, {uint32_t(world.mesh.num_triangles())}).ok());
}

TEST(SurfaceDistance, ReportsDistanceAndClosestTriangle) {
  const Mesh mesh = Rectangle(0.f, 0.f, 1.f, 1.f, 0.f);  // triangle 0 below the diagonal x = y
  auto surface = SurfaceDistance::Build(mesh);
  ASSERT_TRUE(surface.ok()) << surface.status().message();
  std::vector<uint32_t> closest;
  const std::vector<double> d =
      surface->Distances({{0.8, 0.2, 0.3}, {0.2, 0.8, -0.1}, {2.0, 0.5, 0.0}}, &closest);
  ASSERT_EQ(d.size(), 3u);
  EXPECT_NEAR(d[0], 0.3, 1e-12);
  EXPECT_NEAR(d[1], 0.1, 1e-12);
  EXPECT_NEAR(d[2], 1.0, 1e-12);
  EXPECT_EQ(closest[0], 0u);
  EXPECT_EQ(closest[1], 1u);
  EXPECT_FALSE(SurfaceDistance::Build(Mesh{}).ok());
}

}  // namespace
}  // namespace voxplan
