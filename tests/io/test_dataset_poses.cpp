// Poses the dataset readers can be trusted with: Redwood/Open3D frames matched to trajectory
// entries by the number in the file name (a missing frame or unpadded names shift nothing),
// ground truth not interpolated across long gaps, pose counts that differ warned with both
// numbers, non-rigid poses costing their frame (not the dataset), non-positive focal lengths
// from camera files refused as file:line. Fixtures are tiny folders written here.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/dataset.h"
#include "io/image_io.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

void WriteText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// A 16 x 12 depth PNG of a wall `z_m` away, in units of `scale` per metre.
void WriteDepth(const fs::path& p, float z_m = 1.5f, double scale = 1000.0) {
  fs::create_directories(p.parent_path());
  ASSERT_TRUE(WriteDepthPng16(p.string(), DepthImage(16, 12, z_m), scale).ok());
}

bool Contains(const std::string& s, const std::string& what) {
  return s.find(what) != std::string::npos;
}

bool AnyWarning(const DatasetInfo& info, const std::string& what) {
  return std::any_of(info.warnings.begin(), info.warnings.end(),
                     [&](const std::string& w) { return Contains(w, what); });
}

std::string Warnings(const DatasetInfo& info) {
  std::string all;
  for (const std::string& w : info.warnings) all += w + "\n";
  return all;
}

std::unique_ptr<Dataset> OpenOk(const fs::path& path, const DatasetOptions& options = {}) {
  auto ds = OpenDataset(path.string(), options);
  EXPECT_TRUE(ds.ok()) << ds.status().message();
  return ds.ok() ? std::move(ds).value() : nullptr;
}

DatasetOptions Format(DatasetFormat format) {
  DatasetOptions options;
  options.format = format;
  return options;
}

// A Redwood trajectory.log whose pose k is a translation of (k, 0, 0), for frames `ids`.
std::string RedwoodLog(const std::vector<int>& ids) {
  std::string log;
  for (int k : ids)
    log += std::to_string(k) + " " + std::to_string(k) + " " + std::to_string(ids.size()) +
           "\n1 0 0 " + std::to_string(k) + "\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  return log;
}

// The x translation of frame i's pose, or -1 without one.
double PoseX(const Dataset& ds, size_t i) {
  auto f = ds.Load(i);
  EXPECT_TRUE(f.ok()) << f.status().message();
  return f.ok() && f->T_W_C ? f->T_W_C->translation().x() : -1.0;
}

TEST(DatasetPoses, RedwoodMissingFrameKeepsLaterPosesRight) {
  for (const bool with_match : {false, true}) {
    SCOPED_TRACE(with_match ? "rgbd.match" : "depth/ listing");
    test::TempDir dir("redwood");
    std::string match;
    fs::create_directories(dir / "color");
    for (int k : {0, 1, 3, 4}) {  // 00002 is missing
      const std::string name = "0000" + std::to_string(k) + ".png";
      WriteDepth(dir / ("depth/" + name));
      ASSERT_TRUE(WriteColorPng((dir / ("color/" + name)).string(), ColorImage(16, 12)).ok());
      match += "depth/" + name + " color/" + name + "\n";
    }
    if (with_match) WriteText(dir / "rgbd.match", match);
    WriteText(dir / "trajectory.log", RedwoodLog({0, 1, 2, 3, 4}));
    auto ds = OpenOk(dir.path(), Format(DatasetFormat::kRedwood));
    ASSERT_TRUE(ds);
    ASSERT_EQ(ds->info().num_frames, 4u);
    EXPECT_EQ(PoseX(*ds, 1), 1.0);
    EXPECT_EQ(PoseX(*ds, 2), 3.0);  // by position it would get pose 2
    EXPECT_EQ(PoseX(*ds, 3), 4.0);
    EXPECT_TRUE(AnyWarning(ds->info(), "1 frame numbers missing between 0 and 4 (first: 2)"))
        << Warnings(ds->info());
    EXPECT_TRUE(AnyWarning(ds->info(), "5 poses for 4 frames")) << Warnings(ds->info());
  }
}

TEST(DatasetPoses, RedwoodUnpaddedNamesSortNumerically) {
  test::TempDir dir("redwood");
  std::vector<int> ids;
  for (int k = 0; k < 12; ++k) {
    WriteDepth(dir / ("depth/" + std::to_string(k) + ".png"));
    ids.push_back(k);
  }
  WriteText(dir / "trajectory.log", RedwoodLog(ids));
  auto ds = OpenOk(dir.path(), Format(DatasetFormat::kRedwood));
  ASSERT_TRUE(ds);
  ASSERT_EQ(ds->info().num_frames, 12u);
  for (size_t i = 0; i < 12; ++i) {
    auto f = ds->Load(i);
    ASSERT_TRUE(f.ok());
    EXPECT_EQ(fs::path(f->depth_path).filename(), std::to_string(i) + ".png");
    EXPECT_EQ(PoseX(*ds, i), double(i));
  }
  EXPECT_FALSE(AnyWarning(ds->info(), "missing")) << Warnings(ds->info());
}

