#include "io/rosbag_check.h"

#include <bzlib.h>
#include <roslz4/lz4s.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string_view>
#include <vector>

namespace voxplan {
namespace {

namespace fs = std::filesystem;

// Record ops of format 2.0 (rosbag/constants.h).
constexpr uint8_t kOpMessageData = 0x02, kOpFileHeader = 0x03, kOpIndexData = 0x04, kOpChunk = 0x05,
                  kOpChunkInfo = 0x06, kOpConnection = 0x07;
constexpr char kVersionLine[] = "#ROSBAG V2.0\n";
constexpr uint64_t kVersionBytes = sizeof(kVersionLine) - 1;
// ros::Header::parse refuses longer fields.
constexpr uint32_t kMaxFieldBytes = 1000000;

using Fields = std::map<std::string, std::string, std::less<>>;

uint32_t U32(const char* p) {
  return uint32_t(uint8_t(p[0])) | uint32_t(uint8_t(p[1])) << 8 | uint32_t(uint8_t(p[2])) << 16 |
         uint32_t(uint8_t(p[3])) << 24;
}

// A header: fields of <uint32 length>name=value that fill it exactly; "" or why not.
std::string ParseFields(std::string_view bytes, Fields& out) {
  size_t at = 0;
  while (at < bytes.size()) {
    if (bytes.size() - at < 4) return "a field's length is cut short";
    const uint32_t n = U32(bytes.data() + at);
    at += 4;
    if (n > bytes.size() - at)
      return "a field of " + std::to_string(n) + " bytes runs past the header's end";
    if (n > kMaxFieldBytes) return "a field of " + std::to_string(n) + " bytes";
    const std::string_view field = bytes.substr(at, n);
    at += n;
    const size_t eq = field.find('=');
    if (eq == std::string_view::npos) return "a field without '='";
    out[std::string(field.substr(0, eq))] = std::string(field.substr(eq + 1));
  }
  return "";
}

struct Record {
  uint64_t pos = 0;  // of its header length
  uint8_t op = 0;
  Fields fields;
  uint64_t data_pos = 0;
  uint32_t data_len = 0;
};

class BagChecker {
 public:
  explicit BagChecker(std::string path) : path_(std::move(path)) {}

  Status Run() {
    std::error_code ec;
    size_ = fs::file_size(path_, ec);
    if (ec) return IoError(path_ + ": cannot stat (" + ec.message() + ")");
    in_.open(path_, std::ios::binary);
    if (!in_) return IoError(path_ + ": cannot open");
    std::string version;
    VOXPLAN_RETURN_IF_ERROR(Read(0, std::min<uint64_t>(size_, kVersionBytes), version));
    if (version.compare(0, 9, "#ROSBAG V") != 0)
      return CorruptData(path_ + ": not a ROS 1 bag (no \"#ROSBAG V\" at its start)");
    if (version != kVersionLine) {
      const std::string stated = version.substr(9, version.find('\n') - 9);
      return Unsupported(path_ + ": bag version '" + stated +
                         "', only 2.0 is read (`rosbag fix` converts older bags)");
    }
    VOXPLAN_RETURN_IF_ERROR(WalkRecords());
    VOXPLAN_RETURN_IF_ERROR(CheckIndex());
    return Status::Ok();
  }

 private:
  Status Read(uint64_t pos, uint64_t n, std::string& out) {
    if (pos > size_ || n > size_ - pos)
      return CorruptData(path_ + ": " + std::to_string(n) + " bytes at byte " +
                         std::to_string(pos) + " run past the end of the file (" +
                         std::to_string(size_) + " bytes)");
    out.resize(size_t(n));
    return ReadInto(pos, n, out.data());
  }

  // Seeks only when the read does not follow the last one (the walk reads mostly in order).
  Status ReadInto(uint64_t pos, uint64_t n, char* out) {
    if (pos != next_) {
      in_.clear();
      in_.seekg(std::streamoff(pos));
    }
    next_ = pos + n;
    if (n > 0 && !in_.read(out, std::streamsize(n))) {
      next_ = UINT64_MAX;
      return IoError(path_ + ": read failed at byte " + std::to_string(pos));
    }
    return Status::Ok();
  }

