// ROS 1 bags (io/rosbag_file.h, messages parsed by io/ros_messages.h): the depth, colour and
// camera-info topics are found by their message types (or named with RosBagTopics), poses come
// from a PoseStamped topic or from TF, and colour and poses are associated with the depth
// timestamps as for TUM (nearest colour within 0.02 s; poses interpolated, never across a gap
// longer than max_pose_gap_s). Frames are decoded from the bag on Load.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/bounds.h"
#include "io/color_registration.h"
#include "io/dataset_internal.h"
#include "io/image_io.h"
#include "io/ros_messages.h"
#include "io/rosbag_file.h"
#include "io/text_file.h"
#include "io/tf_tree.h"

namespace voxplan {

Result<RosBagTopics> ParseRosBagTopics(const std::string& text) {
  RosBagTopics t;
  const std::pair<const char*, std::string*> keys[] = {
      {"depth", &t.depth},           {"color", &t.color}, {"info", &t.info},
      {"color_info", &t.color_info}, {"pose", &t.pose},   {"frame", &t.frame}};
  size_t at = 0;
  while (at <= text.size() && !text.empty()) {
    const size_t comma = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, comma - at);
    const size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == item.size())
      return InvalidArgument("--topics: '" + item +
                             "' is not key=topic (keys: depth, color, info, color_info, pose, "
                             "frame)");
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    auto it = std::find_if(std::begin(keys), std::end(keys),
                           [&](const auto& k) { return key == k.first; });
    if (it == std::end(keys))
      return InvalidArgument("--topics: unknown key '" + key +
                             "' (keys: depth, color, info, color_info, pose, frame)");
    if (!it->second->empty()) return InvalidArgument("--topics: '" + key + "' given twice");
    *it->second = value;
    at = comma + 1;
  }
  return t;
}

