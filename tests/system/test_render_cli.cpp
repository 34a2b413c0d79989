// System tests of `voxplan render` and `voxplan eval trajectory`: the built executable run as a
// user would, checking exit codes, the JSON last line, the images written and, on failure, that
// nothing was written.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"
#include "io/image_io.h"
#include "io/map_io.h"
#include "io/mesh_io.h"
#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using test::Describe;
using test::ReadAll;
using test::RunCli;
using test::RunResult;

// A unit cube mesh (12 triangles, outward winding irrelevant to the renderer), coloured red.
void WriteCubeMesh(const fs::path& path) {
  Mesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.positions.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
    mesh.colors.push_back({200, 30, 30});
  }
  const uint32_t quads[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                                {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& q : quads) {
    mesh.triangles.push_back({q[0], q[1], q[2]});
    mesh.triangles.push_back({q[0], q[2], q[3]});
  }
  ASSERT_TRUE(WriteMesh(mesh, path.string()).ok());
}

// A map holding the plane z = 0.2 m over a few blocks: exact TSDF, observed.
void WritePlaneMap(const fs::path& path) {
  TsdfVolume volume(VolumeParams{0.05f, 0.2f});
  for (int x = -2; x <= 1; ++x) {
    for (int y = -2; y <= 1; ++y) {
      for (int z = 0; z <= 1; ++z) {
        const BlockIndex b{x, y, z};
        TsdfBlock& block = volume.FindOrAllocate(b);
        for (int i = 0; i < kBlockVoxels; ++i) {
          const Eigen::Vector3f c = VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), 0.05f);
          block.tsdf[i] = EncodeTsdf((c.z() - 0.2f) / 0.2f);
          block.weight[i] = EncodeWeight(10.0f);
          block.r[i] = 20;
          block.g[i] = 180;
          block.b[i] = 40;
        }
      }
    }
  }
  ASSERT_TRUE(SaveMap(volume, path.string()).ok());
}

bool EmptyOrMissing(const fs::path& dir) {
  std::error_code ec;
  return !fs::exists(dir, ec) || fs::is_empty(dir, ec);
}

