// System tests of `voxplan render` and `voxplan eval trajectory`: the built executable run as a
// user would, checking exit codes, the JSON last line, the images written and, on failure, that
// nothing was written; the default orbit framed on a map's surface (not its stray blocks), the
// up axis a map records (and a version 1 map's default), and upright renders at a y-flipped
// dataset's poses.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/index.h"
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

// Rewrites a map as version 1 wrote it: no up field after the block count, version 1, the
// checksum (FNV-1a 64) over the rest.
void RewriteAsVersion1(const fs::path& path) {
  std::string bytes = ReadAll(path);
  bytes = bytes.substr(0, 28) + bytes.substr(32, bytes.size() - 32 - 8);
  const uint32_t one = 1;
  std::memcpy(bytes.data() + 8, &one, 4);
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : bytes) h = (h ^ c) * 0x100000001b3ull;
  bytes.append(reinterpret_cast<const char*>(&h), 8);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// An ICL-like map: a y-up world (ICL-NUIM's convention) holding a 4 x 4 m floor at y = 0 and a
// 2.4 m wall at z = -2 facing +z, observed from inside the room (above the floor, in front of
// the wall), saved with the up axis `up`; `version1` rewrites the file as version 1 wrote it.
void WriteYUpRoomMap(const fs::path& path, WorldUp up, bool version1 = false) {
  const float voxel = 0.05f, trunc = 0.2f;
  TsdfVolume volume(VolumeParams{voxel, trunc});
  const float block_m = voxel * kBlockSide;
  const auto sdf = [](const Eigen::Vector3f& p) {
    const float floor = p.y(), wall = p.z() + 2.0f;
    if (p.y() > 2.4f) return floor;  // above the wall's top only the floor is near
    return std::min(floor, wall);
  };
  for (int bx = -5; bx < 5; ++bx)
    for (int by = -1; by < 7; ++by)
      for (int bz = -6; bz < 5; ++bz) {
        const BlockIndex b{bx, by, bz};
        const Eigen::Vector3f centre =
            (Eigen::Vector3f(float(bx), float(by), float(bz)) + Eigen::Vector3f::Constant(0.5f)) *
            block_m;
        if (std::abs(sdf(centre)) > trunc + block_m) continue;
        TsdfBlock& block = volume.FindOrAllocate(b);
        for (int i = 0; i < kBlockVoxels; ++i) {
          const Eigen::Vector3f c = VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), voxel);
          block.tsdf[i] = EncodeTsdf(std::clamp(sdf(c) / trunc, -1.0f, 1.0f));
          block.weight[i] = EncodeWeight(std::abs(c.x()) < 2.0f ? 10.0f : 0.0f);
          block.r[i] = 150, block.g[i] = 120, block.b[i] = 90;
        }
      }
  ASSERT_TRUE(SaveMap(volume, path.string(), up).ok());
  if (version1) RewriteAsVersion1(path);
}

// A z-up 4 x 3 x 2.5 m room fused from inside (the distance positive in the room), 5 cm voxels,
// and the stray blocks a real map collects: three 20 cm patches of noise surface and a trail of
// free-space blocks, up to 14 m out.
void WriteRoomMapWithStrays(const fs::path& path) {
  const float voxel = 0.05f, trunc = 0.2f, block_m = voxel * kBlockSide;
  TsdfVolume volume(VolumeParams{voxel, trunc});
  const Eigen::Vector3f lo = Eigen::Vector3f::Zero(), hi(4.f, 3.f, 2.5f);
  const auto room = [&](const Eigen::Vector3f& p) {
    return std::min((p - lo).minCoeff(), (hi - p).minCoeff());
  };
  const auto fill = [&](BlockIndex b, const auto& sdf) {
    TsdfBlock& block = volume.FindOrAllocate(b);
    for (int i = 0; i < kBlockVoxels; ++i) {
      const Eigen::Vector3f c = VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), voxel);
      block.tsdf[i] = EncodeTsdf(std::clamp(sdf(c, VoxelOfLinear(i)) / trunc, -1.0f, 1.0f));
      block.weight[i] = EncodeWeight(1.0f);
      block.r[i] = 150, block.g[i] = 120, block.b[i] = 90;
    }
  };
  for (int bx = -1; bx <= 10; ++bx)
    for (int by = -1; by <= 7; ++by)
      for (int bz = -1; bz <= 6; ++bz) {
        const BlockIndex b{bx, by, bz};
        const Eigen::Vector3f centre = BlockOrigin(b, block_m) + Eigen::Vector3f::Constant(0.2f);
        if (std::abs(room(centre)) <= trunc + block_m)
          fill(b, [&](const Eigen::Vector3f& c, VoxelIndex) { return room(c); });
      }
  for (const BlockIndex b : {BlockIndex{30, 4, 2}, BlockIndex{-20, 25, 3}, BlockIndex{5, -22, 15}})
    fill(b, [&](const Eigen::Vector3f& c, VoxelIndex v) {
      return v.x < 4 && v.y < 4 ? c.z() - BlockOrigin(b, block_m).z() - 0.2f : trunc;
    });
  for (int x = 11; x <= 35; ++x)
    fill({x, 4, 3}, [&](const Eigen::Vector3f&, VoxelIndex) { return trunc; });
  ASSERT_TRUE(SaveMap(volume, path.string(), WorldUp::kPlusZ).ok());
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
  EXPECT_EQ(j.at("framed_on"), "bounds");
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