namespace dataset {
namespace {

bool IsDepthEncoding(const std::string& e) { return e == "16UC1" || e == "mono16" || e == "32FC1"; }
bool IsColorEncoding(const std::string& e) {
  return e == "rgb8" || e == "bgr8" || e == "rgba8" || e == "bgra8" || e == "mono8";
}
bool Contains(const std::string& s, const char* what) { return s.find(what) != std::string::npos; }

// How many leading '/'-separated names two topics share: a camera info belongs to the image
// topic it shares the most with (/camera/depth/image and /camera/depth/camera_info).
size_t SharedNames(const std::string& a, const std::string& b) {
  size_t shared = 0, i = 0;
  while (i < a.size() && i < b.size() && a[i] == b[i]) {
    if (a[i] == '/' && i > 0) ++shared;
    ++i;
  }
  return shared;
}

std::string TopicList(const std::vector<BagTopic>& topics) {
  std::string out;
  for (const BagTopic& t : topics)
    out += (out.empty() ? "" : ", ") + t.topic + " (" + t.datatype + ")";
  return out.empty() ? "none" : out;
}

const BagTopic* FindTopic(const std::vector<BagTopic>& topics, const std::string& name) {
  for (const BagTopic& t : topics)
    if (t.topic == name) return &t;
  return nullptr;
}

bool IsType(const BagTopic& t, const ros1::MessageType& type) {
  return t.datatype == type.name && t.md5sum == type.md5sum;
}

// A topic named in RosBagTopics: it must exist and carry one of the types.
Status CheckNamed(const RosBagFile& bag, const std::string& key, const std::string& name,
                  std::initializer_list<ros1::MessageType> types) {
  const BagTopic* t = FindTopic(bag.topics(), name);
  if (!t)
    return NotFound(bag.path() + ": no topic " + name + " (--topics " + key +
                    "); topics: " + TopicList(bag.topics()));
  for (const ros1::MessageType& type : types)
    if (IsType(*t, type)) return Status::Ok();
  std::string wanted;
  for (const ros1::MessageType& type : types)
    wanted += (wanted.empty() ? "" : " or ") + std::string(type.name);
  return Unsupported(bag.path() + ": topic " + name + " carries " + t->datatype + " (md5 " +
                     t->md5sum + "), --topics " + key + " wants " + wanted);
}

std::string MessageWhere(const RosBagFile& bag, const std::string& topic, size_t n) {
  return bag.path() + ": topic " + topic + " message " + std::to_string(n);
}

// The first message of an image topic (its encoding, size and frame).
Result<ros1::Image> FirstImage(RosBagFile& bag, const std::string& topic) {
  std::optional<ros1::Image> first;
  std::string keep;  // the parsed image points into the bytes
  VOXPLAN_RETURN_IF_ERROR(bag.ForEachMessage(
      topic,
      [&](size_t, double, const std::string& bytes) {
        keep = bytes;
        Result<ros1::Image> image = ros1::ParseImage(keep);
        if (!image.ok()) return image.status().WithContext(MessageWhere(bag, topic, 0));
        first = std::move(image).value();
        first->data = {};
        return Status::Ok();
      },
      1));
  if (!first) return CorruptData(bag.path() + ": topic " + topic + " has no messages");
  return *first;
}

// --- pixels ---

Status CheckImageLayout(const ros1::Image& m, uint32_t bytes_per_pixel, const std::string& where) {
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckImageSize(where + ": image", m.width, m.height));
  if (uint64_t(m.step) < uint64_t(m.width) * bytes_per_pixel)
    return CorruptData(where + ": step " + std::to_string(m.step) + " is shorter than a row of " +
                       std::to_string(m.width) + " " + m.encoding + " pixels");
  if (uint64_t(m.step) * m.height > m.data.size())
    return CorruptData(where + ": " + std::to_string(m.data.size()) + " bytes of data, " +
                       std::to_string(m.height) + " rows of " + std::to_string(m.step) + " need " +
                       std::to_string(uint64_t(m.step) * m.height));
  return Status::Ok();
}

// 16UC1 / mono16 in units of 1 / depth_scale metres, or 32FC1 in metres (then / depth_scale,
// 1 unless overridden); NaN, inf and values <= 0 are invalid (0).
Result<DepthImage> DepthFromImage(const ros1::Image& m, double depth_scale,
                                  const std::string& where) {
  const bool is_float = m.encoding == "32FC1";
  if (!IsDepthEncoding(m.encoding))
    return Unsupported(where + ": depth encoding " + m.encoding + " (read: 16UC1, mono16, 32FC1)");
  VOXPLAN_RETURN_IF_ERROR(CheckImageLayout(m, is_float ? 4 : 2, where));
  DepthImage depth(int(m.width), int(m.height));
  const double inv_scale = 1.0 / depth_scale;
  const auto* bytes = reinterpret_cast<const unsigned char*>(m.data.data());
  for (uint32_t v = 0; v < m.height; ++v) {
    const unsigned char* row = bytes + size_t(v) * m.step;
    float* out = depth.data.data() + size_t(v) * m.width;
    for (uint32_t u = 0; u < m.width; ++u) {
      if (is_float) {
        const unsigned char* p = row + 4 * size_t(u);
        const uint32_t bits = m.big_endian ? uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 |
                                                 uint32_t(p[2]) << 8 | uint32_t(p[3])
                                           : uint32_t(p[3]) << 24 | uint32_t(p[2]) << 16 |
                                                 uint32_t(p[1]) << 8 | uint32_t(p[0]);
        float d = 0.f;
        std::memcpy(&d, &bits, 4);
        out[u] = std::isfinite(d) && d > 0.f ? float(double(d) * inv_scale) : 0.f;
      } else {
        const unsigned char* p = row + 2 * size_t(u);
        const unsigned value =
            m.big_endian ? unsigned(p[0]) << 8 | p[1] : unsigned(p[1]) << 8 | p[0];
        out[u] = float(double(value) * inv_scale);
      }
    }
  }
  return depth;
}

Result<ColorImage> ColorFromImage(const ros1::Image& m, const std::string& where) {
  if (!IsColorEncoding(m.encoding))
    return Unsupported(where + ": colour encoding " + m.encoding +
                       " (read: rgb8, bgr8, rgba8, bgra8, mono8)");
  const uint32_t channels = m.encoding == "mono8" ? 1 : (m.encoding.size() == 5 ? 4 : 3);
  VOXPLAN_RETURN_IF_ERROR(CheckImageLayout(m, channels, where));
  const bool bgr = m.encoding[0] == 'b';
  ColorImage color(int(m.width), int(m.height));
  const auto* bytes = reinterpret_cast<const unsigned char*>(m.data.data());
  for (uint32_t v = 0; v < m.height; ++v) {
    const unsigned char* row = bytes + size_t(v) * m.step;
    uint32_t* out = color.data.data() + size_t(v) * m.width;
    for (uint32_t u = 0; u < m.width; ++u) {
      const unsigned char* p = row + size_t(u) * channels;
      out[u] = channels == 1 ? PackRgb(p[0], p[0], p[0])
               : bgr         ? PackRgb(p[2], p[1], p[0])
                             : PackRgb(p[0], p[1], p[2]);
    }
  }
  return color;
}

Result<ColorImage> ColorFromMessage(const std::string& bytes, bool compressed,
                                    const std::string& where) {
  if (compressed) {
    Result<ros1::CompressedImage> m = ros1::ParseCompressedImage(bytes);
    if (!m.ok()) return m.status().WithContext(where);
    return DecodeColorImage(m->data.data(), m->data.size(), where);
  }
  Result<ros1::Image> m = ros1::ParseImage(bytes);
  if (!m.ok()) return m.status().WithContext(where);
  return ColorFromImage(*m, where);
}

PinholeCamera CameraFromInfo(const ros1::CameraInfo& info) {
  PinholeCamera c;
  c.width = int(std::min<uint32_t>(info.width, uint32_t(bounds::kImageSideMax)));
  c.height = int(std::min<uint32_t>(info.height, uint32_t(bounds::kImageSideMax)));
  c.fx = float(info.K[0]);
  c.fy = float(info.K[4]);
  c.cx = float(info.K[2]);
  c.cy = float(info.K[5]);
  return c;
}

Result<ros1::CameraInfo> FirstCameraInfo(RosBagFile& bag, const std::string& topic) {
  std::optional<ros1::CameraInfo> first;
  VOXPLAN_RETURN_IF_ERROR(bag.ForEachMessage(
      topic,
      [&](size_t, double, const std::string& bytes) {
        Result<ros1::CameraInfo> info = ros1::ParseCameraInfo(bytes);
        if (!info.ok()) return info.status().WithContext(MessageWhere(bag, topic, 0));
        first = std::move(info).value();
        return Status::Ok();
      },
      1));
  if (!first) return CorruptData(bag.path() + ": topic " + topic + " has no messages");
  const std::string where = MessageWhere(bag, topic, 0);
  for (double k : first->K)
    if (!std::isfinite(k)) return CorruptData(where + ": K is not finite");
  VOXPLAN_RETURN_IF_ERROR(CheckFocalLengths(first->K[0], first->K[4], where, 0));
  return *first;
}

// --- topic choice ---

struct Streams {
  std::string depth, color, info, color_info, pose, frame;
  bool color_compressed = false;
  bool pose_is_tf = false;
};

// Picks one topic among candidates: the only one, else the only one whose name holds a hint.
Result<std::string> PickOne(const RosBagFile& bag, const std::vector<std::string>& candidates,
                            std::initializer_list<const char*> hints, const char* what,
                            const char* key) {
  if (candidates.size() == 1) return candidates.front();
  std::vector<std::string> hinted;
  for (const std::string& c : candidates)
    if (std::any_of(hints.begin(), hints.end(), [&](const char* h) { return Contains(c, h); }))
      hinted.push_back(c);
  if (hinted.size() == 1) return hinted.front();
  std::string list;
  for (const std::string& c : candidates) list += (list.empty() ? "" : ", ") + c;
  return InvalidArgument(bag.path() + ": " + std::to_string(candidates.size()) + " " + what +
                         " topics (" + list + "); choose one with --topics " + key + "=TOPIC");
}

// The camera info topic closest to an image topic by name; empty when none is, or two tie.
std::string ClosestInfo(const std::vector<std::string>& infos, const std::string& image) {
  std::string best;
  size_t best_shared = 0;
  bool tie = false;
  for (const std::string& info : infos) {
    const size_t shared = SharedNames(info, image);
    if (shared > best_shared || best.empty()) {
      tie = !best.empty() && shared == best_shared;
      if (!tie) best = info, best_shared = shared;
    } else if (shared == best_shared) {
      tie = true;
    }
  }
  return infos.size() == 1 ? infos.front() : tie ? std::string() : best;
}

Result<Streams> ChooseStreams(RosBagFile& bag, const RosBagTopics& named,
                              std::vector<std::string>& warnings) {
  Streams s;
  std::vector<std::string> depth_topics, color_topics, infos, poses, tfs;
  std::map<std::string, bool> compressed;
  for (const BagTopic& t : bag.topics()) {
    if (IsType(t, ros1::kImage)) {
      Result<ros1::Image> first = FirstImage(bag, t.topic);
      if (!first.ok()) return first.status();
      if (IsDepthEncoding(first->encoding)) depth_topics.push_back(t.topic);
      if (IsColorEncoding(first->encoding)) color_topics.push_back(t.topic);
    } else if (IsType(t, ros1::kCompressedImage)) {
      color_topics.push_back(t.topic);
      compressed[t.topic] = true;
    } else if (IsType(t, ros1::kCameraInfo)) {
      infos.push_back(t.topic);
    } else if (IsType(t, ros1::kPoseStamped)) {
      poses.push_back(t.topic);
    } else if (IsType(t, ros1::kTfMessage)) {
      tfs.push_back(t.topic);
    } else if (t.datatype == ros1::kImage.name || t.datatype == ros1::kCameraInfo.name ||
               t.datatype == ros1::kPoseStamped.name || t.datatype == ros1::kTfMessage.name) {
      warnings.push_back(bag.path() + ": topic " + t.topic + " is a " + t.datatype +
                         " of another definition (md5 " + t.md5sum + "); not read");
    }
  }

  if (!named.depth.empty()) {
    VOXPLAN_RETURN_IF_ERROR(CheckNamed(bag, "depth", named.depth, {ros1::kImage}));
    s.depth = named.depth;
  } else {
    if (depth_topics.empty())
      return NotFound(bag.path() +
                      ": no depth image topic (sensor_msgs/Image in 16UC1, mono16 or 32FC1); "
                      "topics: " +
                      TopicList(bag.topics()));
    Result<std::string> depth = PickOne(bag, depth_topics, {"depth"}, "depth image", "depth");
    if (!depth.ok()) return depth.status();
    s.depth = *depth;
  }

  if (!named.color.empty()) {
    VOXPLAN_RETURN_IF_ERROR(
        CheckNamed(bag, "color", named.color, {ros1::kImage, ros1::kCompressedImage}));
    s.color = named.color;
  } else if (!color_topics.empty()) {
    Result<std::string> color =
        PickOne(bag, color_topics, {"rgb", "color", "colour"}, "colour image", "color");
    if (!color.ok()) return color.status();
    s.color = *color;
  } else {
    warnings.push_back(bag.path() + ": no colour image topic; frames have no colour");
  }
  s.color_compressed =
      !s.color.empty() && IsType(*FindTopic(bag.topics(), s.color), ros1::kCompressedImage);

  if (!named.info.empty()) {
    VOXPLAN_RETURN_IF_ERROR(CheckNamed(bag, "info", named.info, {ros1::kCameraInfo}));
    s.info = named.info;
  } else {
    s.info = ClosestInfo(infos, s.depth);
  }
  if (!named.color_info.empty()) {
    VOXPLAN_RETURN_IF_ERROR(CheckNamed(bag, "color_info", named.color_info, {ros1::kCameraInfo}));
    s.color_info = named.color_info;
  } else if (!s.color.empty() && infos.size() > 1) {
    s.color_info = ClosestInfo(infos, s.color);
    if (s.color_info == s.info) s.color_info.clear();
  }

  if (!named.pose.empty()) {
    VOXPLAN_RETURN_IF_ERROR(
        CheckNamed(bag, "pose", named.pose, {ros1::kPoseStamped, ros1::kTfMessage}));
    s.pose = named.pose;
    s.pose_is_tf = IsType(*FindTopic(bag.topics(), s.pose), ros1::kTfMessage);
  } else if (poses.size() == 1) {
    s.pose = poses.front();
  } else if (poses.size() > 1) {
    Result<std::string> pose = PickOne(bag, poses, {"camera", "pose"}, "pose", "pose");
    if (!pose.ok()) return pose.status();
    s.pose = *pose;
  } else if (std::find(tfs.begin(), tfs.end(), "/tf") != tfs.end()) {
    s.pose = "/tf";
    s.pose_is_tf = true;
  } else {
    warnings.push_back(bag.path() +
                       ": no pose topic (geometry_msgs/PoseStamped or /tf); frames have no pose");
  }
  s.frame = named.frame;
  return s;
}

// --- the dataset ---

struct BagFrame {
  size_t depth_ref = 0;
  std::optional<size_t> color_ref;
};

class BagDataset final : public Dataset {
 public:
  BagDataset(DatasetInfo info, std::vector<Entry> entries, std::vector<BagFrame> frames,
             std::unique_ptr<RosBagFile> bag, Streams streams, PinholeCamera color_camera,
             Pose3d T_color_depth)
      : info_(std::move(info)),
        entries_(std::move(entries)),
        frames_(std::move(frames)),
        bag_(std::move(bag)),
        streams_(std::move(streams)),
        color_camera_(color_camera),
        T_color_depth_(T_color_depth) {}

