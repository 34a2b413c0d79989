// Writes the fuzz targets' seed corpora: `fuzz_make_seeds OUT_DIR [SHARED_DATA_DIR]` fills
// OUT_DIR/<target>/ with small inputs: fixtures the library writes itself (a map, a mesh in each
// format, PNGs of each kind, a trajectory, ScanNet .sens scans, ROS bags and each bag slot's
// message), each dataset role's default file, planner configs,
// and, when the shared data is there, excerpts of it (first lines of its text files, the first
// bytes of its meshes and colour images, crops of its depth images). Nothing is committed.
#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/volume.h"
#include "io/image_io.h"
#include "io/map_io.h"
#include "io/mesh_io.h"
#include "io/sens_file.h"
#include "io/tum_trajectory.h"
#include "tests/fuzz/dataset_scaffold.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/rosbag_scaffold.h"

namespace {

using namespace voxplan;
namespace fs = std::filesystem;

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void Put(const fs::path& dir, const std::string& name, const std::string& bytes) {
  fs::create_directories(dir);
  fuzz::WriteText(dir / name, bytes);
}

// A sphere of radius 3 voxels in the middle of one block, observed.
TsdfVolume SphereVolume() {
  TsdfVolume volume({0.05f, 0.2f});
  TsdfBlock& block = volume.FindOrAllocate({0, 0, 0});
  for (int z = 0; z < kBlockSide; ++z)
    for (int y = 0; y < kBlockSide; ++y)
      for (int x = 0; x < kBlockSide; ++x) {
        const int i = x + kBlockSide * (y + kBlockSide * z);
        const float d = std::sqrt(float((x - 4) * (x - 4) + (y - 4) * (y - 4) + (z - 4) * (z - 4)));
        block.tsdf[i] = EncodeTsdf((d - 3.f) * 0.05f / 0.2f);
        block.weight[i] = EncodeWeight(2.f);
        block.r[i] = uint8_t(30 * x);
        block.g[i] = uint8_t(30 * y);
        block.b[i] = uint8_t(30 * z);
      }
  return volume;
}

Mesh Tetrahedron() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

void LibraryFixtures(const fs::path& out) {
  const fs::path tmp = fuzz::ScratchDir();
  if (!SaveMap(SphereVolume(), (tmp / "m.vpmap").string()).ok()) std::abort();
  Put(out / "fuzz_map", "sphere.vpmap", ReadAll(tmp / "m.vpmap"));
  if (!SaveMap(TsdfVolume({0.01f, 0.04f}), (tmp / "e.vpmap").string()).ok()) std::abort();
  Put(out / "fuzz_map", "empty.vpmap", ReadAll(tmp / "e.vpmap"));
  // Version 2 with an up axis, and the same map as version 1 wrote it (no up field).
  if (!SaveMap(SphereVolume(), (tmp / "y.vpmap").string(), WorldUp::kPlusY).ok()) std::abort();
  const std::string y_up = ReadAll(tmp / "y.vpmap");
  Put(out / "fuzz_map", "sphere_y_up.vpmap", y_up);
  std::string v1 = y_up.substr(0, 28) + y_up.substr(32, y_up.size() - 32 - 8);
  v1[8] = 1;                           // the version's low byte (little-endian)
  uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a 64, as map_io.cpp checksums
  for (unsigned char c : v1) h = (h ^ c) * 0x100000001b3ull;
  v1.append(reinterpret_cast<const char*>(&h), 8);
  Put(out / "fuzz_map", "sphere_v1.vpmap", v1);

  const char* const extensions[] = {".ply", ".obj", ".glb", ".stl"};  // fuzz_mesh's first byte
  for (int e = 0; e < 4; ++e) {
    const fs::path p = tmp / (std::string("t") + extensions[e]);
    if (!WriteMesh(Tetrahedron(), p.string()).ok()) std::abort();
    Put(out / "fuzz_mesh", std::string("tetra") + extensions[e], char(e) + ReadAll(p));
  }
  Put(out / "fuzz_mesh", "ascii.ply",
      std::string(1, '\0') +
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
          "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");

  std::vector<uint16_t> samples(8 * 6 * 4);
  for (size_t i = 0; i < samples.size(); ++i) samples[i] = uint16_t(i * 997);
  for (int channels = 1; channels <= 4; ++channels)
    for (int bits : {8, 16}) {
      const fs::path p = tmp / "i.png";
      std::vector<uint8_t> bytes(samples.size());
      for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = uint8_t(samples[i]);
      const void* data = bits == 8 ? static_cast<const void*>(bytes.data()) : samples.data();
      if (!WritePngRaw(p.string(), 8, 6, channels, bits, data).ok()) std::abort();
      Put(out / "fuzz_image", "c" + std::to_string(channels) + "b" + std::to_string(bits) + ".png",
          ReadAll(p));
    }

  const Pose3d pose = Pose3d::Identity();
  if (!WriteTumTrajectory((tmp / "t.txt").string(), {0.0, 0.5}, {pose, pose}).ok()) std::abort();
  Put(out / "fuzz_tum_trajectory", "written.txt", ReadAll(tmp / "t.txt"));
  Put(out / "fuzz_tum_trajectory", "comments.txt",
      "\xEF\xBB\xBF# t tx ty tz qx qy qz qw\r\n1.0 0 0 0 0 0 0 1 # first\r\n\r\n"
      "+2.5 1e-3 -2 3 0 0 0.7071068 0.7071068\r\n");
}

// --- ScanNet .sens (SensorData version 4, little-endian; tests/io/sens_fixture.h writes the same)
void PutU32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(char((v >> (8 * i)) & 0xff));
}
void PutU64(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(char((v >> (8 * i)) & 0xff));
}
void PutMatrix(std::string& out, const Eigen::Matrix4f& m) {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) PutU32(out, std::bit_cast<uint32_t>(m(r, c)));
}
Eigen::Matrix4f Intrinsic(float f, int width, int height) {
  Eigen::Matrix4f k = Eigen::Matrix4f::Identity();
  k(0, 0) = k(1, 1) = f;
  k(0, 2) = float(width - 1) / 2.f;
  k(1, 2) = float(height - 1) / 2.f;
  return k;
}

