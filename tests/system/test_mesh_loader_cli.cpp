// Every command that reads a mesh refuses a malformed one as a user would see it: exit 1, an
// `error:` naming the file and the reason; before the validating loader these crashed (SIGSEGV
// inside assimp on an out-of-range index or a truncated face list).
#include <gtest/gtest.h>

#include <cstring>
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
using test::RunCli;
using test::RunResult;

std::string Le32(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }

// A binary PLY triangle whose face is `face` (count byte, then int32 indices).
void WriteBadPly(const fs::path& path, const std::string& face_count_line,
                 const std::string& face) {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\n" +
      face_count_line + "property list uchar int vertex_indices\nend_header\n";
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bytes.append(reinterpret_cast<const char*>(xyz), sizeof(xyz));
  bytes += face;
  std::ofstream(path, std::ios::binary) << bytes;
}

TEST(MeshLoaderCli, EveryMeshReadingCommandRefusesAMalformedMesh) {
  test::TempDir dir("mesh_loader_cli");
  const fs::path oob = dir / "out_of_range.ply";
  WriteBadPly(oob, "element face 1\n", std::string(1, 3) + Le32(0) + Le32(1) + Le32(70000000));
  const fs::path cut = dir / "truncated.ply";
  WriteBadPly(cut, "element face 2\n",
              std::string(1, 4) + Le32(0) + Le32(1) + Le32(2) + Le32(0) + std::string(1, 3) +
                  Le32(0) + Le32(1));
  struct Case {
    fs::path mesh;
    const char* reason;
  };
  for (const Case& c : {Case{oob, "vertex index 70000000 is out of range"},
                        Case{cut, "the file ends in the middle of a record"}}) {
    const std::string m = c.mesh.string();
    const std::vector<std::vector<std::string>> commands = {
        {"eval", "mesh", m, m},
        {"render", m, "--size", "32x24", "--out", (dir / "render").string()},
        {"sim", "scene", "--scene", m, "--out", (dir / "scene").string()},
    };
    for (const auto& args : commands) {
      const RunResult r = RunCli(args);
      SCOPED_TRACE(args[0] + " " + args[1]);
      EXPECT_EQ(r.exit_code, 1) << Describe(r);
      EXPECT_NE(r.err.find("error: "), std::string::npos) << Describe(r);
      EXPECT_NE(r.err.find(m), std::string::npos) << Describe(r);
      EXPECT_NE(r.err.find(c.reason), std::string::npos) << Describe(r);
    }
  }
}

}  // namespace
}  // namespace voxplan