  const DatasetInfo& info() const override { return info_; }
  std::vector<std::string> InputFiles() const override { return {bag_->path()}; }

  Result<Frame> Load(size_t i) const override {
    Result<Frame> listed = FrameFromEntry(info_, entries_, i);
    if (!listed.ok()) return listed.status();
    Frame frame = std::move(listed).value();
    const Entry& e = entries_[i];
    Result<std::string> bytes = bag_->Read(frames_[i].depth_ref);
    if (!bytes.ok()) return bytes.status();
    Result<ros1::Image> image = ros1::ParseImage(*bytes);
    if (!image.ok()) return image.status().WithContext(e.depth_path);
    Result<DepthImage> depth = DepthFromImage(*image, info_.depth_scale, e.depth_path);
    if (!depth.ok()) return depth.status();
    frame.depth = std::move(depth).value();
    if (frame.depth.width != info_.camera.width || frame.depth.height != info_.camera.height)
      return CorruptData(e.depth_path + ": depth is " + std::to_string(frame.depth.width) + "x" +
                         std::to_string(frame.depth.height) + " but the sequence is " +
                         std::to_string(info_.camera.width) + "x" +
                         std::to_string(info_.camera.height));
    if (frames_[i].color_ref) {
      Result<std::string> color_bytes = bag_->Read(*frames_[i].color_ref);
      if (!color_bytes.ok()) return color_bytes.status();
      Result<ColorImage> color =
          ColorFromMessage(*color_bytes, streams_.color_compressed, e.color_path);
      if (!color.ok()) return color.status();
      if (color->width != color_camera_.width || color->height != color_camera_.height)
        return CorruptData(e.color_path + ": colour is " + std::to_string(color->width) + "x" +
                           std::to_string(color->height) + " but the stream's first is " +
                           std::to_string(color_camera_.width) + "x" +
                           std::to_string(color_camera_.height));
      frame.color =
          RegisterColorToDepth(*color, color_camera_, frame.depth, info_.camera, T_color_depth_);
    }
    return frame;
  }

