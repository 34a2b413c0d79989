#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

fs::path Rgbd() { return test::SharedDataDir() / "rgbd"; }

void WriteText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream out(p, std::ios::binary);
  out << text;
}

void Copy(const fs::path& from, const fs::path& to) {
  fs::create_directories(to.parent_path());
  fs::copy_file(from, to, fs::copy_options::overwrite_existing);
  fs::permissions(to, fs::perms::owner_read | fs::perms::owner_write);  // shared data is read-only
}

bool Contains(const std::string& s, const std::string& what) {
  return s.find(what) != std::string::npos;
}

// The status failed and its message names every one of `what` (file, file:line, ...).
void ExpectError(const Status& s, std::initializer_list<std::string> what) {
  ASSERT_FALSE(s.ok()) << "expected an error";
  for (const std::string& w : what) EXPECT_TRUE(Contains(s.message(), w)) << s.message();
}

bool AnyWarning(const DatasetInfo& info, const std::string& what) {
  return std::any_of(info.warnings.begin(), info.warnings.end(),
                     [&](const std::string& w) { return Contains(w, what); });
}

float MedianDepth(const DepthImage& depth) {
  std::vector<float> v;
  for (float d : depth.data)
    if (d > 0.f) v.push_back(d);
  if (v.empty()) return 0.f;
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

std::unique_ptr<Dataset> OpenOk(const fs::path& path, const DatasetOptions& options = {}) {
  auto ds = OpenDataset(path.string(), options);
  EXPECT_TRUE(ds.ok()) << ds.status().message();
  return ds.ok() ? std::move(ds).value() : nullptr;
}

// ------------------------------------------------------------------------------------------
// Every reader on its real sequence.

TEST(Datasets, IclNuim) {
  auto ds = OpenOk(Rgbd() / "iclnuim_office_traj0");
  ASSERT_TRUE(ds);
  const DatasetInfo& info = ds->info();
  EXPECT_EQ(info.format, DatasetFormat::kIclNuim);
  EXPECT_EQ(info.num_frames, 200u);  // id 1 is kept, without a pose
  EXPECT_FLOAT_EQ(info.camera.fx, 481.2f);
  EXPECT_FLOAT_EQ(info.camera.fy, -480.f);  // the trap: flipped y axis
  EXPECT_FLOAT_EQ(info.camera.cx, 319.5f);
  EXPECT_FLOAT_EQ(info.camera.cy, 239.5f);
  EXPECT_EQ(info.camera.width, 640);
  EXPECT_EQ(info.camera.height, 480);
  EXPECT_EQ(info.depth_scale, 5000.0);
  EXPECT_TRUE(info.has_color);
  EXPECT_TRUE(Contains(info.pose_source, "traj0.gt.freiburg"));
  EXPECT_TRUE(AnyWarning(info, "associations.txt:1:"));

  auto f0 = ds->Load(0);
  ASSERT_TRUE(f0.ok()) << f0.status().message();
  EXPECT_FALSE(f0->T_W_C.has_value());
  EXPECT_EQ(f0->timestamp, 1.0);

  auto f1 = ds->Load(1);  // id 2: `2 0.000472546 0.00897074 -2.5 -0.00101357 0.000506464 ...`
  ASSERT_TRUE(f1.ok()) << f1.status().message();
  ASSERT_TRUE(f1->T_W_C.has_value());
  EXPECT_EQ(f1->timestamp, 2.0);
  EXPECT_NEAR(f1->T_W_C->translation().x(), 0.000472546, 1e-9);
  EXPECT_NEAR(f1->T_W_C->translation().y(), 0.00897074, 1e-9);
  EXPECT_NEAR(f1->T_W_C->translation().z(), -2.5, 1e-9);
  const Eigen::Quaterniond q(f1->T_W_C->linear());
  EXPECT_NEAR(std::abs(q.x()), 0.00101357, 1e-6);
  EXPECT_EQ(f1->depth.width, 640);
  EXPECT_EQ(f1->color.width, 640);
  EXPECT_TRUE(Contains(f1->depth_path, "depth/2.png"));
  const float median = MedianDepth(f1->depth);
  EXPECT_GT(median, 0.5f);
  EXPECT_LT(median, 6.f);
  EXPECT_FALSE(ds->Load(200).ok());
}

TEST(Datasets, SevenScenes) {
  auto ds = OpenOk(Rgbd() / "7scenes_redkitchen");
  ASSERT_TRUE(ds);
  const DatasetInfo& info = ds->info();
  EXPECT_EQ(info.format, DatasetFormat::kSevenScenes);
  EXPECT_EQ(info.num_frames, 400u);
  EXPECT_FLOAT_EQ(info.camera.fx, 585.f);
  EXPECT_FLOAT_EQ(info.camera.fy, 585.f);
  EXPECT_FLOAT_EQ(info.camera.cx, 320.f);
  EXPECT_FLOAT_EQ(info.camera.cy, 240.f);
  EXPECT_EQ(info.depth_scale, 1000.0);
  EXPECT_TRUE(info.has_color);
  EXPECT_TRUE(Contains(info.intrinsics_source, "camera-intrinsics.txt"));
  EXPECT_TRUE(info.warnings.empty());

  auto f0 = ds->Load(0);
  ASSERT_TRUE(f0.ok()) << f0.status().message();
  ASSERT_TRUE(f0->T_W_C.has_value());
  EXPECT_NEAR(f0->T_W_C->matrix()(0, 0), 0.9093129, 1e-7);
  EXPECT_NEAR(f0->T_W_C->matrix()(0, 3), -0.34045634, 1e-7);
  EXPECT_NEAR(f0->T_W_C->matrix()(2, 3), 0.29656917, 1e-7);
  const float median = MedianDepth(f0->depth);
  EXPECT_GT(median, 0.3f);
  EXPECT_LT(median, 5.f);
  EXPECT_EQ(f0->color.height, 480);

  auto f30 = ds->Load(30);
  ASSERT_TRUE(f30.ok()) << f30.status().message();
  EXPECT_NEAR(f30->timestamp, 1.0, 1e-12);  // 30 Hz by construction
}

TEST(Datasets, RedwoodOpen3d) {
  auto ds = OpenOk(Rgbd() / "open3d_livingroom5");
  ASSERT_TRUE(ds);
  const DatasetInfo& info = ds->info();
  EXPECT_EQ(info.format, DatasetFormat::kRedwood);
  EXPECT_EQ(info.num_frames, 5u);
  EXPECT_FLOAT_EQ(info.camera.fx, 525.f);
  EXPECT_FLOAT_EQ(info.camera.fy, 525.f);
  EXPECT_FLOAT_EQ(info.camera.cx, 319.5f);
  EXPECT_FLOAT_EQ(info.camera.cy, 239.5f);
  EXPECT_EQ(info.depth_scale, 1000.0);
  EXPECT_TRUE(Contains(info.intrinsics_source, "camera_primesense.json"));
  EXPECT_TRUE(Contains(info.pose_source, "trajectory.log"));
  EXPECT_TRUE(info.has_color);

  auto f0 = ds->Load(0);
  ASSERT_TRUE(f0.ok()) << f0.status().message();
  ASSERT_TRUE(f0->T_W_C.has_value());
  EXPECT_NEAR(f0->T_W_C->matrix()(0, 0), -0.2739592186924325, 1e-12);
  EXPECT_NEAR(f0->T_W_C->matrix()(0, 3), -0.31057997014702826, 1e-12);
  EXPECT_NEAR(f0->T_W_C->matrix()(2, 3), 2.1264800183565487, 1e-12);
  const float median = MedianDepth(f0->depth);
  EXPECT_GT(median, 0.5f);
  EXPECT_LT(median, 6.f);
  auto f4 = ds->Load(4);
  ASSERT_TRUE(f4.ok()) << f4.status().message();
  EXPECT_NEAR(f4->T_W_C->matrix()(0, 3), -0.3075481222199825, 1e-12);
  EXPECT_TRUE(Contains(f4->depth_path, "00004.png"));
}

TEST(Datasets, ThreeDMatch) {
  auto ds = OpenOk(Rgbd() / "3dmatch_sun3d5");
  ASSERT_TRUE(ds);
  const DatasetInfo& info = ds->info();
  EXPECT_EQ(info.format, DatasetFormat::kThreeDMatch);
  EXPECT_EQ(info.num_frames, 5u);
  EXPECT_NEAR(info.camera.fx, 570.342205, 1e-4);
  EXPECT_NEAR(info.camera.fy, 570.342205, 1e-4);
  EXPECT_FLOAT_EQ(info.camera.cx, 320.f);
  EXPECT_FLOAT_EQ(info.camera.cy, 240.f);
  EXPECT_EQ(info.depth_scale, 1000.0);

  auto f3 = ds->Load(3);  // frame-000116: ids are not contiguous
  ASSERT_TRUE(f3.ok()) << f3.status().message();
  EXPECT_TRUE(Contains(f3->depth_path, "frame-000116.depth.png"));
  EXPECT_NEAR(f3->timestamp, 116.0 / 30.0, 1e-12);
  ASSERT_TRUE(f3->T_W_C.has_value());
  EXPECT_NEAR(f3->T_W_C->matrix()(0, 3), 1.779847, 1e-9);
  EXPECT_NEAR(f3->T_W_C->matrix()(1, 1), -0.949137, 1e-9);
  const float median = MedianDepth(f3->depth);
  EXPECT_GT(median, 0.3f);
  EXPECT_LT(median, 6.f);

  // Pointing at the sequence folder finds camera-intrinsics.txt beside it.
  auto seq = OpenOk(Rgbd() / "3dmatch_sun3d5/seq-01");
  ASSERT_TRUE(seq);
  EXPECT_EQ(seq->info().num_frames, 5u);
  EXPECT_NEAR(seq->info().camera.fx, 570.342205, 1e-4);
}

TEST(Datasets, ReplicaNiceSlam) {
  auto ds = OpenOk(Rgbd() / "replica_office0");
  ASSERT_TRUE(ds);
  const DatasetInfo& info = ds->info();
  EXPECT_EQ(info.format, DatasetFormat::kReplica);
  EXPECT_EQ(info.num_frames, 4u);  // 2000 poses, 4 frames with images
  EXPECT_EQ(info.camera.width, 1200);
  EXPECT_EQ(info.camera.height, 680);
  EXPECT_FLOAT_EQ(info.camera.fx, 600.f);
  EXPECT_FLOAT_EQ(info.camera.cx, 599.5f);
  EXPECT_FLOAT_EQ(info.camera.cy, 339.5f);
  EXPECT_EQ(info.depth_scale, 6553.5);
  // The one warning: traj.txt holds the whole sequence's poses, matched by frame number.
  ASSERT_EQ(info.warnings.size(), 1u);
  EXPECT_TRUE(Contains(info.warnings[0], "traj.txt: 2000 poses for 4 frames; 1996 poses match no"))
      << info.warnings[0];

  auto f0 = ds->Load(0);
  ASSERT_TRUE(f0.ok()) << f0.status().message();
  ASSERT_TRUE(f0->T_W_C.has_value());
  EXPECT_NEAR(f0->T_W_C->matrix()(0, 0), 0.9062491181555123, 1e-12);
  EXPECT_NEAR(f0->T_W_C->matrix()(0, 3), -0.3569159214564542, 1e-12);
  EXPECT_NEAR(f0->T_W_C->matrix()(2, 3), 0.8192365926179191, 1e-12);
  EXPECT_EQ(f0->color.width, 1200);
  const float median = MedianDepth(f0->depth);
  EXPECT_GT(median, 0.5f);
  EXPECT_LT(median, 6.f);

  // The scene folder itself is accepted too.
  auto scene = OpenOk(Rgbd() / "replica_office0/office0");
  ASSERT_TRUE(scene);
  EXPECT_EQ(scene->info().num_frames, 4u);
}

TEST(Datasets, FormatNamesAndOverrides) {
  for (DatasetFormat f :
       {DatasetFormat::kAuto, DatasetFormat::kTum, DatasetFormat::kIclNuim, DatasetFormat::kRedwood,
        DatasetFormat::kSevenScenes, DatasetFormat::kThreeDMatch, DatasetFormat::kReplica}) {
    auto parsed = ParseDatasetFormat(DatasetFormatName(f));
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, f);
  }
  EXPECT_FALSE(ParseDatasetFormat("kitti").ok());

  DatasetOptions options;
  PinholeCamera k;
  k.fx = 500.f;
  k.fy = -500.f;
  k.cx = 300.f;
  k.cy = 200.f;
  options.intrinsics = k;
  options.depth_scale = 2000.0;
  auto ds = OpenOk(Rgbd() / "3dmatch_sun3d5", options);
  ASSERT_TRUE(ds);
  EXPECT_EQ(ds->info().camera.fx, 500.f);
  EXPECT_EQ(ds->info().camera.fy, -500.f);
  EXPECT_EQ(ds->info().camera.width, 640);  // size still from the images
  EXPECT_EQ(ds->info().intrinsics_source, "flag");
  EXPECT_EQ(ds->info().depth_scale, 2000.0);

  options = {};
  options.format = DatasetFormat::kTum;  // forced format on the wrong folder
  ExpectError(OpenDataset((Rgbd() / "3dmatch_sun3d5").string(), options).status(), {"depth.txt"});
  options = {};
  options.depth_scale = -1.0;
  ExpectError(OpenDataset((Rgbd() / "3dmatch_sun3d5").string(), options).status(), {"depth scale"});
}

