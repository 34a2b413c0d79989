// ROS bags: the hand-written message parsers (round trips, cut-short and lying lengths refused),
// --topics parsing, ROS 1 bags written by rosbag's own writer read back (topics found by type or
// named, TF and PoseStamped poses, TUM-style association, colour registered to depth), bad bags
// refused with the reason, and ROS 2 bags refused saying how to convert them.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/dataset.h"
#include "io/ros_messages.h"
#include "tests/io/bag_fixture.h"
#include "tests/io/dataset_checks.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

void WriteText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

bool Contains(const std::string& s, const std::string& what) {
  return s.find(what) != std::string::npos;
}

void ExpectError(const Status& s, std::initializer_list<std::string> what) {
  ASSERT_FALSE(s.ok()) << "expected an error";
  for (const std::string& w : what) EXPECT_TRUE(Contains(s.message(), w)) << s.message();
}

std::unique_ptr<Dataset> OpenOk(const fs::path& path, const DatasetOptions& options = {}) {
  auto ds = OpenDataset(path.string(), options);
  EXPECT_TRUE(ds.ok()) << ds.status().message();
  return ds.ok() ? std::move(ds).value() : nullptr;
}

TEST(RosMessages, RoundTripsAndBoundedRefusals) {
  ros1::Image image;
  image.header = {7, 12.25, "cam"};
  image.width = 2, image.height = 1, image.encoding = "16UC1", image.step = 4;
  const std::string pixels = "abcd";
  image.data = pixels;
  const std::string bytes = ros1::SerializeImage(image);
  Result<ros1::Image> back = ros1::ParseImage(bytes);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->header.seq, 7u);
  EXPECT_DOUBLE_EQ(back->header.stamp_s, 12.25);
  EXPECT_EQ(back->header.frame_id, "cam");
  EXPECT_EQ(back->encoding, "16UC1");
  EXPECT_EQ(back->data, "abcd");
  ExpectError(ros1::ParseImage(bytes.substr(0, bytes.size() - 1)).status(), {"cut short", "data"});
  ExpectError(ros1::ParseImage(bytes + "x").status(), {"1 bytes left", "sensor_msgs/Image"});
  // A data length of 4 GiB in a message of a few bytes is refused, not allocated.
  std::string lying = bytes;
  for (size_t i = lying.size() - 8; i < lying.size() - 4; ++i) lying[i] = char(0xff);
  ExpectError(ros1::ParseImage(lying).status(), {"cut short", "4294967295"});

  ros1::CameraInfo info;
  info.width = 640, info.height = 480;
  for (int i = 0; i < 9; ++i) info.K[i] = i + 0.5;
  Result<ros1::CameraInfo> info_back = ros1::ParseCameraInfo(ros1::SerializeCameraInfo(info));
  ASSERT_TRUE(info_back.ok()) << info_back.status().message();
  EXPECT_EQ(info_back->width, 640u);
  EXPECT_DOUBLE_EQ(info_back->K[4], 4.5);

  std::vector<ros1::Transform> tf = {test::MakeTransform("a", "b", 1.5, {1, 2, 3})};
  tf[0].rotation = Eigen::Quaterniond(0, 1, 0, 0);
  Result<std::vector<ros1::Transform>> tf_back = ros1::ParseTfMessage(ros1::SerializeTfMessage(tf));
  ASSERT_TRUE(tf_back.ok()) << tf_back.status().message();
  ASSERT_EQ(tf_back->size(), 1u);
  EXPECT_EQ((*tf_back)[0].child_frame_id, "b");
  EXPECT_DOUBLE_EQ((*tf_back)[0].translation.y(), 2.0);
  EXPECT_DOUBLE_EQ((*tf_back)[0].rotation.x(), 1.0);
  // A transform count no message could hold is refused before anything is reserved.
  ExpectError(ros1::ParseTfMessage(std::string("\xff\xff\xff\x7f", 4)).status(), {"transforms"});

  ros1::PoseStamped pose;
  pose.position = {4, 5, 6};
  Result<ros1::PoseStamped> pose_back = ros1::ParsePoseStamped(ros1::SerializePoseStamped(pose));
  ASSERT_TRUE(pose_back.ok());
  EXPECT_DOUBLE_EQ(pose_back->position.z(), 6.0);
  EXPECT_DOUBLE_EQ(pose_back->orientation.w(), 1.0);
}