  Status Fault(uint64_t pos, const std::string& why) const {
    return CorruptData(path_ + ": corrupt bag: record at byte " + std::to_string(pos) + ": " + why);
  }

  // The file after the version line is a sequence of records: <uint32 header length> header
  // <uint32 data length> data. Each must fit; headers are read, data only where checked.
  Status WalkRecords() {
    uint64_t pos = kVersionBytes;
    std::string bytes;
    while (pos < size_) {
      Record r;
      r.pos = pos;
      VOXPLAN_RETURN_IF_ERROR(Read(pos, 4, bytes));
      const uint32_t header_len = U32(bytes.data());
      if (uint64_t(header_len) + 8 > size_ - pos)
        return Fault(pos, "header of " + std::to_string(header_len) +
                              " bytes runs past the end of the file");
      VOXPLAN_RETURN_IF_ERROR(Read(pos + 4, header_len, bytes));
      if (std::string why = ParseFields(bytes, r.fields); !why.empty()) return Fault(pos, why);
      const auto op = r.fields.find("op");
      if (op == r.fields.end() || op->second.size() != 1) return Fault(pos, "no one-byte op field");
      r.op = uint8_t(op->second[0]);
      VOXPLAN_RETURN_IF_ERROR(Read(pos + 4 + header_len, 4, bytes));
      r.data_len = U32(bytes.data());
      r.data_pos = pos + 8 + header_len;
      if (r.data_len > size_ - r.data_pos)
        return Fault(
            pos, "data of " + std::to_string(r.data_len) + " bytes runs past the end of the file");
      if (r.op == kOpConnection) {  // its data is the connection's header
        Fields connection;
        VOXPLAN_RETURN_IF_ERROR(Read(r.data_pos, r.data_len, bytes));
        if (std::string why = ParseFields(bytes, connection); !why.empty())
          return Fault(pos, "connection header: " + why);
      }
      at_[pos] = records_.size();
      pos = r.data_pos + r.data_len;
      records_.push_back(std::move(r));
    }
    return Status::Ok();
  }

  // A field of exactly `bytes` bytes, little-endian.
  Result<uint64_t> Number(const Record& r, const char* name, size_t bytes) const {
    const auto f = r.fields.find(name);
    if (f == r.fields.end() || f->second.size() != bytes)
      return Fault(r.pos,
                   std::string("no ") + std::to_string(bytes) + "-byte '" + name + "' field");
    uint64_t v = 0;
    for (size_t i = bytes; i-- > 0;) v = (v << 8) | uint8_t(f->second[i]);
    return v;
  }

  const Record* At(uint64_t pos) const {
    const auto it = at_.find(pos);
    return it == at_.end() ? nullptr : &records_[it->second];
  }