// TUM ground truth at 0.00, 0.05, 0.10, then a 0.9 s gap to 1.00, 1.05.
void MakeGappyTum(const fs::path& root) {
  for (const char* n : {"a", "b", "c"}) WriteDepth(root / ("depth/" + std::string(n) + ".png"));
  WriteText(root / "depth.txt", "0.025 depth/a.png\n0.500 depth/b.png\n1.025 depth/c.png\n");
  WriteText(root / "groundtruth.txt",
            "0.00 0 0 0 0 0 0 1\n0.05 1 0 0 0 0 0 1\n0.10 2 0 0 0 0 0 1\n"
            "1.00 3 0 0 0 0 0 1\n1.05 4 0 0 0 0 0 1\n");
}

TEST(DatasetPoses, TumGroundTruthGapIsNotInterpolated) {
  test::TempDir dir("tum");
  MakeGappyTum(dir.path());
  auto ds = OpenOk(dir.path());  // default bound: 0.1 s
  ASSERT_TRUE(ds);
  ASSERT_EQ(ds->info().num_frames, 3u);
  EXPECT_DOUBLE_EQ(PoseX(*ds, 0), 0.5);  // within a 0.05 s step: interpolated
  auto b = ds->Load(1);
  ASSERT_TRUE(b.ok());
  EXPECT_FALSE(b->T_W_C.has_value());
  EXPECT_EQ(b->pose_rejected, PoseRejection::kGroundTruthGap);
  EXPECT_TRUE(Contains(b->pose_rejected_why, "depth.txt:2:")) << b->pose_rejected_why;
  EXPECT_TRUE(Contains(b->pose_rejected_why, "0.9 s gap")) << b->pose_rejected_why;
  EXPECT_TRUE(AnyWarning(ds->info(), "1 depth frames have no pose: they lie in gaps"))
      << Warnings(ds->info());
  EXPECT_NEAR(PoseX(*ds, 2), 3.5, 1e-9);

  DatasetOptions wide;
  wide.max_pose_gap_s = 1.0;  // a bound above the gap: interpolated again
  auto ds_wide = OpenOk(dir.path(), wide);
  ASSERT_TRUE(ds_wide);
  EXPECT_NEAR(PoseX(*ds_wide, 1), 2.0 + 0.4 / 0.9, 1e-9);

  DatasetOptions bad;
  bad.max_pose_gap_s = 0.0;
  EXPECT_FALSE(OpenDataset(dir.path().string(), bad).ok());
}

TEST(DatasetPoses, LongerOrShorterPoseListsAreWarnedWithBothCounts) {
  {
    SCOPED_TRACE("Replica: traj.txt with more poses than frames");
    test::TempDir dir("replica");
    WriteText(dir / "cam_params.json",
              "{\"camera\": {\"w\": 16, \"h\": 12, \"fx\": 600.0, \"fy\": 600.0, \"cx\": 7.5, "
              "\"cy\": 5.5, \"scale\": 6553.5}}");
    WriteDepth(dir / "office0/results/depth000000.png", 1.5f, 6553.5);
    const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n";
    WriteText(dir / "office0/traj.txt", identity + identity + identity);
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    EXPECT_TRUE(AnyWarning(ds->info(), "traj.txt: 3 poses for 1 frames; 2 poses match no frame"))
        << Warnings(ds->info());
  }
  {
    SCOPED_TRACE("ICL-NUIM: ground truth longer than the associations");
    test::TempDir dir("icl");
    WriteDepth(dir / "depth/1.png", 1.5f, 5000.0);
    WriteDepth(dir / "depth/2.png", 1.5f, 5000.0);
    WriteText(dir / "associations.txt",
              "1 depth/1.png 1 depth/1.png\n2 depth/2.png 2 depth/2.png\n");
    WriteText(dir / "traj0.gt.freiburg",
              "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n3 0 0 0 0 0 0 1\n4 0 0 0 0 0 0 1\n");
    auto ds = OpenOk(dir.path(), Format(DatasetFormat::kIclNuim));
    ASSERT_TRUE(ds);
    EXPECT_FLOAT_EQ(ds->info().camera.fy, -480.f);  // the format's own convention stays
    EXPECT_TRUE(AnyWarning(ds->info(), "4 poses for 2 frames; 2 poses match no frame"))
        << Warnings(ds->info());
  }
  {
    SCOPED_TRACE("Redwood: fewer poses than frames");
    test::TempDir dir("redwood");
    for (int k = 0; k < 4; ++k) WriteDepth(dir / ("depth/" + std::to_string(k) + ".png"));
    WriteText(dir / "trajectory.log", RedwoodLog({0, 1}));
    auto ds = OpenOk(dir.path(), Format(DatasetFormat::kRedwood));
    ASSERT_TRUE(ds);
    EXPECT_TRUE(AnyWarning(ds->info(), "2 poses for 4 frames; 2 frames have no pose"))
        << Warnings(ds->info());
  }
}