TEST(RosBag, TopicsOptionIsParsedAndChecked) {
  Result<RosBagTopics> t = ParseRosBagTopics("depth=/d,color=/c,info=/i,pose=/tf,frame=cam");
  ASSERT_TRUE(t.ok()) << t.status().message();
  EXPECT_EQ(t->depth, "/d");
  EXPECT_EQ(t->color, "/c");
  EXPECT_EQ(t->info, "/i");
  EXPECT_EQ(t->pose, "/tf");
  EXPECT_EQ(t->frame, "cam");
  EXPECT_TRUE(t->color_info.empty());
  ExpectError(ParseRosBagTopics("depth").status(), {"key=topic"});
  ExpectError(ParseRosBagTopics("dpeth=/d").status(), {"unknown key 'dpeth'"});
  ExpectError(ParseRosBagTopics("depth=/a,depth=/b").status(), {"twice"});
  ExpectError(ParseRosBagTopics("depth=/a,").status(), {"key=topic"});
}

TEST(RosBag, TfPosesFloatDepthAndRegisteredColour) {
  const test::TempDir dir("voxplan-bag-tf");
  const fs::path bag = dir / "run.bag";
  test::WriteBag(bag.string(), test::BagScene{});
  for (const fs::path& open : {bag, dir.path()}) {  // the file, or a folder holding it
    auto ds = OpenOk(open);
    ASSERT_TRUE(ds);
    const DatasetInfo& info = ds->info();
    EXPECT_EQ(info.format, DatasetFormat::kRosBag);
    EXPECT_EQ(info.num_frames, 6u);
    EXPECT_EQ(info.camera.width, 32);
    EXPECT_FLOAT_EQ(info.camera.fx, 24.f);
    EXPECT_DOUBLE_EQ(info.depth_scale, 1.0);  // 32FC1: metres
    EXPECT_TRUE(info.has_color);
    EXPECT_EQ(info.intrinsics_source, bag.string() + ": /camera/depth/camera_info");
    EXPECT_TRUE(Contains(info.pose_source, "/tf (frame depth_optical)")) << info.pose_source;
    EXPECT_TRUE(Contains(info.streams, "depth /camera/depth/image (32FC1)")) << info.streams;
    EXPECT_TRUE(Contains(info.streams, "colour /camera/rgb/image_color")) << info.streams;
    EXPECT_TRUE(Contains(info.streams, "colour info /camera/rgb/camera_info")) << info.streams;
    EXPECT_EQ(ds->InputFiles(), std::vector<std::string>{bag.string()});
  }
  auto ds = OpenOk(bag);
  ASSERT_TRUE(ds);
  for (size_t i : {size_t(0), size_t(4)}) {
    Result<Frame> f = ds->Load(i);
    ASSERT_TRUE(f.ok()) << f.status().message();
    EXPECT_NEAR(f->timestamp, test::FrameTime(int(i)), 1e-6);
    ASSERT_TRUE(f->T_W_C.has_value());
    // world -> camera_link (/tf, interpolated) -> depth_optical (/tf_static, 0.1 m ahead).
    EXPECT_NEAR(f->T_W_C->translation().x(), 0.05 * double(i), 1e-6);
    EXPECT_NEAR(f->T_W_C->translation().z(), 0.0, 1e-9);
    for (float d : f->depth.data) EXPECT_FLOAT_EQ(d, 2.0f);
    // bgr8 64x48 through its camera info into the 32x24 depth camera: u' = 2u + 0.5.
    ASSERT_EQ(f->color.width, 32);
    for (int u : {0, 15, 31})
      EXPECT_NEAR(Red(f->color.at(u, 12)), (2 * u + 0.5) * 255 / 63, 2) << u;
    EXPECT_TRUE(Contains(f->depth_path, "topic /camera/depth/image message " + std::to_string(i)));
  }
}

// A colour camera 5 cm to the right of the depth camera, known from /tf_static (its frame named
// with a leading '/', as ROS 1 bags often do): at 2 m a point moves 48 * 0.05 / 2 = 1.2 colour
// pixels to the left.
TEST(RosBag, ColourRegisteredThroughTf) {
  const test::TempDir dir("voxplan-bag-rgb-tf");
  const fs::path bag = dir / "run.bag";
  test::BagScene scene;
  scene.color_camera_x = 0.05;
  test::WriteBag(bag.string(), scene);
  auto ds = OpenOk(bag);
  ASSERT_TRUE(ds);
  Result<Frame> f = ds->Load(2);
  ASSERT_TRUE(f.ok()) << f.status().message();
  for (int u : {5, 15, 30})
    EXPECT_NEAR(Red(f->color.at(u, 12)), (2 * u + 0.5 - 1.2) * 255 / 63, 2) << u;
}

