// The TUM trajectory reader: comments, CRLF and trailing comments read; malformed lines,
// non-unit quaternions and out-of-order timestamps refused with file:line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/tum_trajectory.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

TEST(TumTrajectoryTest, ReadsCommentsAndCrlfRefusesMalformedLines) {
  const test::TempDir dir("voxplan-traj");
  const auto good = dir / "good.txt";
  WriteText(good,
            "# timestamp tx ty tz qx qy qz qw\r\n"
            "\r\n"
            "1.0 0 0 0 0 0 0 1\r\n"
            "  2.0\t1 2 3 0 0 0.7071068 0.7071068  # trailing comment\r\n");
  Result<TumTrajectory> read = ReadTumTrajectory(good.string());
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->T_W_C.size(), 2u);
  EXPECT_DOUBLE_EQ(read->timestamps_s[1], 2.0);
  EXPECT_TRUE(read->T_W_C[1].translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  const Eigen::Vector3d x_rotated = read->T_W_C[1].linear() * Eigen::Vector3d::UnitX();
  EXPECT_TRUE(x_rotated.isApprox(Eigen::Vector3d::UnitY(), 1e-6));  // 90 deg about z

  const std::vector<std::pair<std::string, std::string>> bad = {
      {"short.txt", "# header\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n"},
      {"word.txt", "# header\n1.0 0 0 0 0 0 0 1\n2.0 0 0 x 0 0 0 1\n"},
      {"quat.txt", "# header\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 3\n"},
      {"order.txt", "# header\n2.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n"}};
  for (const auto& [name, text] : bad) {
    const std::string path = (dir / name).string();
    WriteText(path, text);
    Result<TumTrajectory> r = ReadTumTrajectory(path);
    ASSERT_FALSE(r.ok()) << name;
    EXPECT_NE(r.status().message().find(path + ":3:"), std::string::npos) << r.status().message();
  }
  const std::string empty = (dir / "empty.txt").string();
  WriteText(empty, "# nothing\n");
  EXPECT_FALSE(ReadTumTrajectory(empty).ok());
  EXPECT_FALSE(ReadTumTrajectory((dir / "missing.txt").string()).ok());
}

}  // namespace
}  // namespace voxplan
