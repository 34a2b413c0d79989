#include "io/ros_messages.h"

#include <bit>
#include <cmath>
#include <cstring>

namespace voxplan::ros1 {
namespace {

// Strings in these messages are names (frames, encodings); longer ones are not a real message.
constexpr uint32_t kMaxStringBytes = 4096;

// Little-endian reads over the message bytes; each checks what is left before it reads.
class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}
  size_t left() const { return bytes_.size() - pos_; }

  Status Need(uint64_t n, const char* what) const {
    if (n > left())
      return CorruptData(std::string("message cut short: ") + what + " needs " + std::to_string(n) +
                         " bytes at byte " + std::to_string(pos_) + ", " + std::to_string(left()) +
                         " left");
    return Status::Ok();
  }
  Result<uint8_t> U8(const char* what) {
    VOXPLAN_RETURN_IF_ERROR(Need(1, what));
    return uint8_t(bytes_[pos_++]);
  }
  Result<uint32_t> U32(const char* what) {
    VOXPLAN_RETURN_IF_ERROR(Need(4, what));
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | uint8_t(bytes_[pos_ + size_t(i)]);
    pos_ += 4;
    return v;
  }
  Result<double> F64(const char* what) {
    VOXPLAN_RETURN_IF_ERROR(Need(8, what));
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | uint8_t(bytes_[pos_ + size_t(i)]);
    pos_ += 8;
    return std::bit_cast<double>(v);
  }
  // A uint32 length, then that many bytes (not copied).
  Result<std::string_view> Bytes(const char* what) {
    Result<uint32_t> n = U32(what);
    if (!n.ok()) return n.status();
    VOXPLAN_RETURN_IF_ERROR(Need(*n, what));
    const std::string_view out = bytes_.substr(pos_, *n);
    pos_ += *n;
    return out;
  }
  Result<std::string> String(const char* what) {
    Result<std::string_view> s = Bytes(what);
    if (!s.ok()) return s.status();
    if (s->size() > kMaxStringBytes)
      return CorruptData(std::string(what) + " of " + std::to_string(s->size()) +
                         " bytes (at most " + std::to_string(kMaxStringBytes) + ")");
    return std::string(*s);
  }
  Status Doubles(double* out, int n, const char* what) {
    for (int i = 0; i < n; ++i) {
      Result<double> v = F64(what);
      if (!v.ok()) return v.status();
      out[i] = *v;
    }
    return Status::Ok();
  }
  Status End(const char* type) const {
    if (left() != 0)
      return CorruptData(std::to_string(left()) + " bytes left after a whole " + type +
                         " (another message type?)");
    return Status::Ok();
  }

 private:
  std::string_view bytes_;
  size_t pos_ = 0;
};

Result<Header> ReadHeader(Reader& r) {
  Header h;
  Result<uint32_t> seq = r.U32("header seq");
  if (!seq.ok()) return seq.status();
  Result<uint32_t> sec = r.U32("header stamp");
  if (!sec.ok()) return sec.status();
  Result<uint32_t> nsec = r.U32("header stamp");
  if (!nsec.ok()) return nsec.status();
  Result<std::string> frame = r.String("header frame_id");
  if (!frame.ok()) return frame.status();
  h.seq = *seq;
  h.stamp_s = double(*sec) + 1e-9 * double(*nsec);
  h.frame_id = std::move(frame).value();
  return h;
}

// Point/Vector3 then Quaternion (x y z w), as Pose and Transform both lay them out.
Status ReadRigid(Reader& r, Eigen::Vector3d& t, Eigen::Quaterniond& q) {
  double v[7];
  VOXPLAN_RETURN_IF_ERROR(r.Doubles(v, 7, "pose"));
  t = Eigen::Vector3d(v[0], v[1], v[2]);
  q = Eigen::Quaterniond(v[6], v[3], v[4], v[5]);
  return Status::Ok();
}