TEST(RosBag, PoseTopicMillimetreDepthAndJpegColour) {
  const test::TempDir dir("voxplan-bag-pose");
  const fs::path bag = dir / "run.bag";
  test::BagScene scene;
  scene.tf = false, scene.float_depth = false, scene.compressed = true, scene.color_info = false;
  test::WriteBag(bag.string(), scene);
  auto ds = OpenOk(bag);
  ASSERT_TRUE(ds);
  const DatasetInfo& info = ds->info();
  EXPECT_DOUBLE_EQ(info.depth_scale, 1000.0);
  EXPECT_EQ(info.pose_source, bag.string() + ": /camera/pose");
  EXPECT_TRUE(Contains(info.streams, "/camera/rgb/image_color/compressed")) << info.streams;
  // No colour camera info and another size: resized to depth, and said so.
  bool warned = false;
  for (const std::string& w : info.warnings) warned |= Contains(w, "colour is resized to depth");
  EXPECT_TRUE(warned);
  Result<Frame> f = ds->Load(3);
  ASSERT_TRUE(f.ok()) << f.status().message();
  ASSERT_TRUE(f->T_W_C.has_value());
  EXPECT_NEAR(f->T_W_C->translation().x(), 0.15, 1e-6);
  for (float d : f->depth.data) EXPECT_FLOAT_EQ(d, 2.0f);  // 2000 mm
  EXPECT_NEAR(Green(f->color.at(16, 23)), (2 * 23 + 0.5) * 255 / 47, 6);
}

TEST(RosBag, AssociationGapsAndDroppedFrames) {
  const test::TempDir dir("voxplan-bag-assoc");
  // Colour for every other frame only: the others have none within TUM's 0.02 s and are
  // dropped, counted; with the colour a second late, none associates.
  test::BagScene sparse;
  sparse.color_every = 2;
  test::WriteBag((dir / "sparse.bag").string(), sparse);
  auto sparse_ds = OpenOk(dir / "sparse.bag");
  ASSERT_TRUE(sparse_ds);
  EXPECT_EQ(sparse_ds->info().num_frames, 3u);
  bool warned = false;
  for (const std::string& w : sparse_ds->info().warnings)
    warned |= Contains(w, "3 depth frames of /camera/depth/image have no colour image");
  EXPECT_TRUE(warned);
  test::BagScene late;
  late.color_offset_s = 1.0;
  test::WriteBag((dir / "late.bag").string(), late);
  ExpectError(OpenDataset((dir / "late.bag").string()).status(),
              {"late.bag", "6 depth frames: 6 without colour within 0.02 s"});
  // Poses missing for 0.11 s: the frames inside are kept without a pose, as for TUM.
  test::BagScene gap;
  gap.pose_gap_after_s = test::FrameTime(1) + 0.001;
  test::WriteBag((dir / "gap.bag").string(), gap);
  auto ds = OpenOk(dir / "gap.bag");
  ASSERT_TRUE(ds);
  EXPECT_EQ(ds->info().num_frames, 6u);
  Result<Frame> in_gap = ds->Load(3);
  ASSERT_TRUE(in_gap.ok());
  EXPECT_FALSE(in_gap->T_W_C.has_value());
  EXPECT_EQ(in_gap->pose_rejected, PoseRejection::kGroundTruthGap);
  EXPECT_TRUE(ds->Load(5)->T_W_C.has_value());
  // No colour at all: frames without colour, warned.
  test::BagScene gray;
  gray.color = false;
  test::WriteBag((dir / "nocolor.bag").string(), gray);
  auto no_color = OpenOk(dir / "nocolor.bag");
  ASSERT_TRUE(no_color);
  EXPECT_FALSE(no_color->info().has_color);
}