TEST(RenderCliTest, MeshTurntableWritesNamedPngs) {
  const test::TempDir dir("voxplan-render");
  const fs::path mesh = dir / "cube.ply", out = dir / "views";
  WriteCubeMesh(mesh);
  const RunResult r = RunCli({"render", mesh.string(), "--orbit", "3", "--size", "64x48", "--mode",
                              "colour", "--threads", "1", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const json& j = r.last_json;
  ASSERT_TRUE(j.is_object()) << Describe(r);
  EXPECT_EQ(j.at("command"), "render");
  EXPECT_EQ(j.at("input_kind"), "mesh");
  EXPECT_EQ(j.at("mode"), "colour");
  EXPECT_EQ(j.at("views").get<int>(), 3);
  ASSERT_EQ(j.at("files").size(), 3u);
  EXPECT_GT(j.at("hit_fraction").get<double>(), 0.05);
  for (int k = 0; k < 3; ++k) {
    const fs::path png = out / ("render_00" + std::to_string(k) + ".png");
    EXPECT_EQ(j.at("files")[size_t(k)].get<std::string>(), png.string());
    Result<ColorImage> image = ReadColorImage(png.string());
    ASSERT_TRUE(image.ok()) << image.status().message();
    EXPECT_EQ(image->width, 64);
    EXPECT_EQ(image->height, 48);
    // The cube is framed at the centre, in its own colour.
    EXPECT_EQ(image->at(32, 24), PackRgb(200, 30, 30));
  }
}

TEST(RenderCliTest, MapFromAPoseSeesThePlane) {
  const test::TempDir dir("voxplan-render");
  const fs::path map = dir / "plane.vpmap", out = dir / "views";
  WritePlaneMap(map);
  // 1 m above the plane looking straight down (camera z = world -z: 180 deg about x).
  const RunResult r = RunCli({"render", map.string(), "--pose", "0 0 1.2 1 0 0 0", "--size",
                              "80x60", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  EXPECT_EQ(r.last_json.at("input_kind"), "map");
  EXPECT_GT(r.last_json.at("hit_fraction").get<double>(), 0.5) << Describe(r);
  Result<ColorImage> image = ReadColorImage((out / "render_000.png").string());
  ASSERT_TRUE(image.ok());
  const uint32_t c = image->at(40, 30);
  EXPECT_GT(Green(c), Red(c) + 60) << Describe(r);  // shaded map colour, lit head-on

  // Default: one orbit view.
  const RunResult orbit = RunCli({"render", map.string(), "--size", "80x60", "--mode", "depth",
                                  "--out", (dir / "orbit").string()});
  ASSERT_EQ(orbit.exit_code, 0) << Describe(orbit);
  EXPECT_EQ(orbit.last_json.at("views").get<int>(), 1);
  EXPECT_TRUE(fs::exists(dir / "orbit" / "render_000.png"));
}

// --kernel scalar marches the scalar reference: the same pixels as the default (AVX2) march.
TEST(RenderCliTest, ScalarKernelRendersTheSameImages) {
  const test::TempDir dir("voxplan-render");
  const fs::path map = dir / "plane.vpmap";
  WritePlaneMap(map);
  std::vector<ColorImage> images;
  for (const char* kernel : {"auto", "scalar"}) {
    const fs::path out = dir / kernel;
    const RunResult r = RunCli({"render", map.string(), "--orbit", "2", "--size", "80x60", "--mode",
                                "normals", "--kernel", kernel, "--out", out.string()});
    ASSERT_EQ(r.exit_code, 0) << Describe(r);
    EXPECT_GT(r.last_json.at("hit_fraction").get<double>(), 0.1) << Describe(r);
    for (const char* name : {"render_000.png", "render_001.png"}) {
      Result<ColorImage> image = ReadColorImage((out / name).string());
      ASSERT_TRUE(image.ok()) << image.status().message();
      images.push_back(std::move(*image));
    }
  }
  ASSERT_EQ(images.size(), 4u);
  EXPECT_EQ(images[0].data, images[2].data);
  EXPECT_EQ(images[1].data, images[3].data);
  const RunResult bad =
      RunCli({"render", map.string(), "--kernel", "simd", "--out", (dir / "bad").string()});
  EXPECT_EQ(bad.exit_code, 2) << Describe(bad);
}

TEST(RenderCliTest, RefusesBadArgumentsAndWritesNothing) {
  const test::TempDir dir("voxplan-render");
  const fs::path mesh = dir / "cube.ply", out = dir / "never";
  WriteCubeMesh(mesh);
  const std::vector<std::vector<std::string>> usage = {
      {"--mode", "wireframe"},   {"--size", "0x10"},
      {"--size", "20000x100"},   {"--size", "-4x10"},
      {"--size", "640by480"},    {"--fov-deg", "0"},
      {"--orbit", "0"},          {"--orbit", "2", "--pose", "0 0 0 0 0 0 1"},
      {"--pose", "0 0 0 0 0 0"}, {"--pose", "0 0 0 0 0 0 5"},
  };
  for (const auto& extra : usage) {
    std::vector<std::string> args = {"render", mesh.string(), "--out", out.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const RunResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 2) << extra[0] << "\n" << Describe(r);
    EXPECT_NE(r.err.find("error:"), std::string::npos);
  }
  const RunResult ext = RunCli({"render", (dir / "scene.xyz").string(), "--out", out.string()});
  EXPECT_EQ(ext.exit_code, 2) << Describe(ext);

  const fs::path missing = dir / "missing.ply";
  const RunResult not_found = RunCli({"render", missing.string(), "--out", out.string()});
  EXPECT_EQ(not_found.exit_code, 1) << Describe(not_found);
  EXPECT_NE(not_found.err.find(missing.string()), std::string::npos) << Describe(not_found);

  const fs::path corrupt = dir / "corrupt.vpmap";
  std::ofstream(corrupt) << "not a map";
  const RunResult bad_map = RunCli({"render", corrupt.string(), "--out", out.string()});
  EXPECT_EQ(bad_map.exit_code, 1) << Describe(bad_map);
  EXPECT_NE(bad_map.err.find(corrupt.string()), std::string::npos) << Describe(bad_map);
  EXPECT_TRUE(EmptyOrMissing(out));

  // An output path that is a file cannot become a folder.
  const fs::path file = dir / "a_file";
  std::ofstream(file) << "x";
  const RunResult into_file = RunCli({"render", mesh.string(), "--out", file.string()});
  EXPECT_EQ(into_file.exit_code, 2) << Describe(into_file);
  const RunResult below_file = RunCli({"render", mesh.string(), "--out", (file / "sub").string()});
  EXPECT_EQ(below_file.exit_code, 2) << Describe(below_file);
  EXPECT_EQ(ReadAll(file), "x");
}

TEST(EvalTrajectoryCliTest, ScoresAndRefusesNoOverlap) {
  const test::TempDir dir("voxplan-traj-cli");
  const fs::path est = dir / "est.txt", ref = dir / "ref.txt", late = dir / "late.txt";
  std::ofstream e(est), f(ref), l(late);
  e << "# estimate\n";
  for (int i = 0; i < 10; ++i) {
    const double t = 0.1 * i;
    // The estimate is the reference shifted by 1 m in x: a rigid motion, ATE 0 after alignment.
    f << t << " " << 0.3 * i << " " << 0.1 * i * i << " 0 0 0 0 1\n";
    e << t + 0.005 << " " << 1.0 + 0.3 * i << " " << 0.1 * i * i << " 0 0 0 0 1\r\n";
    l << t + 50.0 << " 0 0 0 0 0 0 1\n";
  }
  e.close();
  f.close();
  l.close();
  const RunResult r = RunCli({"eval", "trajectory", est.string(), ref.string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const json& j = r.last_json;
  EXPECT_EQ(j.at("pairs").get<int>(), 10);
  EXPECT_NEAR(j.at("ate_rmse_m").get<double>(), 0.0, 1e-6);
  for (const char* key :
       {"ate_mean_m", "ate_median_m", "ate_max_m", "rpe_trans_rmse_m", "rpe_rot_rmse_deg"})
    EXPECT_NEAR(j.at(key).get<double>(), 0.0, 1e-5) << key;

  const RunResult none = RunCli({"eval", "trajectory", late.string(), ref.string()});
  EXPECT_EQ(none.exit_code, 1) << Describe(none);
  EXPECT_NE(none.err.find(late.string()), std::string::npos) << Describe(none);
  EXPECT_NE(none.err.find(ref.string()), std::string::npos) << Describe(none);

  const RunResult strict =
      RunCli({"eval", "trajectory", est.string(), ref.string(), "--max-dt", "0.001"});
  EXPECT_EQ(strict.exit_code, 1) << Describe(strict);
  const RunResult negative =
      RunCli({"eval", "trajectory", est.string(), ref.string(), "--max-dt", "-1"});
  EXPECT_EQ(negative.exit_code, 2) << Describe(negative);
}

}  // namespace
}  // namespace voxplan
