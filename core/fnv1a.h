#pragma once
// FNV-1a 64, updated as bytes stream past: map files' trailing checksum (io/map_io.cpp), sharded
// maps' block checksums (io/sharded_map.cpp), checkpoint fingerprints. Not cryptographic.
#include <cstddef>
#include <cstdint>

namespace voxplan {

class Fnv1a64 {
 public:
  void Update(const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    uint64_t h = hash_;
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
    hash_ = h;
  }
  uint64_t value() const { return hash_; }

 private:
  uint64_t hash_ = 0xcbf29ce484222325ull;
};

}  // namespace voxplan