  // What rosbag reads when it opens the bag: the file header, the connection and chunk info
  // records at index_pos, each chunk's header and the index records after it; then, for each
  // message, the record at its index entry's offset in the chunk.
  Status CheckIndex() {
    if (records_.empty() || records_[0].op != kOpFileHeader)
      return Fault(kVersionBytes, "the bag does not start with its file header record");
    const Record& file_header = records_[0];
    if (const auto e = file_header.fields.find("encryptor");
        e != file_header.fields.end() && !e->second.empty())
      return Unsupported(path_ + ": an encrypted bag (" + e->second + "); decrypt it first");
    Result<uint64_t> index_pos = Number(file_header, "index_pos", 8);
    Result<uint64_t> conn_count = Number(file_header, "conn_count", 4);
    Result<uint64_t> chunk_count = Number(file_header, "chunk_count", 4);
    if (!index_pos.ok()) return index_pos.status();
    if (!conn_count.ok()) return conn_count.status();
    if (!chunk_count.ok()) return chunk_count.status();
    if (*index_pos == 0)
      return CorruptData(path_ +
                         ": unindexed bag (its recording did not finish); `rosbag reindex` "
                         "repairs it");
    const auto first = at_.find(*index_pos);
    if (first == at_.end())
      return Fault(file_header.pos,
                   "index_pos " + std::to_string(*index_pos) + " is not the start of a record");
    size_t k = first->second;
    if (*conn_count + *chunk_count > records_.size() - k)
      return Fault(file_header.pos, "states " + std::to_string(*conn_count) + " connections and " +
                                        std::to_string(*chunk_count) +
                                        " chunks, more records than follow index_pos");
    for (uint64_t i = 0; i < *conn_count; ++i, ++k) {
      const Record& c = records_[k];
      if (c.op != kOpConnection) return Fault(c.pos, "a connection record was expected");
      Result<uint64_t> id = Number(c, "conn", 4);
      if (!id.ok()) return id.status();
      connections_.insert(uint32_t(*id));
    }
    std::string bytes;
    for (uint64_t i = 0; i < *chunk_count; ++i, ++k) {
      const Record& info = records_[k];
      if (info.op != kOpChunkInfo) return Fault(info.pos, "a chunk info record was expected");
      Result<uint64_t> ver = Number(info, "ver", 4);
      if (!ver.ok()) return ver.status();
      if (*ver != 1) return Fault(info.pos, "chunk info version " + std::to_string(*ver));
      Result<uint64_t> chunk_pos = Number(info, "chunk_pos", 8);
      Result<uint64_t> count = Number(info, "count", 4);
      if (!chunk_pos.ok()) return chunk_pos.status();
      if (!count.ok()) return count.status();
      if (*count * 8 > info.data_len)
        return Fault(info.pos, std::to_string(*count) + " connection counts in " +
                                   std::to_string(info.data_len) + " bytes");
      VOXPLAN_RETURN_IF_ERROR(Read(info.data_pos, *count * 8, bytes));
      std::set<uint32_t> counted;  // rosbag keeps them in a map: one index record per connection
      for (uint64_t j = 0; j < *count; ++j) counted.insert(U32(bytes.data() + 8 * j));
      VOXPLAN_RETURN_IF_ERROR(CheckChunk(info, *chunk_pos, counted.size()));
    }
    return Status::Ok();
  }

  Status CheckChunk(const Record& info, uint64_t chunk_pos, size_t index_records) {
    const auto at = at_.find(chunk_pos);
    if (at == at_.end() || records_[at->second].op != kOpChunk)
      return Fault(info.pos, "chunk_pos " + std::to_string(chunk_pos) + " is not a chunk record");
    if (index_records > records_.size() - at->second - 1)
      return Fault(info.pos, std::to_string(index_records) +
                                 " index records should follow the chunk; fewer records do");
    const Record& chunk = records_[at->second];
    std::unique_ptr<char[]> chunk_bytes;
    std::string_view chunk_data;
    VOXPLAN_RETURN_IF_ERROR(Chunk(chunk, chunk_bytes, chunk_data));
    std::string bytes;
    for (size_t i = 1; i <= index_records; ++i) {
      const Record& index = records_[at->second + i];
      if (index.op != kOpIndexData) return Fault(index.pos, "an index data record was expected");
      Result<uint64_t> ver = Number(index, "ver", 4);
      Result<uint64_t> conn = Number(index, "conn", 4);
      Result<uint64_t> count = Number(index, "count", 4);
      if (!ver.ok()) return ver.status();
      if (!conn.ok()) return conn.status();
      if (!count.ok()) return count.status();
      if (*ver != 1) return Fault(index.pos, "index data version " + std::to_string(*ver));
      if (!connections_.contains(uint32_t(*conn)))
        return Fault(index.pos, "index of connection " + std::to_string(*conn) +
                                    ", which the bag does not declare");
      if (*count * 12 > index.data_len)
        return Fault(index.pos, std::to_string(*count) + " index entries in " +
                                    std::to_string(index.data_len) + " bytes");
      VOXPLAN_RETURN_IF_ERROR(Read(index.data_pos, *count * 12, bytes));
      for (uint64_t j = 0; j < *count; ++j) {
        const uint32_t offset = U32(bytes.data() + 12 * j + 8);
        if (std::string why = CheckMessageAt(chunk_data, offset); !why.empty())
          return Fault(index.pos, "entry " + std::to_string(j) + ": the message at offset " +
                                      std::to_string(offset) + " of the chunk at byte " +
                                      std::to_string(chunk.pos) + ": " + why);
      }
    }
    return Status::Ok();
  }

