// Downstream use of an installed voxplan, written as in-tree code reads: fuse one synthetic
// depth frame of a wall 1 m in front of the camera, then check the signed distance around it,
// the extracted mesh against the true wall (voxplan::eval), a map file round trip and the depth
// frame read back from a 16-bit PNG by ReadDepthImage (whose file also holds the TIFF and EXR
// readers: linked with libtiff and OpenEXR as the package states). Prints what failed and exits 1,
// or prints a summary and exits 0.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "core/pose.h"
#include "core/queries.h"
#include "core/volume.h"
#include "eval/eval_mesh.h"
#include "fusion/integrate.h"
#include "fusion/mesh_extract.h"
#include "io/depth_image.h"
#include "io/image_io.h"
#include "io/map_io.h"

namespace {

constexpr float kVoxelM = 0.02f;
constexpr float kWallZM = 1.0f;

int Fail(const std::string& what) {
  std::fprintf(stderr, "downstream: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace voxplan;
  if (argc != 2) return Fail("usage: downstream OUT_DIR");

  const PinholeCamera camera{160, 120, 120.f, 120.f, 79.5f, 59.5f};
  const DepthImage depth(camera.width, camera.height, kWallZM);
  const Pose3f T_W_C = Pose3f::Identity();
  TsdfVolume volume({.voxel_size_m = kVoxelM, .trunc_m = 4 * kVoxelM});
  const Result<IntegrateStats> stats =
      IntegrateFrame(depth, ColorImage{}, camera, T_W_C, IntegrateParams{}, volume);
  if (!stats.ok()) return Fail("IntegrateFrame: " + stats.status().message());
  if (stats->blocks_allocated == 0) return Fail("no blocks allocated");

  // In front of the wall the distance is positive, behind it negative, on it about zero.
  const auto in_front = VoxelAtPoint(volume, {0.f, 0.f, kWallZM - 2.5f * kVoxelM});
  const auto behind = VoxelAtPoint(volume, {0.f, 0.f, kWallZM + 2.5f * kVoxelM});
  if (!in_front || !behind || !(in_front->tsdf_m > 0.f) || !(behind->tsdf_m < 0.f))
    return Fail("TSDF does not change sign across the wall");

  // The mesh lies on the wall: scored against the true wall (two triangles, wider than the view).
  const Mesh mesh = ExtractMesh(volume);
  if (mesh.empty()) return Fail("empty mesh");
  Mesh wall;
  wall.positions = {
      {-1.f, -1.f, kWallZM}, {1.f, -1.f, kWallZM}, {1.f, 1.f, kWallZM}, {-1.f, 1.f, kWallZM}};
  wall.triangles = {{0, 1, 2}, {0, 2, 3}};
  const Result<MeshEvalResult> score = EvaluateMesh(mesh, wall, {.threshold_m = kVoxelM});
  if (!score.ok()) return Fail("EvaluateMesh: " + score.status().message());
  if (!(score->accuracy_mean_m < 0.25 * kVoxelM))
    return Fail("mesh off the wall by " + std::to_string(score->accuracy_mean_m) + " m");

  // The map survives a save and a load.
  const std::string path = (std::filesystem::path(argv[1]) / "wall.vpmap").string();
  if (const Status saved = SaveMap(volume, path); !saved.ok())
    return Fail("SaveMap: " + saved.message());
  const Result<TsdfVolume> loaded = LoadMap(path);
  if (!loaded.ok()) return Fail("LoadMap: " + loaded.status().message());
  if (ExtractMesh(*loaded).num_triangles() != mesh.num_triangles())
    return Fail("loaded map meshes differently");

  // The depth frame as a dataset's 16-bit PNG, read back as the dataset readers read depth.
  const std::string png = (std::filesystem::path(argv[1]) / "wall_depth.png").string();
  if (const Status written = WriteDepthPng16(png, depth, 1000.0); !written.ok())
    return Fail("WriteDepthPng16: " + written.message());
  const Result<DepthImage> read = ReadDepthImage(png, 1000.0);
  if (!read.ok()) return Fail("ReadDepthImage: " + read.status().message());
  if (read->width != depth.width || read->height != depth.height ||
      std::fabs(read->at(7, 5) - kWallZM) > 1e-3f)
    return Fail("the depth PNG reads back differently");

  std::printf("downstream: %zu blocks, %zu triangles, accuracy %.5f m\n", stats->blocks_allocated,
              mesh.num_triangles(), score->accuracy_mean_m);
  return 0;
}