TEST(RosBag, TopicsFoundByTypeOrNamed) {
  const test::TempDir dir("voxplan-bag-topics");
  test::BagScene odd;
  odd.depth_topic = "/sensor/range";  // no "depth" in the name: still found by its encoding
  test::WriteBag((dir / "odd.bag").string(), odd);
  auto ds = OpenOk(dir / "odd.bag");
  ASSERT_TRUE(ds);
  EXPECT_TRUE(Contains(ds->info().streams, "depth /sensor/range (32FC1)"));

  DatasetOptions named;
  named.topics.depth = "/camera/rgb/image_color";  // a colour topic named as depth
  ExpectError(OpenDataset((dir / "odd.bag").string(), named).status(),
              {"odd.bag", "depth encoding bgr8"});
  named.topics.depth = "/nope";
  ExpectError(OpenDataset((dir / "odd.bag").string(), named).status(),
              {"no topic /nope", "/sensor/range (sensor_msgs/Image)"});
  named.topics.depth = "/camera/depth/camera_info";
  ExpectError(OpenDataset((dir / "odd.bag").string(), named).status(),
              {"carries sensor_msgs/CameraInfo", "wants sensor_msgs/Image"});
  named.topics = {};
  named.topics.pose = "/tf";
  named.topics.frame = "no_such_frame";
  auto no_frame = OpenOk(dir / "odd.bag", named);
  ASSERT_TRUE(no_frame);
  EXPECT_EQ(no_frame->info().pose_source, "none");
  EXPECT_FALSE(no_frame->Load(0)->T_W_C.has_value());
}

// The layout librealsense records: per-sensor topics, mono16 depth in the units its "Depth
// Units" option states, no poses.
TEST(RosBag, RealSenseLayout) {
  const test::TempDir dir("voxplan-bag-realsense");
  const fs::path path = dir / "d435.bag";
  auto writer = RosBagWriter::Create(path.string()).value();
  const auto write = [&](const std::string& topic, double t, const ros1::MessageType& type,
                         const std::string& bytes) {
    ASSERT_TRUE(writer->Write(topic, t, type.name, type.md5sum, bytes).ok());
  };
  const std::string sensor0 = "/device_0/sensor_0/", sensor1 = "/device_0/sensor_1/";
  write(sensor0 + "option/Depth Units/value", 1.0, ros1::kFloat32, ros1::SerializeFloat32(1e-4f));
  ros1::CameraInfo info;
  info.width = 4, info.height = 2;
  const double k[9] = {4, 0, 1.5, 0, 4, 0.5, 0, 0, 1};
  std::copy(k, k + 9, info.K);
  write(sensor0 + "Depth_0/info/camera_info", 1.0, ros1::kCameraInfo,
        ros1::SerializeCameraInfo(info));
  write(sensor1 + "Color_0/info/camera_info", 1.0, ros1::kCameraInfo,
        ros1::SerializeCameraInfo(info));
  for (int i = 0; i < 3; ++i) {
    const double t = 1.0 + i / 30.0;
    ros1::Image depth;
    depth.header.stamp_s = t;
    depth.width = 4, depth.height = 2, depth.encoding = "mono16", depth.step = 8;
    std::string units;
    for (int p = 0; p < 8; ++p) units += std::string("\x20\x4e", 2);  // 20000 units: 2 m
    depth.data = units;
    write(sensor0 + "Depth_0/image/data", t, ros1::kImage, ros1::SerializeImage(depth));
    ros1::Image color = depth;
    color.encoding = "rgb8", color.step = 12;
    const std::string rgb(24, char(200));
    color.data = rgb;
    write(sensor1 + "Color_0/image/data", t, ros1::kImage, ros1::SerializeImage(color));
  }
  ASSERT_TRUE(writer->Close().ok());
  auto ds = OpenOk(path);
  ASSERT_TRUE(ds);
  const DatasetInfo& info_read = ds->info();
  EXPECT_DOUBLE_EQ(info_read.depth_scale, 1e4);
  EXPECT_EQ(info_read.num_frames, 3u);
  EXPECT_EQ(info_read.intrinsics_source,
            path.string() + ": " + sensor0 + "Depth_0/info/camera_info");
  EXPECT_TRUE(Contains(info_read.streams, "colour info " + sensor1 + "Color_0/info/camera_info"));
  EXPECT_EQ(info_read.pose_source, "none");
  Result<Frame> f = ds->Load(1);
  ASSERT_TRUE(f.ok()) << f.status().message();
  for (float d : f->depth.data) EXPECT_FLOAT_EQ(d, 2.0f);
  EXPECT_EQ(Red(f->color.at(2, 1)), 200);
  EXPECT_FALSE(f->T_W_C.has_value());
}