// ------------------------------------------------------------------------------------------
// TUM on a hand-made folder where the association and interpolation are known.

const char kTumRgb[] =
    "\xEF\xBB\xBF# color images\r\n"  // BOM and CRLF must be accepted
    "# timestamp filename\r\n"
    "10.000 rgb/a.jpg\r\n"
    "10.033 rgb/b.jpg\r\n"
    "10.100 rgb/c.jpg\r\n"
    "10.140 rgb/d.jpg\r\n";
const char kTumDepth[] =
    "# depth maps\n"
    "# timestamp filename\n"
    "9.990 depth/a.png\n"     // 3: before the first pose -> dropped
    "10.010 depth/tum.png\n"  // 4: rgb a (0.010 s), pose halfway between 10.000 and 10.020
    "10.040 depth/b.png\n"    // 5: rgb b (0.007 s), pose a quarter from 10.020 to 10.100
    "10.070 depth/c.png\n"    // 6: nearest rgb 0.030 s away -> dropped
    "10.135 depth/d.png\n";   // 7: after the last pose -> dropped
const char kTumGt[] =
    "# ground truth trajectory\n"
    "# timestamp tx ty tz qx qy qz qw\n"
    "10.000 0 0 0 0 0 0 1\n"
    "10.020 1 2 3 0 0 0.70710678118654752 0.70710678118654752\n"
    "10.100 5 2 3 0 0 0.70710678118654752 0.70710678118654752\n";

