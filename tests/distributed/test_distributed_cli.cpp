// `mpirun -n N voxplan fuse` against one process, on loopback with oversubscription: the map
// (per voxel: the checksum of its sorted blocks) and the mesh (bytes) are the same for 1, 2 and
// 4 ranks, on a generated sequence and on a shared real one; a run with one rank killed mid-way,
// resumed from its checkpoint under another rank count, gives the same map and mesh; the task farm
// runs a task file over two ranks with the outputs of a serial run; commands that cannot run split
// refuse.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

// prefix + n, appended piecewise: `"r" + std::to_string(n)` trips a GCC 12 -Wrestrict false
// positive.
std::string Numbered(const std::string& prefix, int n, const std::string& suffix = "") {
  std::string s = prefix;
  s.append(std::to_string(n)).append(suffix);
  return s;
}
using test::Describe;
using test::ReadAll;
using test::RunCli;
using test::RunResult;

// mpirun in front of the CLI: as root in a container it needs the two variables, and more ranks
// than cores need --oversubscribe.
std::string Mpirun(int ranks) {
  return Numbered(
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
      "OMPI_MCA_rmaps_base_oversubscribe=1 mpirun --bind-to none -n ",
      ranks);
}

std::string Checksum(const fs::path& map) {
  const RunResult r = RunCli({"info", map.string()});
  EXPECT_EQ(r.exit_code, 0) << Describe(r);
  return r.last_json.is_object() ? r.last_json.value("checksum", std::string("none")) : "none";
}

// Fuses `args` in one process and under 1, 2 and 4 ranks; the maps and meshes must agree.
void ExpectSameOnAnyRankCount(const test::TempDir& dir, const std::vector<std::string>& args) {
  const fs::path map1 = dir / "serial.vpmap", mesh1 = dir / "serial.ply";
  std::vector<std::string> serial = args;
  serial.insert(serial.end(), {"--map", map1.string(), "--mesh", mesh1.string()});
  const RunResult base = RunCli(serial);
  ASSERT_EQ(base.exit_code, 0) << Describe(base);
  const std::string checksum = Checksum(map1), mesh = ReadAll(mesh1);
  ASSERT_GT(mesh.size(), 10000u);
  // 2 ranks twice: with the band walk split (the default) and whole on every rank.
  for (const auto& [ranks, walk] : std::vector<std::pair<int, std::string>>{
           {1, "split"}, {2, "split"}, {2, "whole"}, {4, "whole"}}) {
    const std::string tag = Numbered("r", ranks, walk);
    const fs::path map = dir / (tag + ".vpmap"), mesh_path = dir / (tag + ".ply");
    std::vector<std::string> split = args;
    split.insert(split.end(),
                 {"--map", map.string(), "--mesh", mesh_path.string(), "--band-walk", walk});
    const RunResult r = RunCli(split, Mpirun(ranks));
    ASSERT_EQ(r.exit_code, 0) << tag << "\n" << Describe(r);
    // One rank is the one-process run under mpirun; more report their ranks.
    if (ranks > 1) {
      EXPECT_EQ(r.last_json["ranks"], ranks) << Describe(r);
      EXPECT_EQ(r.last_json["band_walk"], walk) << Describe(r);
    }
    EXPECT_EQ(r.last_json["blocks"], base.last_json["blocks"]) << tag;
    EXPECT_EQ(Checksum(map), checksum) << tag;
    EXPECT_TRUE(ReadAll(mesh_path) == mesh) << tag << ": the mesh differs";
    if (ranks > 1) {
      // Each rank holds its share, not the whole map.
      const auto& rank_blocks = r.last_json["rank_blocks"];
      ASSERT_EQ(rank_blocks.size(), size_t(ranks));
      for (const auto& b : rank_blocks)
        EXPECT_LT(b.get<size_t>(), base.last_json["blocks"].get<size_t>());
      EXPECT_GT(r.last_json["broadcast_mb_per_frame"].get<double>(), 0.0);
    }
  }
}

TEST(DistributedCli, AGeneratedSequenceFusesTheSameOnOneTwoAndFourRanks) {
  const test::TempDir dir("voxplan-mpi-generated");
  RunResult r = RunCli({"sim", "scene", "--generate", "apartment", "--size", "S", "--seed", "2",
                        "--out", (dir / "apt").string(), "--no-glb"});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const std::string scene = (dir / "apt" / "world.ply").string();
  r = RunCli({"sim", "tour", "--scene", scene, "--out", (dir / "tour.txt").string(),
              "--frame-step-deg", "30", "--frame-step", "0.5"});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  r = RunCli({"sim", "render", "--scene", scene, "--trajectory", (dir / "tour.txt").string(),
              "--out", (dir / "seq").string(), "--size", "160x120", "--fx", "130"});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  ExpectSameOnAnyRankCount(dir, {"fuse", (dir / "seq").string(), "--frames", "40", "--voxel-size",
                                 "0.03", "--trunc", "0.12"});
}

TEST(DistributedCli, ARealSequenceFusesTheSameOnOneTwoAndFourRanks) {
  const test::TempDir dir("voxplan-mpi-icl");
  ExpectSameOnAnyRankCount(dir, {"fuse", test::IclDir().string(), "--frames", "40", "--voxel-size",
                                 "0.02", "--trunc", "0.08"});
}

