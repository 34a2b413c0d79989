#pragma once
// The dataset folders fuzz_dataset fuzzes one file of, in every layout the readers know, and
// which file each role replaces; tests/fuzz/make_seeds.cpp seeds each role with its default.
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

namespace voxplan::fuzz {

struct FileSpec {
  std::string name, content;
};

// Every layout's files but its images; role r fuzzes kRoles[r].fuzzed in its own folder.
inline const std::vector<FileSpec> kTum = {
    {"depth.txt", "1.000000 d.png\n1.033333 d.png\n"},
    {"rgb.txt", "1.000000 c.png\n1.033333 c.png\n"},
    {"groundtruth.txt", "0.9 0 0 0 0 0 0 1\n1.1 0.1 0 0 0 0 0 1\n"},
    {"camera.txt", "20 20 1.5 1\n"}};
inline const std::vector<FileSpec> kIcl = {
    {"associations.txt", "0 d.png 0 c.png\n1 d.png 1 c.png\n"},
    {"traj0.gt.freiburg", "0 0 0 0 0 0 0 1\n1 0 0 0.1 0 0 0 1\n"}};
inline const std::vector<FileSpec> kRedwood = {
    {"camera.json", R"({"width": 4, "height": 3, "intrinsic_matrix": [20,0,0,0,20,0,1.5,1,1]})"},
    {"trajectory.log",
     "0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n1 1 2\n1 0 0 0.1\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"}};
inline const std::vector<FileSpec> kRedwoodMatch = {
    {"rgbd.match", "depth/000000.png color/000000.png\ndepth/000001.png color/000001.png\n"}};
inline const std::vector<FileSpec> kSevenScenes = {
    {"camera-intrinsics.txt", "20 0 1.5\n0 20 1\n0 0 1\n"},
    {"frame-000000.pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"}};
inline const std::vector<FileSpec> kReplica = {
    {"cam_params.json",
     R"({"camera": {"w": 4, "h": 3, "fx": 20, "fy": 20, "cx": 1.5, "cy": 1, "scale": 1000}})"},
    {"office0/traj.txt", "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n1 0 0 0.1 0 1 0 0 0 0 1 0 0 0 0 1\n"}};

enum class Layout { kTum, kIcl, kRedwood, kRedwoodMatch, kSevenScenes, kReplica };
struct Role {
  Layout layout;
  std::string fuzzed;
};
inline const Role kRoles[] = {
    {Layout::kTum, "depth.txt"},
    {Layout::kTum, "rgb.txt"},
    {Layout::kTum, "groundtruth.txt"},
    {Layout::kTum, "camera.txt"},
    {Layout::kIcl, "associations.txt"},
    {Layout::kIcl, "traj0.gt.freiburg"},
    {Layout::kRedwood, "trajectory.log"},
    {Layout::kRedwood, "camera.json"},
    {Layout::kRedwoodMatch, "rgbd.match"},
    {Layout::kSevenScenes, "camera-intrinsics.txt"},
    {Layout::kSevenScenes, "frame-000000.pose.txt"},
    {Layout::kReplica, "cam_params.json"},
    {Layout::kReplica, "office0/traj.txt"},
};
constexpr size_t kNumRoles = sizeof(kRoles) / sizeof(kRoles[0]);

// Paths of the layout's depth and colour images.
inline std::vector<std::pair<std::string, std::string>> Images(Layout layout) {
  switch (layout) {
    case Layout::kTum:
    case Layout::kIcl:
      return {{"d.png", "c.png"}};
    case Layout::kRedwood:
    case Layout::kRedwoodMatch:
      return {{"depth/000000.png", "color/000000.png"}, {"depth/000001.png", "color/000001.png"}};
    case Layout::kSevenScenes:
      return {{"frame-000000.depth.png", "frame-000000.color.png"},
              {"frame-000001.depth.png", "frame-000001.color.png"}};
    case Layout::kReplica:
      return {{"office0/results/depth000000.png", "office0/results/frame000000.png"},
              {"office0/results/depth000001.png", "office0/results/frame000001.png"}};
  }
  return {};
}

inline std::vector<FileSpec> Files(Layout layout) {
  switch (layout) {
    case Layout::kTum:
      return kTum;
    case Layout::kIcl:
      return kIcl;
    case Layout::kRedwood:
      return kRedwood;
    case Layout::kRedwoodMatch: {
      std::vector<FileSpec> files = kRedwood;
      files.insert(files.end(), kRedwoodMatch.begin(), kRedwoodMatch.end());
      return files;
    }
    case Layout::kSevenScenes:
      return kSevenScenes;
    case Layout::kReplica:
      return kReplica;
  }
  return {};
}

inline std::string DefaultContent(const Role& role) {
  for (const FileSpec& f : Files(role.layout))
    if (f.name == role.fuzzed) return f.content;
  std::abort();
}

}  // namespace voxplan::fuzz