 private:
  DatasetInfo info_;
  std::vector<Entry> entries_;
  std::vector<BagFrame> frames_;
  std::unique_ptr<RosBagFile> bag_;
  Streams streams_;
  PinholeCamera color_camera_;
  Pose3d T_color_depth_;
};

// A stamped image reference: header stamp (the record time where the stamp is zero).
struct StampedRef {
  double t = 0.0;
  size_t ref = 0;
  size_t n = 0;  // message number on its topic
  std::string frame_id;
};

Result<std::vector<StampedRef>> ReadStamps(RosBagFile& bag, const std::string& topic,
                                           bool compressed) {
  std::vector<StampedRef> out;
  VOXPLAN_RETURN_IF_ERROR(
      bag.ForEachMessage(topic, [&](size_t ref, double record_t, const std::string& bytes) {
        ros1::Header header;
        if (compressed) {
          Result<ros1::CompressedImage> m = ros1::ParseCompressedImage(bytes);
          if (!m.ok()) return m.status().WithContext(MessageWhere(bag, topic, out.size()));
          header = m->header;
        } else {
          Result<ros1::Image> m = ros1::ParseImage(bytes);
          if (!m.ok()) return m.status().WithContext(MessageWhere(bag, topic, out.size()));
          header = m->header;
        }
        out.push_back(
            {header.stamp_s > 0.0 ? header.stamp_s : record_t, ref, out.size(), header.frame_id});
        return Status::Ok();
      }));
  // Bags are in record order; association wants stamp order (stable, so deterministic).
  std::stable_sort(out.begin(), out.end(),
                   [](const StampedRef& a, const StampedRef& b) { return a.t < b.t; });
  return out;
}

// Poses of a PoseStamped topic, by header stamp; non-rigid ones are counted and left out.
Result<std::vector<StampedPose>> ReadPoseTopic(RosBagFile& bag, const std::string& topic,
                                               std::vector<std::string>& warnings) {
  std::vector<StampedPose> out;
  size_t n = 0, bad = 0;
  std::string first_bad;
  VOXPLAN_RETURN_IF_ERROR(bag.ForEachMessage(topic, [&](size_t, double record_t,
                                                        const std::string& bytes) {
    Result<ros1::PoseStamped> m = ros1::ParsePoseStamped(bytes);
    if (!m.ok()) return m.status().WithContext(MessageWhere(bag, topic, n));
    const Eigen::Quaterniond& q = m->orientation;
    Result<Pose3d> pose = PoseFromTranslationQuaternion(m->position, q.x(), q.y(), q.z(), q.w());
    if (!pose.ok()) {
      if (bad++ == 0) first_bad = MessageWhere(bag, topic, n) + ": " + pose.status().message();
    } else {
      out.push_back({m->header.stamp_s > 0.0 ? m->header.stamp_s : record_t, pose->translation(),
                     Eigen::Quaterniond(pose->linear())});
    }
    ++n;
    return Status::Ok();
  }));
  if (bad > 0)
    warnings.push_back(std::to_string(bad) + " poses of " + topic +
                       " are not rigid transforms and are not used (first: " + first_bad + ")");
  std::stable_sort(out.begin(), out.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; });
  return out;
}

