// Outputs checked before any work: two outputs that are one file, or an output that is an input,
// are refused with exit 2 and nothing written or damaged; symbolic and hard links count. A
// command that writes several files and fails half-way leaves none of them behind.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

using test::Describe;
using test::ReadAll;
using test::RunCli;
using test::RunResult;

void WriteTextFile(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

using test::IclDir;

// The first three ICL-NUIM frames, copied: a dataset the tests may try to damage.
fs::path CopyIcl(const fs::path& dir) {
  const fs::path root = dir / "icl";
  fs::create_directories(root / "depth");
  fs::create_directories(root / "rgb");
  std::string list;
  for (int i = 1; i <= 3; ++i) {
    const std::string n = std::to_string(i);
    fs::copy_file(IclDir() / "depth" / (n + ".png"), root / "depth" / (n + ".png"));
    fs::copy_file(IclDir() / "rgb" / (n + ".jpg"), root / "rgb" / (n + ".jpg"));
    list += n + " depth/" + n + ".png " + n + " rgb/" + n + ".jpg\n";
  }
  WriteTextFile(root / "associations.txt", list);
  fs::copy_file(IclDir() / "traj0.gt.freiburg", root / "traj0.gt.freiburg");
  return root;
}

std::vector<std::string> Fuse(const fs::path& dataset, std::vector<std::string> outputs) {
  std::vector<std::string> args = {
      "fuse", dataset.string(), "--voxel-size", "0.05", "--trunc", "0.2", "--threads", "2"};
  args.insert(args.end(), outputs.begin(), outputs.end());
  return args;
}

// Exit 2 before any work, the message naming both options and the file.
void ExpectRefused(const RunResult& r, const std::string& a, const std::string& b,
                   const std::string& path) {
  EXPECT_EQ(r.exit_code, 2) << Describe(r);
  EXPECT_NE(r.err.find("error: "), std::string::npos) << Describe(r);
  EXPECT_NE(r.err.find(a), std::string::npos) << Describe(r);
  EXPECT_NE(r.err.find(b), std::string::npos) << Describe(r);
  EXPECT_NE(r.err.find(path), std::string::npos) << Describe(r);
  EXPECT_EQ(r.err.find("fused"), std::string::npos) << "work was done: " << Describe(r);
}

// Every file under `dir`, as relative paths.
std::vector<std::string> Files(const fs::path& dir) {
  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    files.push_back(fs::relative(e.path(), dir).string());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(OutputsCliTest, MapAndStatsOnOneFileAreRefused) {
  const test::TempDir dir("voxplan-outputs");
  const std::string x = (dir / "x.json").string();
  const RunResult r = RunCli(Fuse(IclDir(), {"--map", x, "--stats", x, "--frames", "2"}));
  ExpectRefused(r, "--map", "--stats", x);
  EXPECT_FALSE(fs::exists(x));
  EXPECT_TRUE(Files(dir.path()).empty());
}

TEST(OutputsCliTest, MeshAndFrameListOnOneFileAreRefusedAndItKeepsItsBytes) {
  const test::TempDir dir("voxplan-outputs");
  const fs::path x = dir / "x.ply";
  WriteTextFile(x, "old bytes");
  const RunResult r =
      RunCli(Fuse(IclDir(), {"--mesh", x.string(), "--frame-list", x.string(), "--frames", "2"}));
  ExpectRefused(r, "--mesh", "--frame-list", x.string());
  EXPECT_EQ(ReadAll(x), "old bytes");
}

TEST(OutputsCliTest, TrajectoryOverTheDatasetsGroundTruthIsRefused) {
  const test::TempDir dir("voxplan-outputs");
  const fs::path icl = CopyIcl(dir.path());
  const fs::path gt = icl / "traj0.gt.freiburg";
  const std::string before = ReadAll(gt);
  const RunResult r = RunCli(Fuse(icl, {"--trajectory", gt.string()}));
  ExpectRefused(r, "--trajectory", "the dataset", gt.string());
  EXPECT_EQ(ReadAll(gt), before);
  // The association list and the images are inputs too.
  const fs::path list = icl / "associations.txt";
  const std::string list_before = ReadAll(list);
  ExpectRefused(RunCli(Fuse(icl, {"--stats", list.string()})), "--stats", "the dataset",
                list.string());
  EXPECT_EQ(ReadAll(list), list_before);
  const fs::path depth = icl / "depth" / "2.png";
  const std::string depth_before = ReadAll(depth);
  ExpectRefused(RunCli(Fuse(icl, {"--frame-list", depth.string()})), "--frame-list", "the dataset",
                depth.string());
  EXPECT_EQ(ReadAll(depth), depth_before);
  // A new file in the dataset's folder is fine.
  const RunResult ok = RunCli(Fuse(icl, {"--trajectory", (icl / "estimate.txt").string()}));
  EXPECT_EQ(ok.exit_code, 0) << Describe(ok);
  EXPECT_EQ(ReadAll(gt), before);
}

TEST(OutputsCliTest, SymbolicAndHardLinksCount) {
  const test::TempDir dir("voxplan-outputs");
  const fs::path icl = CopyIcl(dir.path());
  const fs::path gt = icl / "traj0.gt.freiburg";
  const std::string before = ReadAll(gt);
  const fs::path hard = dir / "hard.txt", soft = dir / "soft.txt";
  fs::create_hard_link(gt, hard);
  fs::create_symlink(gt, soft);
  ExpectRefused(RunCli(Fuse(icl, {"--trajectory", hard.string()})), "--trajectory", "the dataset",
                hard.string());
  ExpectRefused(RunCli(Fuse(icl, {"--trajectory", soft.string()})), "--trajectory", "the dataset",
                soft.string());
  EXPECT_EQ(ReadAll(gt), before);

  // Two outputs through a symlinked folder, and through a link to a file not there yet.
  fs::create_directory(dir / "real");
  fs::create_directory_symlink(dir / "real", dir / "alias");
  const std::string a = (dir / "real" / "m.vpmap").string(),
                    b = (dir / "alias" / "m.vpmap").string();
  ExpectRefused(RunCli(Fuse(icl, {"--map", a, "--stats", b})), "--map", "--stats", b);
  fs::create_symlink(dir / "later.json", dir / "dangling.json");
  ExpectRefused(RunCli(Fuse(icl, {"--stats", (dir / "later.json").string(), "--frame-list",
                                  (dir / "dangling.json").string()})),
                "--stats", "--frame-list", (dir / "dangling.json").string());
  EXPECT_FALSE(fs::exists(dir / "real" / "m.vpmap"));
  EXPECT_FALSE(fs::exists(dir / "later.json"));
}

TEST(OutputsCliTest, MeshAndRenderOutputsMayNotBeTheirInput) {
  const test::TempDir dir("voxplan-outputs");
  const fs::path icl = CopyIcl(dir.path());
  const fs::path map = dir / "m.vpmap", ply = dir / "m.ply";
  ASSERT_EQ(RunCli(Fuse(icl, {"--map", map.string(), "--mesh", ply.string()})).exit_code, 0);
  const std::string map_before = ReadAll(map), ply_before = ReadAll(ply);
  // A hard link to the map under a mesh name, and a view file that is a link to the mesh.
  const fs::path linked = dir / "linked.ply";
  fs::create_hard_link(map, linked);
  ExpectRefused(RunCli({"mesh", map.string(), "--out", linked.string()}), "--out", "the map",
                linked.string());
  fs::create_directory(dir / "views");
  fs::create_symlink(ply, dir / "views" / "render_000.png");
  ExpectRefused(RunCli({"render", ply.string(), "--out", (dir / "views").string()}), "--out",
                "the input", "render_000.png");
  EXPECT_EQ(ReadAll(map), map_before);
  EXPECT_EQ(ReadAll(ply), ply_before);
}

TEST(OutputsCliTest, SimSceneOutputsMayNotBeItsScene) {
  const test::TempDir dir("voxplan-outputs");
  const fs::path out = dir / "w";
  const RunResult made = RunCli({"sim", "scene", "--generate", "apartment", "--size", "S",
                                 "--no-furniture-meshes", "--out", out.string()});
  ASSERT_EQ(made.exit_code, 0) << Describe(made);
  const fs::path scene = out / "world.ply";
  const std::string before = ReadAll(scene);
  const RunResult r = RunCli({"sim", "scene", "--scene", scene.string(), "--out", out.string()});
  ExpectRefused(r, "--out", "--scene", scene.string());
  EXPECT_EQ(ReadAll(scene), before);
}

// The last file sim scene writes cannot land (a folder is in its place): none of the others may
// be left behind, and the folder it created goes too.
TEST(OutputsCliTest, SimSceneThatFailsHalfWayLeavesNothingBehind) {
  const test::TempDir dir("voxplan-outputs");
  const fs::path out = dir / "w";
  fs::create_directories(out / "world_floor_plan.yaml");
  const std::vector<std::string> args = {
      "sim",   "scene",     "--generate", "apartment", "--size", "S", "--no-furniture-meshes",
      "--out", out.string()};
  const RunResult r = RunCli(args);
  EXPECT_EQ(r.exit_code, 1) << Describe(r);
  EXPECT_NE(r.err.find("world_floor_plan.yaml"), std::string::npos) << Describe(r);
  EXPECT_EQ(Files(out), std::vector<std::string>{"world_floor_plan.yaml"});

  // A folder it created goes too (here the writer refuses the file name once the world exists).
  std::vector<std::string> fresh_args = args;
  fresh_args.back() = (dir / "fresh").string();
  fresh_args.insert(fresh_args.end(), {"--name", "a/b"});
  const RunResult bad_name = RunCli(fresh_args);
  EXPECT_EQ(bad_name.exit_code, 1) << Describe(bad_name);
  EXPECT_FALSE(fs::exists(dir / "fresh")) << Describe(bad_name);
}

}  // namespace
}  // namespace voxplan