void MakeTumFolder(const fs::path& root, const std::string& rgb = kTumRgb,
                   const std::string& depth = kTumDepth, const std::string& gt = kTumGt) {
  const fs::path icl = Rgbd() / "iclnuim_office_traj0";
  Copy(Rgbd() / "open3d_livingroom5/other_formats/TUM_depth.png", root / "depth/tum.png");
  Copy(icl / "depth/1.png", root / "depth/a.png");
  Copy(icl / "depth/100.png", root / "depth/b.png");
  Copy(icl / "depth/150.png", root / "depth/c.png");
  Copy(icl / "depth/200.png", root / "depth/d.png");
  Copy(icl / "rgb/1.jpg", root / "rgb/a.jpg");
  Copy(icl / "rgb/100.jpg", root / "rgb/b.jpg");
  Copy(icl / "rgb/150.jpg", root / "rgb/c.jpg");
  Copy(icl / "rgb/200.jpg", root / "rgb/d.jpg");
  WriteText(root / "rgb.txt", rgb);
  WriteText(root / "depth.txt", depth);
  if (!gt.empty()) WriteText(root / "groundtruth.txt", gt);
}

TEST(Datasets, TumAssociationAndInterpolation) {
  test::TempDir dir("tum");
  MakeTumFolder(dir.path());
  auto ds = OpenOk(dir.path());
  ASSERT_TRUE(ds);
  const DatasetInfo& info = ds->info();
  EXPECT_EQ(info.format, DatasetFormat::kTum);
  ASSERT_EQ(info.num_frames, 2u);
  EXPECT_FLOAT_EQ(info.camera.fx, 517.3f);
  EXPECT_FLOAT_EQ(info.camera.fy, 516.5f);
  EXPECT_FLOAT_EQ(info.camera.cx, 318.6f);
  EXPECT_FLOAT_EQ(info.camera.cy, 255.3f);
  EXPECT_EQ(info.depth_scale, 5000.0);
  EXPECT_TRUE(Contains(info.intrinsics_source, "default"));
  EXPECT_TRUE(AnyWarning(info, "Freiburg 1"));
  EXPECT_TRUE(AnyWarning(info, "depth.txt:3:"));  // no bracketing pose
  EXPECT_TRUE(AnyWarning(info, "depth.txt:6:"));  // no rgb within 0.02 s
  EXPECT_TRUE(AnyWarning(info, "depth.txt:7:"));  // no bracketing pose
  EXPECT_EQ(info.warnings.size(), 4u);

  auto f0 = ds->Load(0);
  ASSERT_TRUE(f0.ok()) << f0.status().message();
  EXPECT_DOUBLE_EQ(f0->timestamp, 10.010);
  EXPECT_TRUE(Contains(f0->depth_path, "tum.png"));
  ASSERT_TRUE(f0->T_W_C.has_value());
  EXPECT_TRUE(f0->T_W_C->translation().isApprox(Eigen::Vector3d(0.5, 1.0, 1.5), 1e-9));
  const Eigen::Matrix3d r45 = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).matrix();
  EXPECT_TRUE(f0->T_W_C->linear().isApprox(r45, 1e-9)) << f0->T_W_C->linear();
  auto rgb_a = ReadColorImage((dir / "rgb/a.jpg").string());
  ASSERT_TRUE(rgb_a.ok());
  EXPECT_EQ(f0->color.data, rgb_a->data);
  const float median = MedianDepth(f0->depth);  // a real TUM frame at scale 5000
  EXPECT_GT(median, 0.4f);
  EXPECT_LT(median, 6.f);

  auto f1 = ds->Load(1);
  ASSERT_TRUE(f1.ok()) << f1.status().message();
  EXPECT_TRUE(f1->T_W_C->translation().isApprox(Eigen::Vector3d(2.0, 2.0, 3.0), 1e-9));
  const Eigen::Matrix3d r90 = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).matrix();
  EXPECT_TRUE(f1->T_W_C->linear().isApprox(r90, 1e-9));
  auto rgb_b = ReadColorImage((dir / "rgb/b.jpg").string());
  ASSERT_TRUE(rgb_b.ok());
  EXPECT_EQ(f1->color.data, rgb_b->data);

  // An explicit camera silences the default-intrinsics warning.
  DatasetOptions options;
  options.intrinsics = PinholeCamera{0, 0, 535.4f, 539.2f, 320.1f, 247.6f};
  auto fr3 = OpenOk(dir.path(), options);
  ASSERT_TRUE(fr3);
  EXPECT_EQ(fr3->info().camera.fx, 535.4f);
  EXPECT_FALSE(AnyWarning(fr3->info(), "Freiburg 1"));
}