TEST(RosBag, BadBagsAreRefusedWithTheReason) {
  const test::TempDir dir("voxplan-bag-bad");
  WriteText(dir / "text.bag", "not a bag at all");
  ExpectError(OpenDataset((dir / "text.bag").string()).status(), {"text.bag", "not a ROS 1 bag"});
  test::WriteBag((dir / "good.bag").string(), test::BagScene{});
  const std::string bytes = test::ReadFileBytes(dir / "good.bag");
  WriteText(dir / "cut.bag", bytes.substr(0, bytes.size() / 2));
  ExpectError(OpenDataset((dir / "cut.bag").string()).status(), {"cut.bag"});
  // A bag with no depth images says which topics it has.
  auto writer = RosBagWriter::Create((dir / "tf_only.bag").string()).value();
  ASSERT_TRUE(writer
                  ->Write("/tf", 1.0, ros1::kTfMessage.name, ros1::kTfMessage.md5sum,
                          ros1::SerializeTfMessage(
                              {test::MakeTransform("w", "c", 1.0, Eigen::Vector3d::Zero())}))
                  .ok());
  ASSERT_TRUE(writer->Close().ok());
  ExpectError(OpenDataset((dir / "tf_only.bag").string()).status(),
              {"tf_only.bag", "no depth image topic", "/tf (tf2_msgs/TFMessage)"});
  // A depth message whose data is shorter than its rows opens (only stamps are read) and fails
  // on Load naming the topic and message.
  auto w2 = RosBagWriter::Create((dir / "short.bag").string()).value();
  ros1::Image img;
  img.header.stamp_s = 1.0;
  img.width = 4, img.height = 4, img.encoding = "16UC1", img.step = 8;
  const std::string few(8, '\0');
  img.data = few;
  ASSERT_TRUE(
      w2->Write("/depth", 1.0, ros1::kImage.name, ros1::kImage.md5sum, ros1::SerializeImage(img))
          .ok());
  ASSERT_TRUE(w2->Close().ok());
  DatasetOptions k;
  k.intrinsics = PinholeCamera{0, 0, 4, 4, 2, 2};
  auto ds = OpenOk(dir / "short.bag", k);
  ASSERT_TRUE(ds);
  ExpectError(ds->Load(0).status(), {"short.bag: topic /depth message 0", "8 bytes of data"});
}

// The top-level records of a bag (format 2.0): where each starts, its op, where its header and
// data lie. For the tests below, which corrupt one length or field.
struct BagRecord {
  size_t pos = 0, header_pos = 0, header_len = 0, data_pos = 0, data_len = 0;
  int op = -1;
};
uint32_t GetU32(const std::string& b, size_t at) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | uint8_t(b[at + size_t(i)]);
  return v;
}
void PutU32At(std::string& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + size_t(i)] = char((v >> (8 * i)) & 0xff);
}
std::vector<BagRecord> BagRecords(const std::string& b) {
  std::vector<BagRecord> out;
  for (size_t pos = 13; pos + 8 <= b.size();) {
    BagRecord r;
    r.pos = pos;
    r.header_pos = pos + 4;
    r.header_len = GetU32(b, pos);
    r.data_pos = r.header_pos + r.header_len + 4;
    r.data_len = GetU32(b, r.header_pos + r.header_len);
    const size_t op = b.find(std::string("op=", 3), r.header_pos);
    if (op < r.header_pos + r.header_len) r.op = uint8_t(b[op + 3]);
    out.push_back(r);
    pos = r.data_pos + r.data_len;
  }
  return out;
}
// Where the value of `name=` starts in the record's header.
size_t FieldValue(const std::string& b, const BagRecord& r, const std::string& name) {
  const size_t at = b.find(name + "=", r.header_pos);
  EXPECT_LT(at, r.header_pos + r.header_len) << name;
  return at + name.size() + 1;
}