// /tf (stamped) and /tf_static (fixed) into one tree; transforms that are not rigid are
// counted and left out.
Status ReadTf(RosBagFile& bag, const std::string& topic, TfTree& tree,
              std::vector<std::string>& warnings) {
  std::vector<std::string> topics = {topic};
  if (topic != "/tf_static") topics.push_back("/tf_static");
  for (const std::string& t : topics) {
    const BagTopic* info = FindTopic(bag.topics(), t);
    if (!info || !IsType(*info, ros1::kTfMessage)) continue;
    const bool is_static = t == "/tf_static";
    size_t n = 0, bad = 0;
    VOXPLAN_RETURN_IF_ERROR(bag.ForEachMessage(t, [&](size_t, double, const std::string& bytes) {
      Result<std::vector<ros1::Transform>> m = ros1::ParseTfMessage(bytes);
      if (!m.ok()) return m.status().WithContext(MessageWhere(bag, t, n));
      for (const ros1::Transform& tr : *m) {
        const Eigen::Quaterniond& q = tr.rotation;
        Result<Pose3d> pose =
            PoseFromTranslationQuaternion(tr.translation, q.x(), q.y(), q.z(), q.w());
        if (!pose.ok()) {
          ++bad;
          continue;
        }
        tree.Add(tr.header.frame_id, tr.child_frame_id, tr.header.stamp_s, *pose, is_static);
      }
      ++n;
      return Status::Ok();
    }));
    if (bad > 0)
      warnings.push_back(bag.path() + ": " + std::to_string(bad) + " transforms of " + t +
                         " are not rigid and are not used");
  }
  tree.Finish();
  if (tree.conflicts() > 0)
    warnings.push_back(bag.path() + ": " + std::to_string(tree.conflicts()) +
                       " transforms give a frame a second parent and are not used");
  return Status::Ok();
}