  // The chunk's records, decompressed as its header says. The buffer is not written before the
  // decompressor writes it, so a size the data cannot fill costs no memory.
  Status Chunk(const Record& chunk, std::unique_ptr<char[]>& buffer, std::string_view& out) {
    const auto compression = chunk.fields.find("compression");
    Result<uint64_t> size = Number(chunk, "size", 4);
    if (!size.ok()) return size.status();
    if (compression == chunk.fields.end()) return Fault(chunk.pos, "chunk without compression");
    const std::string& kind = compression->second;
    if (kind != "none" && kind != "bz2" && kind != "lz4")
      return Unsupported(path_ + ": chunk at byte " + std::to_string(chunk.pos) +
                         " has compression '" + kind + "' (read: none, bz2, lz4)");
    if (kind == "none" && *size != chunk.data_len)
      return Fault(chunk.pos, "uncompressed chunk of " + std::to_string(chunk.data_len) +
                                  " bytes states size " + std::to_string(*size));
    if (*size > kMaxBagChunkBytes)
      return Fault(chunk.pos, "chunk of " + std::to_string(*size) + " bytes (at most " +
                                  std::to_string(kMaxBagChunkBytes) + ")");
    if (kind == "none") {
      buffer.reset(new char[chunk.data_len]);
      VOXPLAN_RETURN_IF_ERROR(ReadInto(chunk.data_pos, chunk.data_len, buffer.get()));
      out = std::string_view(buffer.get(), chunk.data_len);
      return Status::Ok();
    }
    std::string stored;
    VOXPLAN_RETURN_IF_ERROR(Read(chunk.data_pos, chunk.data_len, stored));
    buffer.reset(new char[size_t(*size) + 1]);
    unsigned int out_len = unsigned(*size);
    const bool ok = kind == "bz2"
                        ? BZ2_bzBuffToBuffDecompress(buffer.get(), &out_len, stored.data(),
                                                     unsigned(stored.size()), 0, 0) == BZ_OK
                        : roslz4_buffToBuffDecompress(stored.data(), unsigned(stored.size()),
                                                      buffer.get(), &out_len) == ROSLZ4_OK;
    if (!ok || out_len != *size)
      return Fault(chunk.pos, "the " + kind + " chunk does not decompress to its " +
                                  std::to_string(*size) + " bytes");
    out = std::string_view(buffer.get(), out_len);
    return Status::Ok();
  }

  // A whole message data record at `offset` of the decompressed chunk; "" or why not.
  static std::string CheckMessageAt(std::string_view chunk, uint64_t offset) {
    if (offset > chunk.size() || chunk.size() - offset < 8) return "runs past the chunk's end";
    const uint32_t header_len = U32(chunk.data() + offset);
    if (uint64_t(header_len) + 8 > chunk.size() - offset) return "its header runs past the chunk";
    Fields fields;
    if (std::string why = ParseFields(chunk.substr(offset + 4, header_len), fields); !why.empty())
      return why;
    const auto op = fields.find("op");
    if (op == fields.end() || op->second.size() != 1 || uint8_t(op->second[0]) != kOpMessageData)
      return "not a message data record";
    const uint32_t data_len = U32(chunk.data() + offset + 4 + header_len);
    if (data_len > chunk.size() - offset - 8 - header_len) return "its data runs past the chunk";
    return "";
  }

  std::string path_;
  std::ifstream in_;
  uint64_t size_ = 0, next_ = 0;  // next_: where the stream stands
  std::vector<Record> records_;
  std::map<uint64_t, size_t> at_;  // record position -> records_ index
  std::set<uint32_t> connections_;
};

}  // namespace

Status CheckRosBagStructure(const std::string& path) { return BagChecker(path).Run(); }

}  // namespace voxplan
