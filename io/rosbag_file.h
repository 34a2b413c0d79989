#pragma once
// ROS 1 bags through Debian's rosbag_storage, the one file in voxplan that includes ROS
// headers: a bag's topics, and the serialized bytes of its messages (parsed by
// io/ros_messages.h). rosbag's exceptions become Status naming the bag (and topic and message);
// its console_bridge log is silenced, so nothing is printed. A writer makes small bags for tests
// and fixtures.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"

namespace voxplan {

struct BagTopic {
  std::string topic, datatype, md5sum;
  size_t messages = 0;
};

// A message larger than this is refused before its bytes are copied (a 8192 x 8192 float image
// is 256 MiB): a corrupt size cannot take the machine's memory.
inline constexpr uint32_t kMaxBagMessageBytes = (uint32_t(1) << 28) + (uint32_t(1) << 20);

class RosBagFile {
 public:
  // Checks the bag's structure (io/rosbag_check.h: every length against the file, each index
  // entry against its chunk; this reads the whole file once), then opens and indexes it.
  static Result<std::unique_ptr<RosBagFile>> Open(const std::string& path);
  ~RosBagFile();
  RosBagFile(const RosBagFile&) = delete;
  RosBagFile& operator=(const RosBagFile&) = delete;

  const std::string& path() const;
  const std::vector<BagTopic>& topics() const;  // sorted by topic name

  // Calls visit(ref, record_time_s, bytes) for each message on `topic` in bag order, at most
  // `max_messages` (0: all); `ref` reads the message again later (Read). Stops at the first
  // error visit returns.
  using Visitor = std::function<Status(size_t ref, double record_time_s, const std::string& bytes)>;
  Status ForEachMessage(const std::string& topic, const Visitor& visit, size_t max_messages = 0);

  // The bytes of a message ForEachMessage visited. Thread-safe (rosbag's reader is not: calls
  // are serialised).
  Result<std::string> Read(size_t ref) const;

 private:
  struct Impl;
  explicit RosBagFile(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Writes a ROS 1 bag of already serialized messages (uncompressed chunks).
class RosBagWriter {
 public:
  static Result<std::unique_ptr<RosBagWriter>> Create(const std::string& path);
  ~RosBagWriter();
  RosBagWriter(const RosBagWriter&) = delete;
  RosBagWriter& operator=(const RosBagWriter&) = delete;

  Status Write(const std::string& topic, double time_s, const std::string& datatype,
               const std::string& md5sum, const std::string& bytes);
  Status Close();  // writes the index; also done (errors dropped) by the destructor

 private:
  struct Impl;
  explicit RosBagWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace voxplan