struct SensSeedFrame {
  Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
  std::string color, depth;
};

std::string EncodeSens(const SensHeader& h, const std::vector<SensSeedFrame>& frames) {
  std::string out;
  PutU32(out, 4);
  PutU64(out, h.sensor_name.size());
  out += h.sensor_name;
  for (const Eigen::Matrix4f* m :
       {&h.color_intrinsic, &h.color_extrinsic, &h.depth_intrinsic, &h.depth_extrinsic})
    PutMatrix(out, *m);
  PutU32(out, uint32_t(h.color_compression));
  PutU32(out, uint32_t(h.depth_compression));
  for (int side : {h.color_width, h.color_height, h.depth_width, h.depth_height})
    PutU32(out, uint32_t(side));
  PutU32(out, std::bit_cast<uint32_t>(h.depth_shift));
  PutU64(out, frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    PutMatrix(out, frames[i].pose);
    PutU64(out, 1000000 + 33333 * i);  // colour, depth timestamps (us)
    PutU64(out, 1000000 + 33333 * i);
    PutU64(out, frames[i].color.size());
    PutU64(out, frames[i].depth.size());
    out += frames[i].color;
    out += frames[i].depth;
  }
  return out;
}

std::string RawDepth(int width, int height, int frame) {
  std::string raw;
  for (int k = 0; k < width * height; ++k) {
    const unsigned mm = unsigned(1500 + 10 * k + 50 * frame);
    raw.push_back(char(mm & 0xff));
    raw.push_back(char(mm >> 8));
  }
  return raw;
}

std::string Zlib(const std::string& raw) {
  uLongf size = compressBound(uLong(raw.size()));
  std::string out(size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(out.data()), &size,
                reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()), 6) != Z_OK)
    std::abort();
  out.resize(size);
  return out;
}

std::string RawRgb(const ColorImage& c) {
  std::string out;
  for (uint32_t p : c.data) {
    out.push_back(char(Red(p)));
    out.push_back(char(Green(p)));
    out.push_back(char(Blue(p)));
  }
  return out;
}

