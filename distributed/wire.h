#pragma once
// Flat byte encoding for what ranks exchange (frames, blocks, mesh pieces): plain values,
// strings and vectors of trivially copyable values appended in order and read back in the same
// order. All ranks run the same build on the same kind of host, so values travel as their bytes.
// A reader that runs past the end fails (CorruptData) instead of reading out of bounds.
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "core/status.h"
#include "distributed/communicator.h"

namespace voxplan::wire {

class Writer {
 public:
  template <typename T>
  void Put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  template <typename T, typename A>
  void PutVector(const std::vector<T, A>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    Put(uint64_t(v.size()));
    const auto* p = reinterpret_cast<const uint8_t*>(v.data());
    bytes_.insert(bytes_.end(), p, p + v.size() * sizeof(T));
  }
  void PutString(const std::string& s) {
    Put(uint64_t(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  Bytes& bytes() { return bytes_; }
  Bytes Take() { return std::move(bytes_); }

 private:
  Bytes bytes_;
};

class Reader {
 public:
  explicit Reader(const Bytes& bytes) : data_(bytes.data()), size_(bytes.size()) {}
  template <typename T>
  bool Get(T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (size_ - pos_ < sizeof(T)) return Fail();
    std::memcpy(&v, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  template <typename T, typename A>
  bool GetVector(std::vector<T, A>& v) {
    uint64_t n = 0;
    if (!Get(n) || n > (size_ - pos_) / sizeof(T)) return Fail();
    v.resize(size_t(n));
    if (n) std::memcpy(v.data(), data_ + pos_, size_t(n) * sizeof(T));
    pos_ += size_t(n) * sizeof(T);
    return true;
  }
  bool GetString(std::string& s) {
    uint64_t n = 0;
    if (!Get(n) || n > size_ - pos_) return Fail();
    s.assign(reinterpret_cast<const char*>(data_ + pos_), size_t(n));
    pos_ += size_t(n);
    return true;
  }
  bool ok() const { return ok_; }
  bool at_end() const { return pos_ == size_; }
  // Ok when every read succeeded and nothing is left over; else CorruptData naming `what`.
  Status Finish(const std::string& what) const {
    return ok_ && at_end() ? Status::Ok() : CorruptData("malformed message: " + what);
  }

 private:
  bool Fail() {
    ok_ = false;
    pos_ = size_;
    return false;
  }
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  bool ok_ = true;
};

}  // namespace voxplan::wire