TEST(DatasetPoses, NonRigidPoseCostsItsFrameNotTheDataset) {
  test::TempDir dir("7s");
  WriteText(dir / "camera-intrinsics.txt", "585 0 7.5\n0 585 5.5\n0 0 1\n");
  for (int k = 0; k < 3; ++k) WriteDepth(dir / ("frame-00000" + std::to_string(k) + ".depth.png"));
  const std::string identity = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  WriteText(dir / "frame-000000.pose.txt", identity);
  WriteText(dir / "frame-000001.pose.txt", "-inf -inf -inf -inf\n" + identity.substr(8));
  WriteText(dir / "frame-000002.pose.txt", "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  auto ds = OpenOk(dir.path());
  ASSERT_TRUE(ds);
  ASSERT_EQ(ds->info().num_frames, 3u);
  EXPECT_TRUE(AnyWarning(ds->info(), "2 poses are not a rigid transform")) << Warnings(ds->info());
  EXPECT_TRUE(AnyWarning(ds->info(), "frame-000001.pose.txt:1:")) << Warnings(ds->info());
  EXPECT_EQ(PoseX(*ds, 0), 0.0);
  for (size_t i : {1u, 2u}) {
    auto f = ds->Load(i);
    ASSERT_TRUE(f.ok());
    EXPECT_FALSE(f->T_W_C.has_value());
    EXPECT_EQ(f->pose_rejected, PoseRejection::kBadValues);
  }
}

// The status failed naming `where` (file:line) and `what`.
void ExpectRefused(const fs::path& root, const std::string& where, const std::string& what) {
  auto ds = OpenDataset(root.string());
  ASSERT_FALSE(ds.ok()) << "accepted; expected " << where;
  EXPECT_TRUE(Contains(ds.status().message(), where)) << ds.status().message();
  EXPECT_TRUE(Contains(ds.status().message(), what)) << ds.status().message();
}

TEST(DatasetPoses, NonPositiveFocalLengthsFromCameraFilesAreRefused) {
  {
    test::TempDir dir("tum");
    MakeGappyTum(dir.path());
    // camera.txt is voxplan's own (sim render writes it): a negative fy is a y-flipped camera,
    // as ICL-NUIM's, which sim render can render; a negative fx is not.
    WriteText(dir / "camera.txt", "# fx fy cx cy\n-517.3 516.5 7.5 5.5\n");
    ExpectRefused(dir.path(), "camera.txt:2:", "fx -517.3 must be positive");
  }
  {
    test::TempDir dir("7s");
    WriteDepth(dir / "frame-000000.depth.png");
    WriteText(dir / "camera-intrinsics.txt", "-585 0 7.5\n0 585 5.5\n0 0 1\n");
    ExpectRefused(dir.path(), "camera-intrinsics.txt:1:", "fx -585 must be positive");
  }
  {
    test::TempDir dir("redwood");
    WriteDepth(dir / "depth/00000.png");
    WriteText(dir / "camera.json",
              "{\n  \"width\": 16,\n  \"height\": 12,\n  \"intrinsic_matrix\": [525, 0, 0, 0, "
              "-525, 0, 7.5, 5.5, 1]\n}\n");
    ExpectRefused(dir.path(), "camera.json:4:", "fy -525 must be positive");
  }
  {
    test::TempDir dir("replica");
    WriteText(dir / "cam_params.json",
              "{\"camera\": {\"w\": 16, \"h\": 12,\n \"fx\": 0.0,\n \"fy\": 600.0, \"cx\": 7.5, "
              "\"cy\": 5.5, \"scale\": 6553.5}}");
    WriteDepth(dir / "office0/results/depth000000.png", 1.5f, 6553.5);
    ExpectRefused(dir.path(), "cam_params.json:2:", "fx 0 must be positive");
  }
}

}  // namespace
}  // namespace voxplan