TEST(DistributedCli, AKilledRunResumedFromItsCheckpointGivesTheSameMap) {
  const test::TempDir dir("voxplan-mpi-resume");
  const std::vector<std::string> args = {"fuse",         test::IclDir().string(),
                                         "--frames",     "150",
                                         "--voxel-size", "0.02",
                                         "--trunc",      "0.08",
                                         "--threads",    "1"};
  std::vector<std::string> serial = args;
  serial.insert(serial.end(), {"--map", (dir / "serial.vpmap").string(), "--mesh",
                               (dir / "serial.ply").string()});
  ASSERT_EQ(RunCli(serial).exit_code, 0);

  // Three ranks, a checkpoint every 10 frames; one rank is killed (SIGKILL) once the
  // checkpoint of 20 frames or more is in place.
  const fs::path map = dir / "split.vpmap";
  std::vector<std::string> split = args;
  split.insert(split.end(), {"--map", map.string(), "--checkpoint-every", "10"});
  RunResult killed_run;
  std::thread run([&] { killed_run = RunCli(split, Mpirun(3)); });
  bool killed = false;
  for (int i = 0; i < 1200 && !killed; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    const std::string manifest = ReadAll(map);
    for (const char* done : {"\"frames_done\": 20", "\"frames_done\": 30", "\"frames_done\": 40"})
      if (manifest.find(done) != std::string::npos) killed = true;
    if (manifest.find("\"complete\": true") != std::string::npos) break;
  }
  // One rank (not mpirun, whose command line starts with "mpirun"): mpirun then ends the others.
  if (killed) {
    const std::string kill_one_rank =
        "pgrep -f '^[^ ]*voxplan fuse .*" + map.string() + "' | tail -n 1 | xargs kill -KILL";
    EXPECT_EQ(std::system(kill_one_rank.c_str()), 0);
  }
  run.join();
  ASSERT_TRUE(killed) << "the run ended before a checkpoint could be seen";
  EXPECT_NE(killed_run.exit_code, 0) << Describe(killed_run);
  const std::string manifest = ReadAll(map);
  ASSERT_NE(manifest.find("\"complete\": false"), std::string::npos) << manifest.substr(0, 400);

  // Resumed under two ranks (the loader re-splits the shards), then written with the mesh.
  std::vector<std::string> resume = split;
  resume.insert(resume.end(), {"--resume", "--mesh", (dir / "split.ply").string()});
  const RunResult r = RunCli(resume, Mpirun(2));
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  EXPECT_GE(r.last_json["frames_resumed"].get<int>(), 20);
  EXPECT_EQ(Checksum(map), Checksum(dir / "serial.vpmap"));
  EXPECT_TRUE(ReadAll(dir / "split.ply") == ReadAll(dir / "serial.ply"));
  // Only the final generation's shards are left.
  size_t shards = 0;
  for (const auto& e : fs::directory_iterator(dir.path()))
    shards += e.path().filename().string().rfind("split.vpmap.g", 0) == 0;
  EXPECT_EQ(shards, 2u);
  // A second resume of a finished run changes nothing.
  const RunResult twice = RunCli(resume, Mpirun(2));
  ASSERT_EQ(twice.exit_code, 0) << Describe(twice);
  EXPECT_EQ(twice.last_json["frames_resumed"], 150) << Describe(twice);  // every frame was done
  EXPECT_EQ(Checksum(map), Checksum(dir / "serial.vpmap"));
}

TEST(DistributedCli, TheTaskFarmRunsATaskFileOverTwoRanksAsInOrder) {
  const test::TempDir dir("voxplan-mpi-farm");
  const fs::path tasks = dir / "tasks.txt";
  {
    std::ofstream f(tasks);
    // Long enough that the second rank is up and asking before the first has run them all.
    for (int i = 0; i < 6; ++i)
      f << "sleep 0.5; echo task " << i << " > " << (dir / Numbered("out", i)).string() << "\n";
    f << "exit 4\n";
  }
  const RunResult r =
      RunCli({"farm", tasks.string(), "--stats", (dir / "farm.json").string()}, Mpirun(2));
  EXPECT_EQ(r.exit_code, 1) << Describe(r);  // one task failed
  EXPECT_EQ(r.last_json["tasks"], 7) << Describe(r);
  EXPECT_EQ(r.last_json["failed"], 1);
  EXPECT_EQ(r.last_json["failed_tasks"], nlohmann::json::array({7}));
  // Both ranks ran tasks.
  EXPECT_GT(r.last_json["tasks_per_rank"][0].get<int>(), 0) << Describe(r);
  EXPECT_GT(r.last_json["tasks_per_rank"][1].get<int>(), 0) << Describe(r);
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(ReadAll(dir / Numbered("out", i)), Numbered("task ", i, "\n"));
}

TEST(DistributedCli, WhatCannotRunSplitIsRefusedWithTheReason) {
  const test::TempDir dir("voxplan-mpi-refuse");
  RunResult r = RunCli({"fuse", test::IclDir().string(), "--frames", "5", "--track"}, Mpirun(2));
  EXPECT_EQ(r.exit_code, 2) << Describe(r);
  EXPECT_NE(r.err.find("--track under mpirun"), std::string::npos) << Describe(r);
  r = RunCli({"info", test::IclDir().string()}, Mpirun(2));
  EXPECT_EQ(r.exit_code, 2) << Describe(r);
  EXPECT_NE(r.err.find("only fuse and farm run under mpirun"), std::string::npos) << Describe(r);
  r = RunCli({"fuse", test::IclDir().string(), "--frames", "5", "--resume"});
  EXPECT_EQ(r.exit_code, 2) << Describe(r);
  EXPECT_NE(r.err.find("need --map"), std::string::npos) << Describe(r);
}

}  // namespace
}  // namespace voxplan