// RealSense's "Depth Units" option (metres per unit, std_msgs/Float32), as units per metre.
Result<std::optional<double>> RealSenseDepthScale(RosBagFile& bag) {
  for (const BagTopic& t : bag.topics()) {
    if (!IsType(t, ros1::kFloat32) || !Contains(t.topic, "Depth Units")) continue;
    std::optional<double> scale;
    const Status read = bag.ForEachMessage(
        t.topic,
        [&](size_t, double, const std::string& bytes) {
          const std::string where = MessageWhere(bag, t.topic, 0);
          Result<float> units = ros1::ParseFloat32(bytes);
          if (!units.ok()) return units.status().WithContext(where);
          // The option is a float (0.001 reads as 0.0010000000475): to the digits it holds, so
          // that 1 mm units are 1000 per metre exactly.
          char digits[32];
          std::snprintf(digits, sizeof(digits), "%.6g", 1.0 / double(*units));
          const double per_metre = std::strtod(digits, nullptr);
          scale = per_metre;
          return bounds::CheckRange(where + ": depth units per metre", per_metre,
                                    bounds::kDepthScaleMin, bounds::kDepthScaleMax);
        },
        1);
    if (!read.ok()) return read;
    return scale;
  }
  return std::optional<double>();
}

}  // namespace