// camera.txt beside the lists ("fx fy cx cy", as `voxplan sim render` writes it) replaces the
// Freiburg 1 default; a malformed one is refused naming the file.
TEST(Datasets, TumCameraTxtGivesIntrinsics) {
  test::TempDir dir("tum");
  MakeTumFolder(dir.path());
  WriteText(dir / "camera.txt", "# fx fy cx cy\n554.25 -554.25 319.5 239.5\n");
  auto ds = OpenOk(dir.path());
  ASSERT_TRUE(ds);
  const DatasetInfo& info = ds->info();
  EXPECT_EQ(info.camera.fx, 554.25f);
  EXPECT_EQ(info.camera.fy, -554.25f);
  EXPECT_EQ(info.camera.cx, 319.5f);
  EXPECT_EQ(info.camera.cy, 239.5f);
  EXPECT_TRUE(Contains(info.intrinsics_source, "camera.txt"));
  EXPECT_FALSE(AnyWarning(info, "Freiburg 1"));
  // The flag still wins over the file.
  DatasetOptions options;
  options.intrinsics = PinholeCamera{0, 0, 535.4f, 539.2f, 320.1f, 247.6f};
  auto flagged = OpenOk(dir.path(), options);
  ASSERT_TRUE(flagged);
  EXPECT_EQ(flagged->info().camera.fx, 535.4f);

  for (const char* bad : {"554.25 554.25 319.5\n", "554.25 0 319.5 239.5\n",
                          "554.25 554.25 nan 239.5\n", "1 1 1 1\n2 2 2 2\n"}) {
    WriteText(dir / "camera.txt", bad);
    auto refused = OpenDataset(dir.path().string());
    ASSERT_FALSE(refused.ok()) << bad;
    EXPECT_TRUE(Contains(refused.status().message(), "camera.txt")) << refused.status().message();
  }
}