// --- writing ---
void PutU32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(char((v >> (8 * i)) & 0xff));
}
void PutF64(std::string& out, double v) {
  const uint64_t bits = std::bit_cast<uint64_t>(v);
  for (int i = 0; i < 8; ++i) out.push_back(char((bits >> (8 * i)) & 0xff));
}
void PutBytes(std::string& out, std::string_view s) {
  PutU32(out, uint32_t(s.size()));
  out.append(s);
}
void PutHeader(std::string& out, const Header& h) {
  PutU32(out, h.seq);
  uint64_t sec = uint64_t(std::floor(h.stamp_s));
  uint64_t nsec = uint64_t(std::llround((h.stamp_s - double(sec)) * 1e9));
  if (nsec >= 1000000000u) ++sec, nsec -= 1000000000u;
  PutU32(out, uint32_t(sec));
  PutU32(out, uint32_t(nsec));
  PutBytes(out, h.frame_id);
}
void PutRigid(std::string& out, const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  for (double v : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) PutF64(out, v);
}

}  // namespace

Result<Image> ParseImage(std::string_view bytes) {
  Reader r(bytes);
  Image m;
  Result<Header> h = ReadHeader(r);
  if (!h.ok()) return h.status();
  m.header = std::move(h).value();
  Result<uint32_t> height = r.U32("height"), width = r.U32("width");
  if (!height.ok()) return height.status();
  if (!width.ok()) return width.status();
  Result<std::string> encoding = r.String("encoding");
  if (!encoding.ok()) return encoding.status();
  Result<uint8_t> big = r.U8("is_bigendian");
  if (!big.ok()) return big.status();
  Result<uint32_t> step = r.U32("step");
  if (!step.ok()) return step.status();
  Result<std::string_view> data = r.Bytes("data");
  if (!data.ok()) return data.status();
  VOXPLAN_RETURN_IF_ERROR(r.End(kImage.name));
  m.height = *height;
  m.width = *width;
  m.encoding = std::move(encoding).value();
  m.big_endian = *big != 0;
  m.step = *step;
  m.data = *data;
  return m;
}

Result<CompressedImage> ParseCompressedImage(std::string_view bytes) {
  Reader r(bytes);
  CompressedImage m;
  Result<Header> h = ReadHeader(r);
  if (!h.ok()) return h.status();
  m.header = std::move(h).value();
  Result<std::string> format = r.String("format");
  if (!format.ok()) return format.status();
  Result<std::string_view> data = r.Bytes("data");
  if (!data.ok()) return data.status();
  VOXPLAN_RETURN_IF_ERROR(r.End(kCompressedImage.name));
  m.format = std::move(format).value();
  m.data = *data;
  return m;
}

Result<CameraInfo> ParseCameraInfo(std::string_view bytes) {
  Reader r(bytes);
  CameraInfo m;
  Result<Header> h = ReadHeader(r);
  if (!h.ok()) return h.status();
  m.header = std::move(h).value();
  Result<uint32_t> height = r.U32("height"), width = r.U32("width");
  if (!height.ok()) return height.status();
  if (!width.ok()) return width.status();
  m.height = *height;
  m.width = *width;
  Result<std::string> model = r.String("distortion_model");
  if (!model.ok()) return model.status();
  Result<uint32_t> d_count = r.U32("D length");
  if (!d_count.ok()) return d_count.status();
  VOXPLAN_RETURN_IF_ERROR(r.Need(uint64_t(*d_count) * 8, "D"));
  std::vector<double> d(*d_count);
  VOXPLAN_RETURN_IF_ERROR(r.Doubles(d.data(), int(d.size()), "D"));
  VOXPLAN_RETURN_IF_ERROR(r.Doubles(m.K, 9, "K"));
  double rest[9 + 12];  // R, P
  VOXPLAN_RETURN_IF_ERROR(r.Doubles(rest, 21, "R and P"));
  for (const char* what :
       {"binning_x", "binning_y", "roi x_offset", "roi y_offset", "roi height", "roi width"}) {
    Result<uint32_t> v = r.U32(what);
    if (!v.ok()) return v.status();
  }
  Result<uint8_t> rectify = r.U8("roi do_rectify");
  if (!rectify.ok()) return rectify.status();
  VOXPLAN_RETURN_IF_ERROR(r.End(kCameraInfo.name));
  return m;
}