Result<std::unique_ptr<Dataset>> OpenRosBag(const fs::path& bag_file,
                                            const DatasetOptions& options) {
  const std::string path = bag_file.string();
  Result<std::unique_ptr<RosBagFile>> opened = RosBagFile::Open(path);
  if (!opened.ok()) return opened.status();
  RosBagFile& bag = **opened;

  Draft d;
  d.format = DatasetFormat::kRosBag;
  d.root = path;
  Result<Streams> chosen = ChooseStreams(bag, options.topics, d.warnings);
  if (!chosen.ok()) return chosen.status();
  Streams s = std::move(chosen).value();

  // Depth: its first image fixes the encoding, size and camera frame.
  Result<ros1::Image> first = FirstImage(bag, s.depth);
  if (!first.ok()) return first.status();
  if (!IsDepthEncoding(first->encoding))
    return Unsupported(MessageWhere(bag, s.depth, 0) + ": depth encoding " + first->encoding +
                       " (read: 16UC1, mono16, 32FC1)");
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckImageSize(MessageWhere(bag, s.depth, 0) + ": image",
                                                 first->width, first->height));
  const bool float_depth = first->encoding == "32FC1";
  d.depth_scale = float_depth ? 1.0 : 1000.0;  // 32FC1 in metres, 16-bit in millimetres
  if (!float_depth) {
    Result<std::optional<double>> units = RealSenseDepthScale(bag);
    if (!units.ok()) return units.status();
    if (*units) d.depth_scale = **units;
  }
  if (s.frame.empty()) s.frame = first->header.frame_id;

  if (!s.info.empty()) {
    Result<ros1::CameraInfo> info = FirstCameraInfo(bag, s.info);
    if (!info.ok()) return info.status();
    if (info->width != 0 && (info->width != first->width || info->height != first->height))
      return CorruptData(MessageWhere(bag, s.info, 0) + ": camera info is " +
                         std::to_string(info->width) + "x" + std::to_string(info->height) +
                         " but the depth images of " + s.depth + " are " +
                         std::to_string(first->width) + "x" + std::to_string(first->height));
    const float k[4] = {float(info->K[0]), float(info->K[4]), float(info->K[2]), float(info->K[5])};
    SetIntrinsics(d, k);
    d.intrinsics_source = path + ": " + s.info;
  } else {
    SetIntrinsics(d, kPrimeSense);
    d.intrinsics_source = "default (PrimeSense 525, 525, 319.5, 239.5)";
    d.default_intrinsics_warning = path + ": no camera info for " + s.depth +
                                   ": using PrimeSense 525, 525, 319.5, 239.5; pass --intrinsics "
                                   "or --topics info=TOPIC";
  }

  Result<std::vector<StampedRef>> depth = ReadStamps(bag, s.depth, false);
  if (!depth.ok()) return depth.status();
  std::vector<StampedRef> color;
  std::vector<double> color_t;
  if (!s.color.empty()) {
    Result<std::vector<StampedRef>> c = ReadStamps(bag, s.color, s.color_compressed);
    if (!c.ok()) return c.status();
    color = std::move(c).value();
    for (const StampedRef& r : color) color_t.push_back(r.t);
  }

  std::vector<StampedPose> pose_list;
  TfTree tf;
  if (!s.pose.empty() && !s.pose_is_tf) {
    Result<std::vector<StampedPose>> poses = ReadPoseTopic(bag, s.pose, d.warnings);
    if (!poses.ok()) return poses.status();
    pose_list = std::move(poses).value();
    d.pose_source = path + ": " + s.pose;
  } else if (s.pose_is_tf) {
    VOXPLAN_RETURN_IF_ERROR(ReadTf(bag, s.pose, tf, d.warnings));
    if (!tf.Has(s.frame)) {
      d.warnings.push_back(path + ": the camera frame '" + s.frame + "' is not in " + s.pose +
                           "; frames have no pose (name the frame with --topics frame=NAME)");
      s.pose.clear();
    } else {
      d.pose_source = path + ": " + s.pose + " (frame " + s.frame + ")";
    }
  }

  // Colour camera: its own camera info, else the depth camera scaled to the colour size.
  PinholeCamera depth_camera{int(first->width), int(first->height), d.intrinsics[0],
                             d.intrinsics[1],   d.intrinsics[2],    d.intrinsics[3]};
  PinholeCamera color_camera = depth_camera;
  Pose3d T_color_depth = Pose3d::Identity();
  if (!color.empty()) {
    Result<std::string> bytes = bag.Read(color.front().ref);
    if (!bytes.ok()) return bytes.status();
    Result<ColorImage> c =
        ColorFromMessage(*bytes, s.color_compressed, MessageWhere(bag, s.color, color.front().n));
    if (!c.ok()) return c.status();
    if (!s.color_info.empty()) {
      Result<ros1::CameraInfo> info = FirstCameraInfo(bag, s.color_info);
      if (!info.ok()) return info.status();
      color_camera = CameraFromInfo(*info);
    } else if (c->width != depth_camera.width || c->height != depth_camera.height) {
      const float sx = float(c->width) / float(depth_camera.width),
                  sy = float(c->height) / float(depth_camera.height);
      color_camera.fx *= sx, color_camera.cx = (color_camera.cx + 0.5f) * sx - 0.5f;
      color_camera.fy *= sy, color_camera.cy = (color_camera.cy + 0.5f) * sy - 0.5f;
      d.warnings.push_back(path + ": colour " + s.color + " is " + std::to_string(c->width) + "x" +
                           std::to_string(c->height) + ", depth " +
                           std::to_string(depth_camera.width) + "x" +
                           std::to_string(depth_camera.height) +
                           ", and no colour camera info: colour is resized to depth");
    }
    color_camera.width = c->width;
    color_camera.height = c->height;
    // The cameras' offset, where TF knows both frames.
    const std::string& color_frame = color.front().frame_id;
    if (s.pose_is_tf && TfTree::Bare(color_frame) != TfTree::Bare(s.frame) && tf.Has(color_frame)) {
      std::string root_c, root_d, why;
      bool gap = false;
      const double t0 = depth->front().t;
      std::optional<Pose3d> T_r_c = tf.Lookup(color_frame, t0, 1e9, &root_c, &why, &gap);
      std::optional<Pose3d> T_r_d = tf.Lookup(s.frame, t0, 1e9, &root_d, &why, &gap);
      if (T_r_c && T_r_d && root_c == root_d) T_color_depth = T_r_c->inverse() * *T_r_d;
    }
  }

  size_t no_color = 0, no_pose = 0, in_gap = 0;
  std::string first_gap, first_no_pose;
  std::vector<BagFrame> frames;
  for (const StampedRef& r : *depth) {
    Entry e;
    e.depth_path = MessageWhere(bag, s.depth, r.n);
    e.timestamp = r.t;
    e.origin = e.depth_path;
    BagFrame f;
    f.depth_ref = r.ref;
    if (!s.color.empty()) {
      const std::optional<size_t> best = NearestStamp(color_t, r.t, kTumMaxAssociationDt);
      if (!best) {
        ++no_color;
        continue;
      }
      f.color_ref = color[*best].ref;
      e.color_path = MessageWhere(bag, s.color, color[*best].n);
    }
    if (!s.pose.empty()) {
      double gap_from = 0.0, gap_to = 0.0;
      std::string why, root;
      bool gap = false;
      if (s.pose_is_tf) {
        e.T_W_C = tf.Lookup(s.frame, r.t, options.max_pose_gap_s, &root, &why, &gap);
      } else {
        e.T_W_C = InterpolatePose(pose_list, r.t, options.max_pose_gap_s, &gap_from, &gap_to);
        gap = gap_to > gap_from;
        if (gap)
          why = s.pose + " has a gap from " + NumberText(gap_from) + " to " + NumberText(gap_to) +
                " s";
      }
      if (!e.T_W_C && gap) {
        // Kept without a pose, so that fusion counts it as skipped for the gap.
        e.pose_rejected = PoseRejection::kGroundTruthGap;
        e.pose_rejected_why = e.depth_path + ": depth " + NumberText(r.t) + ": " + why +
                              ", longer than the " + NumberText(options.max_pose_gap_s) +
                              " s allowed for interpolation";
        if (in_gap++ == 0) first_gap = e.pose_rejected_why;
      } else if (!e.T_W_C) {
        if (no_pose++ == 0)
          first_no_pose =
              e.depth_path + " (" + NumberText(r.t) + " s)" + (why.empty() ? "" : ": " + why);
        continue;
      }
    }
    d.entries.push_back(std::move(e));
    frames.push_back(f);
  }
  if (no_color > 0)
    d.warnings.push_back(std::to_string(no_color) + " depth frames of " + s.depth +
                         " have no colour image of " + s.color + " within 0.02 s; dropped");
  if (no_pose > 0)
    d.warnings.push_back(std::to_string(no_pose) + " depth frames have no pose around them in " +
                         s.pose + "; dropped (first: " + first_no_pose + ")");
  if (in_gap > 0)
    d.warnings.push_back(std::to_string(in_gap) + " depth frames have no pose: they lie in gaps " +
                         "of " + s.pose + " (first: " + first_gap + ")");
  d.empty_message = path + ": no depth frame of " + s.depth + " associates (" +
                    std::to_string(depth->size()) + " depth frames: " + std::to_string(no_color) +
                    " without colour within 0.02 s, " + std::to_string(no_pose) +
                    " without a pose around them)";

  if (!s.pose.empty()) {
    // REP 103: ROS world frames (map, odom, world) are x forward / east, y left, z up.
    d.stated_up = WorldUp::kPlusZ;
    d.up_convention = "ROS convention (REP 103: world frames are z-up)";
  }
  Result<DatasetInfo> finished = FinishInfo(d, options);
  if (!finished.ok()) return finished.status();
  DatasetInfo info = std::move(finished).value();
  info.camera.width = depth_camera.width;
  info.camera.height = depth_camera.height;
  info.streams = "depth " + s.depth + " (" + first->encoding + ")";
  if (!s.color.empty()) info.streams += ", colour " + s.color;
  if (!s.info.empty()) info.streams += ", info " + s.info;
  if (!s.color_info.empty()) info.streams += ", colour info " + s.color_info;
  if (!s.pose.empty())
    info.streams += ", pose " + s.pose + (s.pose_is_tf ? " (frame " + s.frame + ")" : "");
  return std::unique_ptr<Dataset>(new BagDataset(std::move(info), std::move(d.entries),
                                                 std::move(frames), std::move(opened).value(),
                                                 std::move(s), color_camera, T_color_depth));
}

}  // namespace dataset
}  // namespace voxplan