// The default orbit frames a map's surface, not the union of its blocks: a room with stray
// blocks 14 m out fills its views, as the blocks' box could not (0.01 of the pixels); given
// numbers still win, and a mesh is framed on its bounds.
TEST(RenderCliTest, AMapsDefaultOrbitFramesItsRoomNotItsStrayBlocks) {
  const test::TempDir dir("voxplan-render-framing");
  const fs::path map = dir / "room.vpmap";
  WriteRoomMapWithStrays(map);
  const RunResult r = RunCli({"render", map.string(), "--orbit", "8", "--size", "80x60",
                              "--threads", "2", "--out", (dir / "orbit").string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const json& j = r.last_json;
  EXPECT_EQ(j.at("framed_on"), "surface") << Describe(r);
  EXPECT_GT(j.at("bounds_max").at(0).get<double>(), 14.0);  // the blocks' box
  EXPECT_GT(j.at("hit_fraction").get<double>(), 0.3) << Describe(r);
  const double room_centre[3] = {2.0, 1.5, 1.25};
  for (size_t k = 0; k < 3; ++k)
    EXPECT_NEAR(j.at("centre").at(k).get<double>(), room_centre[k], 0.1) << Describe(r);
  // The same bytes again.
  const RunResult again = RunCli({"render", map.string(), "--orbit", "8", "--size", "80x60",
                                  "--threads", "1", "--out", (dir / "again").string()});
  ASSERT_EQ(again.exit_code, 0) << Describe(again);
  for (int k = 0; k < 8; ++k) {
    const std::string name = "render_00" + std::to_string(k) + ".png";
    EXPECT_EQ(ReadAll(dir / "orbit" / name), ReadAll(dir / "again" / name)) << name;
  }
  const RunResult given =
      RunCli({"render", map.string(), "--orbit", "2", "--size", "80x60", "--orbit-radius", "9",
              "--orbit-height", "-4", "--out", (dir / "given").string()});
  ASSERT_EQ(given.exit_code, 0) << Describe(given);
  EXPECT_EQ(given.last_json.at("orbit_radius_m").get<double>(), 9.0);
  EXPECT_EQ(given.last_json.at("orbit_height_m").get<double>(), -4.0);
  const RunResult posed = RunCli({"render", map.string(), "--pose", "2 1.5 8 1 0 0 0", "--size",
                                  "80x60", "--out", (dir / "posed").string()});
  ASSERT_EQ(posed.exit_code, 0) << Describe(posed);
  EXPECT_FALSE(posed.last_json.contains("framed_on"));
  EXPECT_GT(posed.last_json.at("hit_fraction").get<double>(), 0.3) << Describe(posed);
}

// Normals mode: the floor (normal +y, green 255) and the wall (normal +z, blue 255) pixels of a
// view, and their mean rows.
struct RoomView {
  int floor = 0, wall = 0;
  double floor_row = 0.0, wall_row = 0.0;
};
RoomView SeeRoom(const ColorImage& image) {
  RoomView r;
  for (int v = 0; v < image.height; ++v)
    for (int u = 0; u < image.width; ++u) {
      const uint32_t c = image.at(u, v);
      if (Green(c) > 240) {
        ++r.floor;
        r.floor_row += v;
      } else if (Blue(c) > 240 && Green(c) > 60 && Green(c) < 200) {
        ++r.wall;
        r.wall_row += v;
      }
    }
  if (r.floor > 0) r.floor_row /= r.floor;
  if (r.wall > 0) r.wall_row /= r.wall;
  return r;
}

// The orbit turns about the up axis the map records: an ICL-like (y-up) map shows its room
// upright, the floor seen from above in every view and below the wall wherever the wall is in
// view. About z (a version 1 map's default, or --up z) the room lies on its side: some views
// see the floor only from below (nothing: rays pass back faces), the others above the wall.
TEST(RenderCliTest, OrbitsAboutTheUpAxisTheMapRecords) {
  const test::TempDir dir("voxplan-render-up");
  const fs::path map = dir / "room.vpmap", old_map = dir / "room_v1.vpmap";
  WriteYUpRoomMap(map, WorldUp::kPlusY);
  WriteYUpRoomMap(old_map, WorldUp::kPlusY, /*version1=*/true);
  const auto orbit = [&](const fs::path& input, const std::string& tag,
                         std::vector<std::string> extra) {
    std::vector<std::string> args = {
        "render", input.string(), "--orbit", "8",     "--size",
        "80x60",  "--mode",       "normals", "--out", (dir / tag).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const RunResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 0) << Describe(r);
    return r;
  };
  const RunResult recorded = orbit(map, "recorded", {});
  const RunResult about_z = orbit(map, "z", {"--up", "z"});
  const RunResult version1 = orbit(old_map, "v1", {});
  const RunResult given_y = orbit(old_map, "v1_y", {"--up", "y"});
  EXPECT_EQ(recorded.last_json.at("up"), json::array({0.0, 1.0, 0.0})) << Describe(recorded);
  EXPECT_EQ(recorded.last_json.at("up_source"), "map");
  EXPECT_EQ(about_z.last_json.at("up_source"), "--up");
  EXPECT_EQ(version1.last_json.at("up"), json::array({0.0, 0.0, 1.0})) << Describe(version1);
  EXPECT_EQ(version1.last_json.at("up_source"), "default");
  EXPECT_GT(recorded.last_json.at("hit_fraction").get<double>(), 0.15) << Describe(recorded);
  int walls_seen = 0, z_views_without_floor = 0, z_floor_above_wall = 0;
  for (int k = 0; k < 8; ++k) {
    const std::string name = "render_00" + std::to_string(k) + ".png";
    // A version 1 map renders as before (about z); --up y gives it the recorded axis' views.
    EXPECT_EQ(ReadAll(dir / "v1" / name), ReadAll(dir / "z" / name)) << name;
    EXPECT_EQ(ReadAll(dir / "v1_y" / name), ReadAll(dir / "recorded" / name)) << name;
    Result<ColorImage> upright = ReadColorImage((dir / "recorded" / name).string());
    Result<ColorImage> sideways = ReadColorImage((dir / "z" / name).string());
    ASSERT_TRUE(upright.ok() && sideways.ok());
    const RoomView r = SeeRoom(*upright), z = SeeRoom(*sideways);
    EXPECT_GT(r.floor, upright->width * upright->height / 10) << name;
    if (r.wall > 20) {
      ++walls_seen;
      EXPECT_LT(r.wall_row + 5.0, r.floor_row) << name;
    }
    z_views_without_floor += z.floor == 0;
    z_floor_above_wall += z.floor > 20 && z.wall > 20 && z.floor_row + 5.0 < z.wall_row;
  }
  EXPECT_GE(walls_seen, 4);
  EXPECT_GE(z_views_without_floor, 2);
  EXPECT_GE(z_floor_above_wall, 2);

  // voxplan info reports the recorded axis, and unknown for version 1.
  const RunResult info = RunCli({"info", map.string()});
  ASSERT_EQ(info.exit_code, 0) << Describe(info);
  EXPECT_EQ(info.last_json.at("version"), 2);
  EXPECT_EQ(info.last_json.at("up"), "+y");
  const RunResult old_info = RunCli({"info", old_map.string()});
  ASSERT_EQ(old_info.exit_code, 0) << Describe(old_info);
  EXPECT_EQ(old_info.last_json.at("version"), 1);
  EXPECT_EQ(old_info.last_json.at("up"), "unknown");
  EXPECT_EQ(
      RunCli({"render", map.string(), "--up", "w", "--out", (dir / "bad").string()}).exit_code, 2);
}

// Mean green (normals mode: the world normal's y, 0 for -y, 255 for +y) of the hit pixels in
// rows [v0, v1).
double MeanGreen(const ColorImage& image, int v0, int v1) {
  double sum = 0.0;
  int n = 0;
  for (int v = v0; v < v1; ++v)
    for (int u = 0; u < image.width; ++u)
      if (image.at(u, v) != PackRgb(48, 48, 48)) sum += Green(image.at(u, v)), ++n;
  return n > 0 ? sum / n : -1.0;
}

// ICL-NUIM (fy = -480, y up) fused, then rendered at its frames: the pictures are its frames',
// upright, with the ceiling (normal -y) on top; the same pose through a y-down camera would be
// upside down (render warns), and --intrinsics with the negative fy gives the dataset's picture.
TEST(RenderCliTest, RendersUprightAtAYFlippedDatasetsPoses) {
  const test::TempDir dir("voxplan-render-icl");
  const fs::path map = dir / "icl.vpmap";
  const RunResult fused =
      RunCli({"fuse", test::IclDir().string(), "--start", "80", "--frames", "30", "--voxel-size",
              "0.02", "--trunc", "0.08", "--threads", "2", "--map", map.string()});
  ASSERT_EQ(fused.exit_code, 0) << Describe(fused);
  EXPECT_EQ(fused.last_json.at("up"), "+y");
  EXPECT_NE(fused.last_json.at("up_source").get<std::string>().find("ICL-NUIM"), std::string::npos);
  const RunResult ds_info = RunCli({"info", test::IclDir().string()});
  EXPECT_EQ(ds_info.last_json.at("up"), "+y") << Describe(ds_info);

  const RunResult at =
      RunCli({"render", map.string(), "--dataset", test::IclDir().string(), "--start", "99",
              "--frames", "2", "--mode", "normals", "--out", (dir / "at").string()});
  ASSERT_EQ(at.exit_code, 0) << Describe(at);
  EXPECT_EQ(at.last_json.at("views"), 2);
  EXPECT_EQ(at.last_json.at("dataset_frames"), json::array({99, 100}));
  EXPECT_EQ(at.last_json.at("camera").at("fy").get<float>(), -480.f);
  EXPECT_EQ(at.last_json.at("rows_flipped"), false);
  EXPECT_EQ(at.last_json.at("dollhouse"), false);
  EXPECT_GT(at.last_json.at("hit_fraction").get<double>(), 0.5) << Describe(at);
  Result<ColorImage> image = ReadColorImage((dir / "at" / "render_000.png").string());
  ASSERT_TRUE(image.ok());
  ASSERT_EQ(image->width, 640);
  ASSERT_EQ(image->height, 480);
  // Frame id 100 looks at the ceiling's edge: the ceiling (normal -y) fills the top rows.
  EXPECT_LT(MeanGreen(*image, 0, 80), 60.0);
  EXPECT_GT(MeanGreen(*image, 400, 480), 100.0);

  // Its ground-truth pose (id 100), as --pose with a y-down camera: upside down, warned.
  std::ifstream gt(test::IclDir() / "traj0.gt.freiburg");
  std::string line, pose;
  while (std::getline(gt, line))
    if (line.rfind("100 ", 0) == 0) pose = line.substr(4);
  ASSERT_FALSE(pose.empty());
  const RunResult y_down = RunCli({"render", map.string(), "--pose", pose, "--size", "640x480",
                                   "--mode", "normals", "--out", (dir / "y_down").string()});
  ASSERT_EQ(y_down.exit_code, 0) << Describe(y_down);
  EXPECT_NE(y_down.err.find("upside down"), std::string::npos) << Describe(y_down);
  Result<ColorImage> flipped = ReadColorImage((dir / "y_down" / "render_000.png").string());
  ASSERT_TRUE(flipped.ok());
  EXPECT_LT(MeanGreen(*flipped, 400, 480), 60.0);  // the ceiling at the bottom
  // With the dataset's camera, the dataset's picture.
  const RunResult given =
      RunCli({"render", map.string(), "--pose", pose, "--size", "640x480", "--intrinsics",
              "481.2,-480,319.5,239.5", "--mode", "normals", "--out", (dir / "given").string()});
  ASSERT_EQ(given.exit_code, 0) << Describe(given);
  EXPECT_EQ(given.err.find("upside down"), std::string::npos) << Describe(given);
  EXPECT_EQ(ReadAll(dir / "given" / "render_000.png"), ReadAll(dir / "at" / "render_000.png"));

  // A version 1 map of it records no up axis: at the dataset's poses, the dataset's is taken.
  const fs::path old_map = dir / "icl_v1.vpmap";
  fs::copy_file(map, old_map);
  RewriteAsVersion1(old_map);
  const RunResult old_at =
      RunCli({"render", old_map.string(), "--dataset", test::IclDir().string(), "--start", "99",
              "--frames", "2", "--mode", "normals", "--out", (dir / "old_at").string()});
  ASSERT_EQ(old_at.exit_code, 0) << Describe(old_at);
  EXPECT_EQ(old_at.last_json.at("up_source"), "dataset");
  EXPECT_EQ(old_at.last_json.at("up"), json::array({0.0, 1.0, 0.0}));
  EXPECT_EQ(ReadAll(dir / "old_at" / "render_000.png"), ReadAll(dir / "at" / "render_000.png"));

  const RunResult usage = RunCli({"render", map.string(), "--dataset", test::IclDir().string(),
                                  "--orbit", "2", "--out", (dir / "bad").string()});
  EXPECT_EQ(usage.exit_code, 2) << Describe(usage);
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