Result<std::vector<Transform>> ParseTfMessage(std::string_view bytes) {
  Reader r(bytes);
  Result<uint32_t> count = r.U32("transforms length");
  if (!count.ok()) return count.status();
  // Each transform takes at least its header, an empty child name and 7 doubles.
  constexpr uint64_t kMinTransformBytes = 16 + 4 + 56;
  VOXPLAN_RETURN_IF_ERROR(r.Need(uint64_t(*count) * kMinTransformBytes, "transforms"));
  std::vector<Transform> out(*count);
  for (Transform& t : out) {
    Result<Header> h = ReadHeader(r);
    if (!h.ok()) return h.status();
    t.header = std::move(h).value();
    Result<std::string> child = r.String("child_frame_id");
    if (!child.ok()) return child.status();
    t.child_frame_id = std::move(child).value();
    VOXPLAN_RETURN_IF_ERROR(ReadRigid(r, t.translation, t.rotation));
  }
  VOXPLAN_RETURN_IF_ERROR(r.End(kTfMessage.name));
  return out;
}

Result<PoseStamped> ParsePoseStamped(std::string_view bytes) {
  Reader r(bytes);
  PoseStamped m;
  Result<Header> h = ReadHeader(r);
  if (!h.ok()) return h.status();
  m.header = std::move(h).value();
  VOXPLAN_RETURN_IF_ERROR(ReadRigid(r, m.position, m.orientation));
  VOXPLAN_RETURN_IF_ERROR(r.End(kPoseStamped.name));
  return m;
}

Result<float> ParseFloat32(std::string_view bytes) {
  Reader r(bytes);
  Result<uint32_t> bits = r.U32("data");
  if (!bits.ok()) return bits.status();
  VOXPLAN_RETURN_IF_ERROR(r.End(kFloat32.name));
  return std::bit_cast<float>(*bits);
}

std::string SerializeImage(const Image& m) {
  std::string out;
  PutHeader(out, m.header);
  PutU32(out, m.height);
  PutU32(out, m.width);
  PutBytes(out, m.encoding);
  out.push_back(char(m.big_endian ? 1 : 0));
  PutU32(out, m.step);
  PutBytes(out, m.data);
  return out;
}

std::string SerializeCompressedImage(const CompressedImage& m) {
  std::string out;
  PutHeader(out, m.header);
  PutBytes(out, m.format);
  PutBytes(out, m.data);
  return out;
}

std::string SerializeCameraInfo(const CameraInfo& m) {
  std::string out;
  PutHeader(out, m.header);
  PutU32(out, m.height);
  PutU32(out, m.width);
  PutBytes(out, "plumb_bob");
  PutU32(out, 5);
  for (int i = 0; i < 5; ++i) PutF64(out, 0.0);
  for (double k : m.K) PutF64(out, k);
  const double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (double v : R) PutF64(out, v);
  const double P[12] = {m.K[0], 0, m.K[2], 0, 0, m.K[4], m.K[5], 0, 0, 0, 1, 0};
  for (double v : P) PutF64(out, v);
  for (int i = 0; i < 6; ++i) PutU32(out, 0);  // binning, roi
  out.push_back(0);                            // do_rectify
  return out;
}

std::string SerializeTfMessage(const std::vector<Transform>& transforms) {
  std::string out;
  PutU32(out, uint32_t(transforms.size()));
  for (const Transform& t : transforms) {
    PutHeader(out, t.header);
    PutBytes(out, t.child_frame_id);
    PutRigid(out, t.translation, t.rotation);
  }
  return out;
}

std::string SerializePoseStamped(const PoseStamped& m) {
  std::string out;
  PutHeader(out, m.header);
  PutRigid(out, m.position, m.orientation);
  return out;
}

std::string SerializeFloat32(float v) {
  std::string out;
  PutU32(out, std::bit_cast<uint32_t>(v));
  return out;
}

}  // namespace voxplan::ros1
