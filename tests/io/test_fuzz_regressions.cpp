// Inputs the libFuzzer targets (tests/fuzz) found crashing, aborting or hanging the old mesh
// path (assimp's PLY importer), kept as files and replayed: each must now be refused, quickly,
// with a message naming the file.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>

#include "io/mesh_io.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

TEST(FuzzRegressions, MeshCrashersAreRefusedNamingTheFile) {
  const fs::path dir = fs::path(VOXPLAN_FUZZ_REGRESSIONS_DIR) / "mesh";
  int replayed = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    SCOPED_TRACE(e.path().string());
    const auto start = std::chrono::steady_clock::now();
    const Result<Mesh> mesh = ReadMesh(e.path().string());
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_FALSE(mesh.ok());
    EXPECT_NE(mesh.status().message().find(e.path().filename().string()), std::string::npos)
        << mesh.status().message();
    EXPECT_LT(s, 5.0);
    ++replayed;
  }
  EXPECT_GE(replayed, 4);
}

}  // namespace
}  // namespace voxplan
