#include "io/rosbag_file.h"

#include <console_bridge/console.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <algorithm>
#include <cstring>
#include <exception>
#include <filesystem>
#include <map>
#include <mutex>
#include <utility>

#include "io/rosbag_check.h"

namespace voxplan {
namespace {

// A message already serialized, written by rosbag as it is (its traits below).
struct RawMessage {
  const std::string* datatype = nullptr;
  const std::string* md5sum = nullptr;
  const std::string* bytes = nullptr;
};

// rosbag logs through console_bridge to stderr; the library never prints.
void SilenceRosbag() {
  static std::once_flag once;
  std::call_once(once,
                 [] { console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE); });
}

double Seconds(const ros::Time& t) { return double(t.sec) + 1e-9 * double(t.nsec); }

}  // namespace
}  // namespace voxplan

namespace ros::message_traits {
template <>
struct MD5Sum<voxplan::RawMessage> {
  static const char* value(const voxplan::RawMessage& m) { return m.md5sum->c_str(); }
  static const char* value() { return "*"; }
};
template <>
struct DataType<voxplan::RawMessage> {
  static const char* value(const voxplan::RawMessage& m) { return m.datatype->c_str(); }
  static const char* value() { return "*"; }
};
template <>
struct Definition<voxplan::RawMessage> {
  static const char* value(const voxplan::RawMessage&) { return ""; }
  static const char* value() { return ""; }
};
}  // namespace ros::message_traits

namespace ros::serialization {
template <>
struct Serializer<voxplan::RawMessage> {
  template <typename Stream>
  static void write(Stream& stream, const voxplan::RawMessage& m) {
    if (!m.bytes->empty())
      std::memcpy(stream.advance(uint32_t(m.bytes->size())), m.bytes->data(), m.bytes->size());
  }
  static uint32_t serializedLength(const voxplan::RawMessage& m) {
    return uint32_t(m.bytes->size());
  }
};
}  // namespace ros::serialization

namespace voxplan {

struct RosBagFile::Impl {
  std::string path;
  rosbag::Bag bag;
  std::vector<BagTopic> topics;
  std::vector<rosbag::MessageInstance> refs;  // each holds its index entry; valid while bag is
  mutable std::mutex mutex;                   // rosbag's reader keeps a chunk cache
};

RosBagFile::RosBagFile(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RosBagFile::~RosBagFile() = default;
const std::string& RosBagFile::path() const { return impl_->path; }
const std::vector<BagTopic>& RosBagFile::topics() const { return impl_->topics; }

Result<std::unique_ptr<RosBagFile>> RosBagFile::Open(const std::string& path) {
  SilenceRosbag();
  // rosbag_storage trusts the file's lengths: its structure is checked first (rosbag_check.h).
  VOXPLAN_RETURN_IF_ERROR(CheckRosBagStructure(path));
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  try {
    impl->bag.open(path, rosbag::bagmode::Read);
    rosbag::View view(impl->bag);
    std::map<std::string, BagTopic> by_topic;
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      BagTopic& t = by_topic[c->topic];
      if (!t.topic.empty() && (t.datatype != c->datatype || t.md5sum != c->md5sum))
        return CorruptData(path + ": topic " + c->topic + " carries two message types (" +
                           t.datatype + ", " + c->datatype + ")");
      t.topic = c->topic;
      t.datatype = c->datatype;
      t.md5sum = c->md5sum;
    }
    for (auto& [name, topic] : by_topic) {
      rosbag::View counted(impl->bag, rosbag::TopicQuery(name));
      topic.messages = counted.size();
      impl->topics.push_back(topic);
    }
  } catch (const std::exception& e) {
    return CorruptData(path + ": cannot read the bag (" + e.what() + ")");
  }
  return std::unique_ptr<RosBagFile>(new RosBagFile(std::move(impl)));
}

Status RosBagFile::ForEachMessage(const std::string& topic, const Visitor& visit,
                                  size_t max_messages) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  size_t n = 0;
  try {
    rosbag::View view(impl_->bag, rosbag::TopicQuery(topic));
    for (const rosbag::MessageInstance& m : view) {
      const std::string where = impl_->path + ": topic " + topic + " message " + std::to_string(n);
      const uint32_t size = m.size();
      if (size > kMaxBagMessageBytes)
        return CorruptData(where + ": " + std::to_string(size) + " bytes (at most " +
                           std::to_string(kMaxBagMessageBytes) + ")");
      std::string bytes(size, '\0');
      ros::serialization::OStream stream(reinterpret_cast<uint8_t*>(bytes.data()), size);
      m.write(stream);
      impl_->refs.push_back(m);
      VOXPLAN_RETURN_IF_ERROR(visit(impl_->refs.size() - 1, Seconds(m.getTime()), bytes));
      if (++n == max_messages) break;
    }
  } catch (const std::exception& e) {
    return CorruptData(impl_->path + ": topic " + topic + " message " + std::to_string(n) +
                       ": cannot read (" + e.what() + ")");
  }
  return Status::Ok();
}

Result<std::string> RosBagFile::Read(size_t ref) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (ref >= impl_->refs.size())
    return InvalidArgument(impl_->path + ": no message " + std::to_string(ref));
  const rosbag::MessageInstance& m = impl_->refs[ref];
  try {
    const uint32_t size = m.size();
    if (size > kMaxBagMessageBytes)
      return CorruptData(impl_->path + ": topic " + m.getTopic() + ": message of " +
                         std::to_string(size) + " bytes");
    std::string bytes(size, '\0');
    ros::serialization::OStream stream(reinterpret_cast<uint8_t*>(bytes.data()), size);
    m.write(stream);
    return bytes;
  } catch (const std::exception& e) {
    return CorruptData(impl_->path + ": topic " + m.getTopic() + ": cannot read a message (" +
                       e.what() + ")");
  }
}

struct RosBagWriter::Impl {
  std::string path;
  rosbag::Bag bag;
  bool open = false;
};

RosBagWriter::RosBagWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RosBagWriter::~RosBagWriter() { (void)Close(); }

Result<std::unique_ptr<RosBagWriter>> RosBagWriter::Create(const std::string& path) {
  SilenceRosbag();
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  try {
    impl->bag.open(path, rosbag::bagmode::Write);
  } catch (const std::exception& e) {
    return IoError(path + ": cannot create the bag (" + e.what() + ")");
  }
  impl->open = true;
  return std::unique_ptr<RosBagWriter>(new RosBagWriter(std::move(impl)));
}

Status RosBagWriter::Write(const std::string& topic, double time_s, const std::string& datatype,
                           const std::string& md5sum, const std::string& bytes) {
  if (!impl_->open) return InvalidArgument(impl_->path + ": bag already closed");
  if (!(time_s >= 0.0 && time_s < 4e9))
    return InvalidArgument(impl_->path + ": message time " + std::to_string(time_s) +
                           " s is not a ROS time");
  try {
    impl_->bag.write(topic, ros::Time(time_s), RawMessage{&datatype, &md5sum, &bytes});
  } catch (const std::exception& e) {
    return IoError(impl_->path + ": cannot write to " + topic + " (" + e.what() + ")");
  }
  return Status::Ok();
}

Status RosBagWriter::Close() {
  if (!impl_->open) return Status::Ok();
  impl_->open = false;
  try {
    impl_->bag.close();
  } catch (const std::exception& e) {
    return IoError(impl_->path + ": cannot finish the bag (" + e.what() + ")");
  }
  return Status::Ok();
}

}  // namespace voxplan