TEST(Datasets, TumNearUnitQuaternionIsRenormalisedWithWarning) {
  test::TempDir dir("tum");
  std::string gt = kTumGt;
  gt.replace(gt.find("10.000 0 0 0 0 0 0 1"), 20, "10.000 0 0 0 0 0 0 1.004");
  MakeTumFolder(dir.path(), kTumRgb, kTumDepth, gt);
  auto ds = OpenOk(dir.path());
  ASSERT_TRUE(ds);
  EXPECT_TRUE(AnyWarning(ds->info(), "groundtruth.txt:3:"));
  EXPECT_TRUE(AnyWarning(ds->info(), "renormalised"));
}

// ------------------------------------------------------------------------------------------
// Bad input: each a clear error naming the file (and line).

struct BadTum {
  const char* name;
  const char* file;  // which list gets `text`
  std::string text;
  std::string expect;  // substring of the message besides the file name
};

TEST(DatasetsBadInput, TumListsAndPoses) {
  const std::string ok_depth = kTumDepth;
  const std::vector<BadTum> cases = {
      {"garbage timestamp", "depth.txt", ok_depth + "abc depth/a.png\n", "depth.txt:8:"},
      {"extra field", "depth.txt", ok_depth + "10.2 depth/a.png extra\n", "depth.txt:8:"},
      {"binary junk", "depth.txt", ok_depth + std::string("\x01\x02\x7f junk\n", 9),
       "depth.txt:8:"},
      {"nan timestamp", "depth.txt", "nan depth/a.png\n", "depth.txt:1:"},
      {"negative timestamp", "depth.txt", "-1.0 depth/a.png\n", "depth.txt:1:"},
      {"duplicate timestamp", "depth.txt", "10.010 depth/tum.png\n10.010 depth/b.png\n",
       "depth.txt:2:"},
      {"out of order", "rgb.txt", "10.000 rgb/a.jpg\n10.100 rgb/c.jpg\n10.033 rgb/b.jpg\n",
       "rgb.txt:3:"},
      {"nan pose", "groundtruth.txt", "10.000 nan 0 0 0 0 0 1\n10.1 0 0 0 0 0 0 1\n",
       "groundtruth.txt:1:"},
      {"inf pose", "groundtruth.txt", "10.000 0 0 0 0 0 0 1\n10.1 0 inf 0 0 0 0 1\n",
       "groundtruth.txt:2:"},
      {"non-unit quaternion", "groundtruth.txt", "10.000 0 0 0 0 0 0 2\n", "groundtruth.txt:1:"},
      {"short pose line", "groundtruth.txt", "10.000 0 0 0 0 0 1\n", "groundtruth.txt:1:"},
      {"empty depth list", "depth.txt", "# nothing\n", "depth.txt"},
      {"missing image", "depth.txt", "10.010 depth/tum.png\n10.040 depth/missing.png\n",
       "missing.png"},
      {"no frame associates", "rgb.txt", "20.0 rgb/a.jpg\n", "no frame associates"},
  };
  for (const BadTum& c : cases) {
    SCOPED_TRACE(c.name);
    test::TempDir dir("tum_bad");
    MakeTumFolder(dir.path());
    WriteText(dir / c.file, c.text);
    auto ds = OpenDataset(dir.path().string());
    ExpectError(ds.status(), {c.file, c.expect});
  }
  {
    SCOPED_TRACE("missing depth.txt");
    test::TempDir dir("tum_bad");
    MakeTumFolder(dir.path());
    fs::remove(dir / "depth.txt");
    ExpectError(OpenDataset(dir.path().string()).status(), {"depth.txt", "no such file"});
  }
  {
    SCOPED_TRACE("missing folder");
    const std::string nowhere = (test::SharedDataDir() / "rgbd/no_such_sequence").string();
    auto ds = OpenDataset(nowhere);
    ExpectError(ds.status(), {nowhere});
    EXPECT_EQ(ds.status().code(), StatusCode::kNotFound);
  }
  {
    SCOPED_TRACE("unknown layout");
    test::TempDir dir("tum_bad");
    WriteText(dir / "readme.txt", "hello\n");
    ExpectError(OpenDataset(dir.path().string()).status(), {dir.path().string(), "format"});
  }
}

