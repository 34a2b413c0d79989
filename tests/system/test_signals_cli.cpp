// SIGINT and SIGTERM during `voxplan fuse` of a real sequence: the run stops after the current
// frame with 130 / 143, writes no requested output (a file it would have replaced keeps its
// bytes) and leaves no temporary file; a second signal stops it at once, equally clean.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using test::ReadAll;

struct Child {
  pid_t pid = -1;
  fs::path out, err;
};

// voxplan `args` in the background, stdout and stderr to files in `dir`.
Child Spawn(const std::vector<std::string>& args, const fs::path& dir) {
  Child c{-1, dir / "stdout", dir / "stderr"};
  std::vector<std::string> argv_strings = {VOXPLAN_CLI_PATH};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_strings) argv.push_back(a.data());
  argv.push_back(nullptr);
  c.pid = ::fork();
  if (c.pid == 0) {
    const int out = ::open(c.out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = ::open(c.err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(out, STDOUT_FILENO);
    ::dup2(err, STDERR_FILENO);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return c;
}

// Waits until stderr shows `text` (true) or the child ended or 60 s passed (false). Looks at an
// ended child without reaping it, so Wait still gets its status.
bool WaitFor(const Child& c, const std::string& text) {
  for (int i = 0; i < 60000; ++i) {
    if (ReadAll(c.err).find(text) != std::string::npos) return true;
    siginfo_t info{};
    if (::waitid(P_PID, id_t(c.pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid != 0)
      return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

// The exit status as the shell shows it: the code, or 128 + the signal that killed it.
int Wait(const Child& c) {
  int status = 0;
  ::waitpid(c.pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status) + 1000;
}

struct Outputs {
  fs::path map, mesh, stats, trajectory;
};

std::vector<std::string> FuseArgs(const Outputs& o, const std::string& voxel_size) {
  const fs::path icl = test::SharedDataDir() / "rgbd" / "iclnuim_office_traj0";
  return {"fuse",         icl.string(),
          "--voxel-size", voxel_size,
          "--threads",    "1",
          "--map",        o.map.string(),
          "--mesh",       o.mesh.string(),
          "--stats",      o.stats.string(),
          "--trajectory", o.trajectory.string()};
}

// Runs fuse, sends `sig` once it reports 10 % of the frames, and with `twice` the same again
// once it said it would stop after the frame (signals sent at once would merge into one).
// Returns the exit status.
int InterruptedFuse(const test::TempDir& dir, int sig, bool twice, std::string* err) {
  const Outputs o{dir / "out" / "m.vpmap", dir / "out" / "m.ply", dir / "out" / "s.json",
                  dir / "out" / "t.txt"};
  Child c = Spawn(FuseArgs(o, twice ? "0.004" : "0.01"), dir.path());
  EXPECT_GT(c.pid, 0);
  const bool started = WaitFor(c, "frames (10%)");
  EXPECT_TRUE(started) << ReadAll(c.err);
  ::kill(c.pid, sig);
  if (twice) {
    EXPECT_TRUE(WaitFor(c, "stopping after the current frame")) << ReadAll(c.err);
    ::kill(c.pid, sig);
  }
  const int code = Wait(c);
  *err = ReadAll(c.err);
  return code;
}

// The outputs folder holds only the stale map it held before: no new output, no temporary file.
void ExpectOnlyTheOldMap(const test::TempDir& dir) {
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir / "out")) files.push_back(e.path().filename());
  EXPECT_EQ(files, std::vector<std::string>{"m.vpmap"});
  EXPECT_EQ(ReadAll(dir / "out" / "m.vpmap"), "an older map");
}

void PrepareOut(const test::TempDir& dir) {
  fs::create_directory(dir / "out");
  std::ofstream(dir / "out" / "m.vpmap", std::ios::binary) << "an older map";
}

TEST(SignalsCliTest, SigintFinishesTheFrameAndWritesNothing) {
  const test::TempDir dir("voxplan-signals");
  PrepareOut(dir);
  std::string err;
  EXPECT_EQ(InterruptedFuse(dir, SIGINT, false, &err), 130) << err;
  EXPECT_NE(err.find("error: interrupted by SIGINT: stopped before frame"), std::string::npos)
      << err;
  ExpectOnlyTheOldMap(dir);
}

TEST(SignalsCliTest, SigtermFinishesTheFrameAndWritesNothing) {
  const test::TempDir dir("voxplan-signals");
  PrepareOut(dir);
  std::string err;
  EXPECT_EQ(InterruptedFuse(dir, SIGTERM, false, &err), 143) << err;
  EXPECT_NE(err.find("error: interrupted by SIGTERM: stopped before frame"), std::string::npos)
      << err;
  ExpectOnlyTheOldMap(dir);
}

TEST(SignalsCliTest, ASecondSignalStopsAtOnce) {
  const test::TempDir dir("voxplan-signals");
  PrepareOut(dir);
  std::string err;
  EXPECT_EQ(InterruptedFuse(dir, SIGINT, true, &err), 130) << err;
  EXPECT_NE(err.find("error: interrupted by SIGINT: stopped at once"), std::string::npos) << err;
  ExpectOnlyTheOldMap(dir);
}

}  // namespace
}  // namespace voxplan