void SensSeeds(const fs::path& out) {
  const fs::path dir = out / "fuzz_sens";
  // ScanNet's own kind: zlib depth 4x3, JPEG colour at twice the size (a resize), one lost pose.
  SensHeader h;
  h.sensor_name = "StructureSensor";
  h.depth_width = 4, h.depth_height = 3, h.color_width = 8, h.color_height = 6;
  h.depth_intrinsic = Intrinsic(4.f, 4, 3);
  h.color_intrinsic = Intrinsic(8.f, 8, 6);
  h.color_extrinsic = h.depth_extrinsic = Eigen::Matrix4f::Identity();
  const std::string jpeg = EncodeJpeg(fuzz::BagColor(8, 6), 90).value();
  std::vector<SensSeedFrame> frames(3);
  for (int i = 0; i < 3; ++i) {
    frames[size_t(i)].pose(0, 3) = 0.05f * float(i);
    frames[size_t(i)].color = jpeg;
    frames[size_t(i)].depth = Zlib(RawDepth(4, 3, i));
  }
  frames[1].pose.setConstant(-std::numeric_limits<float>::infinity());
  Put(dir, "scannet.sens", EncodeSens(h, frames));

  // Raw depth and raw colour of the same size, the colour camera 2 cm to the side.
  h.sensor_name = "raw";
  h.color_compression = SensColorCompression::kRaw;
  h.depth_compression = SensDepthCompression::kRawUshort;
  h.color_width = 4, h.color_height = 3;
  h.color_intrinsic = Intrinsic(4.f, 4, 3);
  h.depth_extrinsic(0, 3) = 0.02f;
  std::vector<SensSeedFrame> raw(2);
  for (int i = 0; i < 2; ++i) {
    raw[size_t(i)].color = RawRgb(fuzz::BagColor(4, 3));
    raw[size_t(i)].depth = RawDepth(4, 3, i);
  }
  Put(dir, "raw.sens", EncodeSens(h, raw));

  // PNG colour; and depth alone (no colour size, no colour bytes).
  const fs::path png = fuzz::ScratchDir() / "sens.png";
  std::vector<uint8_t> rgb(4 * 3 * 3, 200);
  if (!WritePngRaw(png.string(), 4, 3, 3, 8, rgb.data()).ok()) std::abort();
  h.sensor_name = "png";
  h.color_compression = SensColorCompression::kPng;
  h.depth_compression = SensDepthCompression::kZlibUshort;
  h.depth_extrinsic = Eigen::Matrix4f::Identity();
  std::vector<SensSeedFrame> with_png(2);
  for (int i = 0; i < 2; ++i) {
    with_png[size_t(i)].color = ReadAll(png);
    with_png[size_t(i)].depth = Zlib(RawDepth(4, 3, i));
  }
  Put(dir, "png.sens", EncodeSens(h, with_png));
  h.sensor_name = "";
  h.color_width = h.color_height = 0;
  for (SensSeedFrame& f : with_png) f.color.clear();
  Put(dir, "depth_only.sens", EncodeSens(h, with_png));
}

// --- ROS 1 bags: the scaffold's two layouts whole, and each slot's message
void BagSeeds(const fs::path& out) {
  const fs::path tmp = fuzz::ScratchDir() / "seed.bag";
  for (auto [layout, name] : {std::pair{fuzz::BagLayout::kA, "tf_bgr8_16uc1.bag"},
                              std::pair{fuzz::BagLayout::kB, "pose_jpeg_32fc1.bag"}}) {
    fuzz::WriteBagFile(tmp.string(), fuzz::BagMessages(layout));
    Put(out / "fuzz_rosbag", name, ReadAll(tmp));
  }
  for (size_t s = 0; s < fuzz::kNumBagSlots; ++s)
    Put(out / "fuzz_ros_messages", "slot" + std::to_string(s), char(s) + fuzz::SlotDefault(s));
}

void HandWritten(const fs::path& out) {
  for (size_t r = 0; r < fuzz::kNumRoles; ++r)
    Put(out / "fuzz_dataset", "role" + std::to_string(r),
        char(r) + fuzz::DefaultContent(fuzz::kRoles[r]));
  // fuzz_planner_config's first byte: 0 omt, 1 greedy, 2 voronoi.
  const std::vector<std::pair<int, std::string>> configs = {
      {0, "{}"},
      {0, R"({"kappa": 3, "importance_threshold": 0.5, "geodesics": "internal", "refine": true})"},
      {0, R"({"use_tsp": false, "delta_m": 0.25, "team_views_per_robot": 4, "num_threads": 2})"},
      {1, R"({"policy": "nearest", "claim_radius_m": 1.5, "dwell_s": 0.5})"},
      {1, R"({"policy": "best", "fov_from_robot": true, "robot_radius_m": 0.2})"},
      {2, R"({"tasks_per_call": 3, "surface_min_height_m": 0.1, "weight_scale": 2})"}};
  for (size_t i = 0; i < configs.size(); ++i)
    Put(out / "fuzz_planner_config", "config" + std::to_string(i),
        char(configs[i].first) + configs[i].second);
}