// Builds a TUM folder whose frame `bad.png` (the second kept frame) is replaced by `bytes`.
TEST(DatasetsBadInput, BadImagesFailAtLoadNamingTheFile) {
  const std::string depth_txt = "10.010 depth/tum.png\n10.040 depth/bad.png\n";
  const std::string png_bytes = [] {
    std::ifstream in(Rgbd() / "iclnuim_office_traj0/depth/100.png", std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }();
  struct Case {
    const char* name;
    std::function<void(const fs::path&)> make;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {"truncated",
       [&](const fs::path& p) { WriteText(p, png_bytes.substr(0, png_bytes.size() / 2)); },
       "truncated"},
      {"corrupt", [&](const fs::path& p) { WriteText(p, "not a png"); }, "PNG"},
      {"8-bit",
       [&](const fs::path& p) {
         std::vector<uint8_t> px(640 * 480, 10);
         ASSERT_TRUE(WritePngRaw(p.string(), 640, 480, 1, 8, px.data()).ok());
       },
       "8-bit"},
      {"3-channel",
       [&](const fs::path& p) {
         std::vector<uint16_t> px(640 * 480 * 3, 1000);
         ASSERT_TRUE(WritePngRaw(p.string(), 640, 480, 3, 16, px.data()).ok());
       },
       "RGB"},
      {"wrong size",
       [&](const fs::path& p) {
         ASSERT_TRUE(WriteDepthPng16(p.string(), DepthImage(320, 240, 1.f), 5000).ok());
       },
       "320x240"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    test::TempDir dir("tum_img");
    MakeTumFolder(dir.path(), kTumRgb, depth_txt);
    c.make(dir / "depth/bad.png");
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    ASSERT_EQ(ds->info().num_frames, 2u);
    EXPECT_TRUE(ds->Load(0).ok());
    auto frame = ds->Load(1);
    ExpectError(frame.status(), {(dir / "depth/bad.png").string(), c.expect});
  }
  {
    SCOPED_TRACE("8-bit first depth fails at open");
    test::TempDir dir("tum_img");
    MakeTumFolder(dir.path(), kTumRgb, "10.040 depth/bad.png\n");
    std::vector<uint8_t> px(64 * 48, 10);
    ASSERT_TRUE(WritePngRaw((dir / "depth/bad.png").string(), 64, 48, 1, 8, px.data()).ok());
    ExpectError(OpenDataset(dir.path().string()).status(), {"bad.png", "16-bit"});
  }
  {
    SCOPED_TRACE("colour size differs from depth");
    test::TempDir dir("tum_img");
    MakeTumFolder(dir.path(), kTumRgb, depth_txt);
    fs::copy_file(dir / "depth/b.png", dir / "depth/bad.png");
    ASSERT_TRUE(WriteColorPng((dir / "rgb/b.jpg").string(), ColorImage(320, 240))
                    .ok());  // PNG bytes, sniffed
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    ExpectError(ds->Load(1).status(), {(dir / "rgb/b.jpg").string(), "320x240"});
  }
  {
    SCOPED_TRACE("all-zero depth is not an error");
    test::TempDir dir("tum_img");
    MakeTumFolder(dir.path(), kTumRgb, depth_txt);
    ASSERT_TRUE(
        WriteDepthPng16((dir / "depth/bad.png").string(), DepthImage(640, 480, 0.f), 5000).ok());
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    auto frame = ds->Load(1);
    ASSERT_TRUE(frame.ok()) << frame.status().message();
    EXPECT_EQ(MedianDepth(frame->depth), 0.f);
  }
}

TEST(DatasetsBadInput, IclNuim) {
  const fs::path icl = Rgbd() / "iclnuim_office_traj0";
  auto make = [&](const fs::path& root, const std::string& assoc, const std::string& gt) {
    for (int id : {1, 2, 3}) {
      Copy(icl / ("depth/" + std::to_string(id) + ".png"),
           root / ("depth/" + std::to_string(id) + ".png"));
      Copy(icl / ("rgb/" + std::to_string(id) + ".jpg"),
           root / ("rgb/" + std::to_string(id) + ".jpg"));
    }
    WriteText(root / "associations.txt", assoc);
    WriteText(root / "traj0.gt.freiburg", gt);
  };
  const std::string assoc =
      "1 depth/1.png 1 rgb/1.jpg\r\n2 depth/2.png 2 rgb/2.jpg\r\n3 depth/3.png 3 rgb/3.jpg\r\n";
  const std::string gt = "2 0 0 -2.5 0 0 0 1\n3 0 0 -2.5 0 0 0 1\n";
  {
    test::TempDir dir("icl");
    make(dir.path(), assoc, gt);
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    EXPECT_EQ(ds->info().num_frames, 3u);
  }
  {
    test::TempDir dir("icl");
    make(dir.path(), assoc, "2 0 0 -2.5 0 0 0 1\n3 0 0 -2.5 0 0 0 1 9\n");
    ExpectError(OpenDataset(dir.path().string()).status(), {"traj0.gt.freiburg:2:"});
  }
  {
    test::TempDir dir("icl");
    make(dir.path(), "1 depth/1.png 1 rgb/1.jpg\n2 depth/2.png\n", gt);
    ExpectError(OpenDataset(dir.path().string()).status(), {"associations.txt:2:"});
  }
  {
    test::TempDir dir("icl");
    make(dir.path(), assoc, gt);
    fs::remove(dir / "rgb/3.jpg");
    ExpectError(OpenDataset(dir.path().string()).status(), {"rgb/3.jpg", "associations.txt:3"});
  }
  {
    SCOPED_TRACE("no ground truth: frames kept without poses");
    test::TempDir dir("icl");
    make(dir.path(), assoc, gt);
    fs::remove(dir / "traj0.gt.freiburg");
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    EXPECT_EQ(ds->info().format, DatasetFormat::kIclNuim);
    EXPECT_EQ(ds->info().pose_source, "none");
    EXPECT_TRUE(AnyWarning(ds->info(), "gt.freiburg"));
    auto f = ds->Load(2);
    ASSERT_TRUE(f.ok());
    EXPECT_FALSE(f->T_W_C.has_value());
  }
}

TEST(DatasetsBadInput, FrameFolders) {
  const fs::path src = Rgbd() / "7scenes_redkitchen";
  auto make = [&](const fs::path& root) {
    for (const char* f :
         {"camera-intrinsics.txt", "frame-000000.depth.png", "frame-000000.color.jpg",
          "frame-000000.pose.txt", "frame-000001.depth.png", "frame-000001.color.jpg",
          "frame-000001.pose.txt"})
      Copy(src / f, root / f);
  };
  {
    test::TempDir dir("7s");
    make(dir.path());
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    EXPECT_EQ(ds->info().num_frames, 2u);
  }
  {
    SCOPED_TRACE("non-orthonormal rotation: the frame has no pose, named in a warning");
    test::TempDir dir("7s");
    make(dir.path());
    WriteText(dir / "frame-000001.pose.txt", "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    EXPECT_TRUE(
        AnyWarning(ds->info(), "frame-000001.pose.txt:1: pose rotation is not orthonormal"));
    auto f1 = ds->Load(1);
    ASSERT_TRUE(f1.ok());
    EXPECT_FALSE(f1->T_W_C.has_value());
  }
  {
    SCOPED_TRACE("inf pose: likewise");
    test::TempDir dir("7s");
    make(dir.path());
    WriteText(dir / "frame-000000.pose.txt", "1 0 0 0\n0 1 0 -inf\n0 0 1 0\n0 0 0 1\n");
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    EXPECT_TRUE(AnyWarning(ds->info(), "frame-000000.pose.txt:1:"));
  }
  {
    SCOPED_TRACE("garbage intrinsics");
    test::TempDir dir("7s");
    make(dir.path());
    WriteText(dir / "camera-intrinsics.txt", "585 0 320\n0 x 240\n0 0 1\n");
    ExpectError(OpenDataset(dir.path().string()).status(), {"camera-intrinsics.txt:2:"});
  }
  {
    SCOPED_TRACE("missing pose is a warning");
    test::TempDir dir("7s");
    make(dir.path());
    fs::remove(dir / "frame-000001.pose.txt");
    auto ds = OpenOk(dir.path());
    ASSERT_TRUE(ds);
    EXPECT_TRUE(AnyWarning(ds->info(), "frame-000001.pose.txt"));
    auto f1 = ds->Load(1);
    ASSERT_TRUE(f1.ok());
    EXPECT_FALSE(f1->T_W_C.has_value());
  }
}

TEST(DatasetsBadInput, RedwoodAndReplica) {
  const fs::path o3d = Rgbd() / "open3d_livingroom5";
  auto make_redwood = [&](const fs::path& root) {
    for (const char* f : {"camera_primesense.json", "rgbd.match", "trajectory.log"})
      Copy(o3d / f, root / f);
    for (int i = 0; i < 5; ++i) {
      const std::string n = "0000" + std::to_string(i);
      Copy(o3d / ("depth/" + n + ".png"), root / ("depth/" + n + ".png"));
      Copy(o3d / ("color/" + n + ".jpg"), root / ("color/" + n + ".jpg"));
    }
  };
  {
    SCOPED_TRACE("stated size differs from the images");
    test::TempDir dir("redwood");
    make_redwood(dir.path());
    WriteText(dir / "camera_primesense.json",
              "{\"width\": 320, \"height\": 240, \"intrinsic_matrix\": [525, 0, 0, 0, 525, 0, "
              "159.5, 119.5, 1]}");
    ExpectError(OpenDataset(dir.path().string()).status(), {"camera_primesense.json", "320x240"});
  }
  {
    // Found by fuzz_dataset: int(1e30) was undefined behaviour (UBSan float-cast-overflow).
    SCOPED_TRACE("stated size beyond int");
    test::TempDir dir("redwood");
    make_redwood(dir.path());
    WriteText(dir / "camera_primesense.json",
              "{\"width\": 1e30, \"height\": 480, \"intrinsic_matrix\": [525, 0, 0, 0, 525, 0, "
              "319.5, 239.5, 1]}");
    ExpectError(OpenDataset(dir.path().string()).status(),
                {"camera_primesense.json", "width", "whole number"});
  }
  {
    // Found by fuzz_dataset: a number past double's range threw out of the reader (terminate).
    SCOPED_TRACE("json number overflow");
    test::TempDir dir("redwood");
    make_redwood(dir.path());
    WriteText(dir / "camera_primesense.json",
              "{\"width\": 1e309, \"height\": 480, \"intrinsic_matrix\": [525, 0, 0, 0, 525, 0, "
              "319.5, 239.5, 1]}");
    ExpectError(OpenDataset(dir.path().string()).status(),
                {"camera_primesense.json", "invalid JSON", "1e309"});
  }
  {
    SCOPED_TRACE("malformed json");
    test::TempDir dir("redwood");
    make_redwood(dir.path());
    WriteText(dir / "camera_primesense.json",
              "{\n\"width\": 640,\n\"intrinsic_matrix\": [525, 0,,]\n}");
    ExpectError(OpenDataset(dir.path().string()).status(), {"camera_primesense.json:3:"});
  }
  {
    SCOPED_TRACE("bad trajectory.log");
    test::TempDir dir("redwood");
    make_redwood(dir.path());
    WriteText(dir / "trajectory.log",
              "0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n1 1 2\n1 0 0 0\n0 1 0 oops\n");
    ExpectError(OpenDataset(dir.path().string()).status(), {"trajectory.log:8:"});
  }

  const fs::path rep = Rgbd() / "replica_office0";
  auto make_replica = [&](const fs::path& root) {
    Copy(rep / "cam_params.json", root / "cam_params.json");
    Copy(rep / "office0/results/depth000000.png", root / "office0/results/depth000000.png");
    Copy(rep / "office0/results/frame000000.jpg", root / "office0/results/frame000000.jpg");
  };
  {
    SCOPED_TRACE("bad traj.txt line");
    test::TempDir dir("replica");
    make_replica(dir.path());
    WriteText(dir / "office0/traj.txt",
              "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n1 0 0 0 0 1 0 0 0 0 1 0 0 0 0\n");
    ExpectError(OpenDataset(dir.path().string()).status(), {"traj.txt:2:"});
  }
  {
    SCOPED_TRACE("size differs from cam_params.json");
    test::TempDir dir("replica");
    make_replica(dir.path());
    WriteText(dir / "office0/traj.txt", "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n");
    WriteText(dir / "cam_params.json",
              "{\"camera\": {\"w\": 640, \"h\": 480, \"fx\": 600.0, \"fy\": 600.0, \"cx\": 599.5, "
              "\"cy\": 339.5, \"scale\": 6553.5}}");
    ExpectError(OpenDataset(dir.path().string()).status(), {"cam_params.json", "640x480"});
  }
  {
    // Found by fuzz_dataset: int(4e20) was undefined behaviour (UBSan float-cast-overflow).
    SCOPED_TRACE("stated size beyond int");
    test::TempDir dir("replica");
    make_replica(dir.path());
    WriteText(dir / "office0/traj.txt", "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n");
    WriteText(dir / "cam_params.json",
              "{\"camera\": {\"w\": 4e20, \"h\": 680, \"fx\": 600.0, \"fy\": 600.0, \"cx\": 599.5, "
              "\"cy\": 339.5, \"scale\": 6553.5}}");
    ExpectError(OpenDataset(dir.path().string()).status(),
                {"cam_params.json", "w ", "whole number"});
  }
}

}  // namespace
}  // namespace voxplan