// rosbag_storage trusts the file's lengths (a header length it allocates, an index entry's offset
// it reads at): io/rosbag_check.h refuses each corruption first, naming the file and the byte.
// The first case is what fuzz_rosbag found (rosbag allocating a 4 GiB header).
TEST(RosBag, CorruptStructureIsRefusedBeforeRosbagReadsIt) {
  const test::TempDir dir("voxplan-bag-structure");
  test::WriteBag((dir / "good.bag").string(), test::BagScene{});
  const std::string good = test::ReadFileBytes(dir / "good.bag");
  const std::vector<BagRecord> records = BagRecords(good);
  ASSERT_GT(records.size(), 4u);
  ASSERT_EQ(records[0].op, 3);
  const auto first = [&](int op) {
    for (const BagRecord& r : records)
      if (r.op == op) return r;
    ADD_FAILURE() << "no record with op " << op;
    return BagRecord{};
  };
  const auto refused = [&](const std::string& name, const std::string& bytes,
                           std::initializer_list<std::string> what) {
    WriteText(dir / name, bytes);
    const auto start = std::chrono::steady_clock::now();
    ExpectError(OpenDataset((dir / name).string()).status(), what);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  };
  std::string b = good;
  PutU32At(b, records[0].pos, 0xfffffff0u);
  refused("header_len.bag", b, {"header_len.bag", "record at byte 13", "runs past the end"});
  b = good;
  PutU32At(b, records[1].header_pos + records[1].header_len, 0x7fffffffu);
  refused("data_len.bag", b, {"data_len.bag", "data of 2147483647 bytes runs past the end"});
  b = good;
  PutU32At(b, records[1].header_pos, 0xffffu);  // the first field's length
  refused("field.bag", b, {"field.bag", "runs past the header's end"});
  const BagRecord index = first(4), chunk = first(5);
  b = good;
  PutU32At(b, index.data_pos + 8, 0xffffff00u);  // the first entry's offset in its chunk
  refused("offset.bag", b, {"offset.bag", "the message at offset 4294967040", "past the chunk"});
  b = good;
  PutU32At(b, index.data_pos + 8, 0);  // the chunk's first record: a connection, not a message
  refused("not_message.bag", b, {"not_message.bag", "not a message data record"});
  b = good;
  PutU32At(b, FieldValue(b, index, "conn"), 777);
  refused("conn.bag", b, {"conn.bag", "connection 777, which the bag does not declare"});
  b = good;
  PutU32At(b, FieldValue(b, chunk, "size"), uint32_t(chunk.data_len + 1));
  refused("size.bag", b, {"size.bag", "states size"});
  b = good;
  b.replace(FieldValue(b, chunk, "compression"), 4, "lz4x");
  refused("compression.bag", b, {"compression.bag", "compression 'lz4x'"});
  b = good;
  for (int i = 0; i < 8; ++i) b[FieldValue(b, records[0], "index_pos") + size_t(i)] = 0;
  refused("unindexed.bag", b, {"unindexed.bag", "unindexed", "rosbag reindex"});
  b = good;
  b[11] = '1';
  refused("v1.bag", b, {"v1.bag", "version '2.1'", "only 2.0"});
}

void ExpectRos2Refusal(const fs::path& path) {
  const Status s = OpenDataset(path.string()).status();
  ASSERT_FALSE(s.ok()) << path;
  EXPECT_EQ(s.code(), StatusCode::kUnsupported) << s.message();
  for (const char* what : {"ROS 2 bag", "rosbags-convert", ".bag"})
    EXPECT_NE(s.message().find(what), std::string::npos) << s.message();
  EXPECT_NE(s.message().find(path.string()), std::string::npos) << s.message();
}

TEST(RosBag, Ros2BagsAreRefusedWithHowToConvert) {
  const test::TempDir dir("voxplan-ros2");
  WriteText(dir / "rec" / "metadata.yaml", "rosbag2_bagfile_information:\n  version: 5\n");
  WriteText(dir / "rec" / "rec_0.db3", "SQLite format 3");
  WriteText(dir / "mcap" / "run.mcap", "\x89MCAP0\r\n");
  WriteText(dir / "meta_only" / "metadata.yaml", "rosbag2_bagfile_information:\n");
  ExpectRos2Refusal(dir / "rec");
  ExpectRos2Refusal(dir / "rec" / "rec_0.db3");
  ExpectRos2Refusal(dir / "mcap" / "run.mcap");
  ExpectRos2Refusal(dir / "mcap");
  ExpectRos2Refusal(dir / "meta_only");
  EXPECT_TRUE(IsDatasetFile("x.db3"));
  EXPECT_TRUE(IsDatasetFile("x.MCAP"));
  EXPECT_TRUE(IsDatasetFile("x.bag"));
}

// fuse decodes frames ahead on worker threads: loads from several threads at once give the
// frames one thread loads.
TEST(RosBag, LoadsFromSeveralThreadsMatchOneThread) {
  const test::TempDir dir("voxplan-bag-threads");
  const fs::path path = dir / "run.bag";
  test::BagScene scene;
  scene.frames = 8;
  test::WriteBag(path.string(), scene);
  auto ds = OpenDataset(path.string());
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  test::ExpectThreadedLoadsMatchOneThread(**ds);
}

}  // namespace
}  // namespace voxplan