std::string FirstLines(const fs::path& path, int lines) {
  std::ifstream in(path, std::ios::binary);
  std::string text, line;
  for (int i = 0; i < lines && std::getline(in, line); ++i) text += line + "\n";
  return text;
}

// Excerpts of the shared data; each source is optional.
void SharedData(const fs::path& out, const fs::path& data) {
  std::error_code ec;
  const fs::path rgbd = data / "rgbd";
  const auto excerpt = [&](const std::string& target, const std::string& name, int prefix,
                           const fs::path& source, int lines) {
    if (!fs::is_regular_file(source, ec)) return;
    const std::string text = FirstLines(source, lines);
    Put(out / target, name, prefix < 0 ? text : char(prefix) + text);
  };
  const fs::path icl = rgbd / "iclnuim_office_traj0";
  excerpt("fuzz_tum_trajectory", "icl_gt", -1, icl / "traj0.gt.freiburg", 20);
  excerpt("fuzz_dataset", "icl_assoc", 4, icl / "associations.txt", 10);
  excerpt("fuzz_dataset", "icl_gt", 5, icl / "traj0.gt.freiburg", 10);
  excerpt("fuzz_dataset", "tum_gt", 2, icl / "traj0.gt.freiburg", 10);
  const fs::path redwood = rgbd / "open3d_livingroom5";
  excerpt("fuzz_dataset", "redwood_log", 6, redwood / "trajectory.log", 20);
  excerpt("fuzz_dataset", "redwood_camera", 7, redwood / "camera_primesense.json", 40);
  excerpt("fuzz_dataset", "redwood_match", 8, redwood / "rgbd.match", 5);
  const fs::path seven = rgbd / "7scenes_redkitchen";
  excerpt("fuzz_dataset", "7scenes_intrinsics", 9, seven / "camera-intrinsics.txt", 5);
  excerpt("fuzz_dataset", "3dmatch_intrinsics", 9, rgbd / "3dmatch_sun3d5/camera-intrinsics.txt",
          5);
  excerpt("fuzz_dataset", "7scenes_pose", 10, seven / "frame-000000.pose.txt", 5);
  const fs::path replica = rgbd / "replica_office0";
  excerpt("fuzz_dataset", "replica_params", 11, replica / "cam_params.json", 40);
  excerpt("fuzz_dataset", "replica_traj", 12, replica / "office0/traj.txt", 3);

  const auto head = [&](const std::string& target, const std::string& name, const std::string& pre,
                        const fs::path& source, size_t bytes) {
    if (!fs::is_regular_file(source, ec)) return;
    Put(out / target, name, pre + ReadAll(source).substr(0, bytes));
  };
  head("fuzz_mesh", "table.ply", std::string(1, '\0'),
       data / "scenes/simple_room/receptacle_mesh_simple_room_table.ply", 8192);
  head("fuzz_mesh", "cornell.obj", std::string(1, '\1'),
       data / "scenes/cornell_box/CornellBox-Original.obj", 8192);
  head("fuzz_mesh", "room.glb", std::string(1, '\2'), data / "scenes/simple_room/simple_room.glb",
       12000);
  head("fuzz_image", "seven.jpg", "", seven / "frame-000000.color.jpg", 12000);

  // Depth images cropped to 16x12, as 16-bit PNGs the library writes.
  const fs::path depths[] = {seven / "frame-000000.depth.png", icl / "depth/1.png",
                             redwood / "depth/00000.png",
                             replica / "office0/results/depth000000.png"};
  int n = 0;
  for (const fs::path& p : depths) {
    const Result<DepthImage> depth = ReadDepthPng(p.string(), 1.0);
    if (!depth.ok()) continue;
    std::vector<uint16_t> crop;
    for (int y = 0; y < 12 && y < depth->height; ++y)
      for (int x = 0; x < 16 && x < depth->width; ++x)
        crop.push_back(uint16_t(depth->data[size_t(y) * size_t(depth->width) + size_t(x)]));
    const fs::path tmp = fuzz::ScratchDir() / "d.png";
    if (crop.size() == 16 * 12 && WritePngRaw(tmp.string(), 16, 12, 1, 16, crop.data()).ok())
      Put(out / "fuzz_image", "depth" + std::to_string(n++) + ".png", ReadAll(tmp));
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: fuzz_make_seeds OUT_DIR [SHARED_DATA_DIR]\n";
    return 2;
  }
  const fs::path out = argv[1];
  LibraryFixtures(out);
  SensSeeds(out);
  BagSeeds(out);
  HandWritten(out);
  if (argc > 2) SharedData(out, argv[2]);
  return 0;
}
